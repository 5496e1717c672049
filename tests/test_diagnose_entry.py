"""`diagnose(...)`, the entry point `bicycle-xval diagnose` calls: its refusals word for word,
how ``--against`` tells an engine from a bicycle, a diagnosis against another engine (the
user's port against Pinocchio, both from the same parameters: no declared differences), the
engine options given to the engine they name, and an engine that declares it cannot represent
the model left out with its reason (all of them: the first one's error). The planted ports
(tests/planted/engines.py, the numpy example) carry known mistakes."""

from __future__ import annotations

from pathlib import Path

import pytest

from comparisons.judgments.diagnose import _engine_named, diagnose
from comparisons.judgments.tolerances import load_tolerances
from engines import UnsupportedModel

TOLS = load_tolerances()
ROOT = Path(__file__).resolve().parents[1]
PLANTED = ROOT / "tests" / "planted" / "engines.py"
NUMPY = f"{ROOT / 'examples' / 'numpy_engine' / 'numpy_bicycle' / 'engine.py'}:NumpyEngine"


@pytest.mark.parametrize("engines, got", [((), "none"), (("reference",), "reference"),
                                          (("pinocchio", "reference"), "pinocchio, reference")])
def test_the_engines_must_name_one_besides_the_reference(engines, got):
    with pytest.raises(ValueError) as err:
        diagnose("thesis", engines=engines, tolerances=TOLS)
    assert str(err.value) == ("engines must name at least one engine other than the reference "
                              f"(the reference is the model under test); got {got}")


@pytest.mark.parametrize("n", [True, 3, 4.0, "8"])
def test_too_few_or_not_whole_states_are_refused(n):
    with pytest.raises(ValueError) as err:
        diagnose("thesis", engines=("pinocchio",), n_states=n, tolerances=TOLS)
    assert str(err.value) == f"n_states must be an integer >= 4; got {n!r}"


def test_against_names_an_engine_or_a_bicycle(tmp_path, monkeypatch):
    assert _engine_named(None) is False
    assert _engine_named("thesis") is False and _engine_named("benchmark") is False
    assert _engine_named("pinocchio") is True and _engine_named("exudyn") is True
    (tmp_path / "pinocchio").write_text("")           # a parameter file of that name, here:
    (tmp_path / "a:b.toml").write_text("")            # the user's bicycle, not the engine
    monkeypatch.chdir(tmp_path)
    assert _engine_named("pinocchio") is False and _engine_named("a:b.toml") is False
    assert _engine_named(f"{PLANTED}:GravitySign") is True
    assert _engine_named("bicycle.toml") is False      # no such file, no such engine


def test_a_port_against_another_engine_is_judged_against_it():
    d = diagnose("thesis", against="pinocchio", engines=(f"{PLANTED}:GravitySign",), n_states=8,
                 tolerances=TOLS)
    assert (d.model, d.against, d.n_states, d.declared, d.not_run) == (
        "thesis", "engine pinocchio", 8, (), ())
    assert d.engines == (f"{PLANTED}:GravitySign",)
    loc = d.localization
    assert loc.localized and loc.explanation.causes == ("sign:Qgrav",)
    assert {c.engines[0] for c in loc.quantities} == {"pinocchio"}   # not the reference
    cannot = f"{PLANTED}:CannotRepresent"
    d = diagnose("thesis", against="pinocchio", engines=(cannot, f"{PLANTED}:GravitySign"),
                 n_states=8, tolerances=TOLS)
    assert d.declared == () and [e for e, _ in d.not_run] == [cannot]


def test_engine_options_reach_the_engine_they_name():
    clean = diagnose("thesis", engines=(NUMPY,), n_states=8, tolerances=TOLS)
    assert clean.agrees
    bugged = diagnose("thesis", engines=(NUMPY,), n_states=8, tolerances=TOLS,
                      options={NUMPY: {"bug": "gyroscopic"}})
    assert bugged.localization.explanation.causes == ("gyroscopic",)


def test_an_engine_that_cannot_represent_the_model_is_left_out_with_its_reason():
    cannot = f"{PLANTED}:CannotRepresent"
    d = diagnose("thesis", engines=(cannot, f"{PLANTED}:PortedBicycle"), n_states=8,
                 tolerances=TOLS)
    assert d.engines == (f"{PLANTED}:PortedBicycle",) and d.agrees
    # the loader's line: the engine, its spec, the model, then the engine's own reason
    assert d.not_run == ((cannot, f"engine 'planted-cannot-represent' ({cannot}) cannot "
                                  "represent model 'thesis': its bodies cannot take this model's "
                                  "inertias (declared for the test)"),)
    with pytest.raises(UnsupportedModel, match="^engine 'planted-cannot-represent' "):
        diagnose("thesis", engines=(cannot,), n_states=8, tolerances=TOLS)


def test_a_model_under_test_without_the_gyroscopic_terms_is_told_so():
    """The other way round from the planted NoGyroscopic port: the model under test lacks
    w x (I w) and the engine (Pinocchio) has it, so the fit toggles the model's variant with
    coefficient +1 and the line says the model lacks them (its value 'without')."""
    from comparisons.judgments.diagnose import localize
    from comparisons.judgments.terms import random_states
    from engines import load_engine
    from reference_model import Model, load_model
    thesis = load_model("thesis")
    lacking = Model(thesis.params, gyroscopic=False)
    loc = localize(lacking, random_states(8, seed=11), [load_engine("pinocchio", thesis)],
                   tolerances=TOLS)
    e = loc.explanation
    assert loc.localized and e.causes == ("gyroscopic",) and e.model_values == ("without",)
    assert abs(e.estimates[0] - 1.0) < 1e-9
    assert ("the model under test lacks the gyroscopic terms the engines have (coefficient "
            "1.000)") in e.describe()


def test_a_bicycle_against_another_bicycle_names_both_and_the_differences():
    """The result names the file under test and what the engines were built from; the same
    file gives no 'against' and no declared differences; the states are the seeded ones (the
    same seed gives the same numbers, another seed others)."""
    same = diagnose("thesis", engines=("pinocchio",), n_states=8, tolerances=TOLS)
    assert (same.model, same.against, same.declared, same.not_run) == ("thesis", None, (), ())
    other = diagnose("thesis", against="thesis-disc", engines=("pinocchio",), n_states=8,
                     tolerances=TOLS)
    assert (other.model, other.against) == ("thesis", "thesis-disc")
    assert other.declared == (("contact", "thesis", "disc"),)       # the only difference
    again = diagnose("thesis", engines=("pinocchio",), n_states=8, seed=11, tolerances=TOLS)
    moved = diagnose("thesis", engines=("pinocchio",), n_states=8, seed=5, tolerances=TOLS)
    worst = lambda d: [c.max_abs_error for c in d.localization.checks]
    assert worst(again) == worst(same) and worst(moved) != worst(same)
