"""What a run with --model and --scenario-file runs (`comparisons.stages.cases`), by the rules
of its docstring and docs/report.md: the built-ins on their own models by default; on a
user's model every scenario renamed ``<scenario>-on-<model>`` with its expected differences
dropped, but a scenario on the model it was written for kept as built in, and the benchmark
manoeuvres listed as not run with the reason; a scenario file on its own model under its own
name and on every --model; two cases of one name refused in one line; model names made safe
for file names."""

from __future__ import annotations

from pathlib import Path

import pytest

from comparisons.stages.cases import (build_cases, model_spec, not_applicable, on_model,
                                      slug)
from reference_model import NAMED_MODELS
from reference_model.scenarios import SCENARIOS
from scenario_text import FORWARD, write


@pytest.mark.parametrize("text, safe", [("Batavus Browser", "Batavus-Browser"),
                                        ("a/b:c", "a-b-c"), (" -x- ", "x"), ("v1.2_b", "v1.2_b"),
                                        ("///", "model"), ("", "model"),
                                        ("Xtreme Bike", "Xtreme-Bike")])
def test_slug(text, safe):
    assert slug(text) == safe


def test_a_named_model_keeps_its_name_and_a_file_becomes_an_absolute_path(tmp_path, monkeypatch):
    spec = model_spec("benchmark")
    assert (spec.spec, spec.name, spec.contact) == ("benchmark", "benchmark", "disc")
    assert spec.source == str(NAMED_MODELS["benchmark"][0]) and spec.cv == 0.0
    assert type(spec.cv) is float
    assert spec.as_dict() == {"name": "benchmark", "source": spec.source, "contact": "disc",
                              "warnings": []}
    copy = tmp_path / "mine.toml"
    text = Path(NAMED_MODELS["thesis"][0]).read_text("utf-8")
    assert '\nname = "thesis"\n' in text
    copy.write_text(text.replace('\nname = "thesis"\n', '\nname = "My Bike"\n'), "utf-8")
    monkeypatch.chdir(tmp_path)
    mine = model_spec("mine.toml")
    assert mine.spec == str(copy.resolve()) and mine.source == "mine.toml"
    assert mine.name == "My Bike" and mine.contact == "thesis" and mine.cv == 0.8
    # a case on it is named by the model's name, made safe, not by its path
    assert on_model(SCENARIOS["zigzag"], mine).name == "zigzag-on-My-Bike"


def test_only_the_benchmark_manoeuvres_are_not_applicable_elsewhere():
    assert not_applicable(SCENARIOS["benchmark-v4"]) == (
        "written for the benchmark bicycle's critical speeds (weave 4.29, capsize 6.02 m/s); this "
        "bicycle's runs below and above its own critical speeds are in its stability section")
    assert all(not_applicable(SCENARIOS[n]) is None
               for n in ("check", "zigzag", "replay", "stability-psid10", "check-forward"))


def test_on_a_users_model_a_scenario_is_renamed_and_loses_the_thesis_differences():
    sc = SCENARIOS["stability-psid10"]
    assert sc.expected_differences                        # written for thesis vs disc
    m = model_spec("benchmark")
    bound = on_model(sc, m)
    assert (bound.name, bound.model, bound.expected_differences) == (
        "stability-psid10-on-benchmark", "benchmark", ())
    kept = on_model(sc, m, keep_name=True)
    assert (kept.name, kept.model) == ("stability-psid10", "benchmark")
    assert kept.expected_differences == sc.expected_differences


def test_without_models_the_built_ins_run_on_their_own_models():
    cases, skipped = build_cases(["zigzag", "benchmark-v4"], (), ())
    assert [(c.name, c.model, c.origin) for c in cases] == [
        ("zigzag", "thesis", "built-in"), ("benchmark-v4", "benchmark", "built-in")]
    assert cases[0].scenario is SCENARIOS["zigzag"] and skipped == []


def test_with_models_each_scenario_is_bound_or_listed_as_not_run():
    disc, bench = model_spec("thesis-disc"), model_spec("benchmark")
    cases, skipped = build_cases(["zigzag", "benchmark-v4"], (disc, bench), ())
    assert [(c.name, c.model) for c in cases] == [
        ("zigzag-on-thesis-disc", "thesis-disc"), ("zigzag-on-benchmark", "benchmark"),
        ("benchmark-v4", "benchmark")]                     # on its own model: as built in
    assert cases[2].scenario is SCENARIOS["benchmark-v4"]
    assert [(s.scenario, s.model) for s in skipped] == [("benchmark-v4", "thesis-disc")]
    assert skipped[0].reason == not_applicable(SCENARIOS["benchmark-v4"])
    # a scenario on its own model, or one not run, goes on to the next name
    cases, skipped = build_cases(["benchmark-v4", "zigzag"], (disc, bench), ())
    assert [c.name for c in cases] == ["zigzag-on-thesis-disc", "benchmark-v4",
                                       "zigzag-on-benchmark"]
    assert [s.scenario for s in skipped] == ["benchmark-v4"]


def test_a_scenario_file_runs_on_its_own_model_and_on_every_model(tmp_path):
    f = write(tmp_path, FORWARD)
    bench = model_spec("benchmark")
    cases, _ = build_cases([], (bench,), (str(f),))
    assert [(c.name, c.model, c.origin) for c in cases] == [
        ("mine", "thesis", str(f)), ("mine-on-benchmark", "benchmark", str(f))]
    assert [(c.scenario.name, c.scenario.model) for c in cases] == [
        ("mine", "thesis"), ("mine-on-benchmark", "benchmark")]
    thesis = model_spec("thesis")                          # the file's own model given too
    cases, _ = build_cases([], (thesis,), (str(f),))
    assert [c.name for c in cases] == ["mine"]


def test_two_cases_of_one_name_are_refused_naming_both_origins(tmp_path):
    f = write(tmp_path, FORWARD.replace('name = "mine"', 'name = "zigzag"'))
    with pytest.raises(ValueError) as err:
        build_cases(["zigzag"], (), (str(f),))
    assert str(err.value) == (f"two scenarios named 'zigzag' (built-in, {f}); rename one "
                              "(scenario.name in its file)")


def test_a_models_warnings_are_carried_to_what_the_run_reports(tmp_path):
    """A bicycle allowed to break the triangle inequality (I3xx + I3zz < I3yy, [checks]
    triangle = "warn") carries the loader's warning into the run's model list."""
    from reference_model import load_model
    text = Path(NAMED_MODELS["thesis"][0]).read_text("utf-8")
    line = 'I3zz = { value = 3.205,'
    assert line in text
    path = tmp_path / "flat.toml"
    path.write_text(text.replace(line, 'I3zz = { value = 0.5,') + '\n[checks]\ntriangle = "warn"\n',
                    "utf-8")
    warnings = load_model(str(path)).warnings
    assert warnings and any("triangle" in w for w in warnings)
    spec = model_spec(str(path))
    assert spec.warnings == tuple(warnings) and spec.as_dict()["warnings"] == list(warnings)
