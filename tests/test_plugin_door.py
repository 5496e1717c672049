"""An engine from outside the repository goes through every door of the harness unchanged:
`run`, `simulate`, `diagnose`, the conformance plugin, by a bare ``file.py:Class`` spec and by
an entry point of a package the project has never heard of. The engine is the third-party
example (examples/numpy_engine, written from docs/engines.md); its planted bug (the sign of
the frame's product of inertia) must be localized by `diagnose --engine` to its term and body.
"""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from comparisons.cli import main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "numpy_engine"
FILE_SPEC = f"{EXAMPLE / 'numpy_bicycle' / 'engine.py'}:NumpyEngine"


def _pytest(*args, cwd):
    """The conformance plugin in a fresh process, as an engine author runs it."""
    # summary lines not cut; this checkout's code first (an editable install elsewhere, e.g.
    # of another worktree, would otherwise supply the plugin)
    env = dict(os.environ, PYTHONHASHSEED="0", COLUMNS="400",
               PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q",
                           "--pyargs", "comparisons.conformance", *args],
                          cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def test_a_plugin_is_given_every_stage_its_capabilities_allow():
    """The stages' plan for `run --quick --engines reference,FILE.py:Class` (no stage run: the
    whole run is the slow test below): the plugin's terms, its fault injection, its energy drift
    (it simulates) and its benchmark terms are asked for, as a built-in's are (issue 22).
    Planted: the faults stage asking for a list of built-in names leaves the plugin out, and
    this fails."""
    from comparisons.stages.cases import build_cases
    from comparisons.stages.pipeline import _stage_tasks, select
    from comparisons.stages.runs import setups_for
    from comparisons.stages.stage import Plan
    from engines.facts import engine_facts
    opts = select("check", True, f"reference,{FILE_SPEC}")
    cases, _ = build_cases(opts.scenarios, opts.models, ())
    plan = Plan(opts, tuple(setups_for(opts.engines)), {e: engine_facts(e) for e in opts.engines},
                tuple(cases), {})
    tasks = {t.key: t for t in _stage_tasks(plan)}
    for stage in ("terms", "faults"):
        assert (stage, (FILE_SPEC, None)) in tasks, (stage, sorted(map(str, tasks)))
    assert ("energy", (FILE_SPEC, "thesis-disc")) in tasks, sorted(map(str, tasks))
    assert ((FILE_SPEC, {}),) in tasks[("benchmark", "terms")].args


@pytest.mark.slow
def test_run_with_a_file_spec_compares_its_terms(tmp_path):
    out = tmp_path / "r"
    assert main(["run", "--quick", "--scenarios", "check", "--engines",
                 f"reference,{FILE_SPEC}", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    mine = [c for c in summary["comparisons"] if c["engines"] == ["reference", "NumpyEngine"]]
    assert {c["quantity"] for c in mine} >= {"mass_matrix", "constraint_bias", "forward_acceleration"}
    assert all(c["passed"] for c in mine)
    runs = {r["engine"]: r["status"] for r in summary["engine_runs"]}
    assert runs["NumpyEngine"] == "not run"       # no run_inverse: recorded, not dropped
    # a plugin gets every section its capabilities allow, as a built-in does (issue 22):
    # fault injection (planted: the faults stage asking for a list of built-in names leaves it
    # out, and this fails), the energy drift (it simulates), the benchmark's terms
    faults = [f for f in summary["faults"] if f["engine"] == "NumpyEngine"]
    assert len(faults) == 6 and all(f["verdict"] == "localized" for f in faults), faults
    report = (out / "report.md").read_text()
    assert "Reference vs NumpyEngine, term by term" in report
    energy = [c for c in summary["comparisons"] if c["quantity"] == "energy drift percent"]
    assert any(c["engines"] == ["NumpyEngine"] and c["passed"] for c in energy), energy
    bench = [c for c in summary["comparisons"] if c["model"] == "benchmark"
             and c["engines"] == ["reference", "NumpyEngine"]]
    assert {"mass_matrix", "forward_acceleration"} <= {c["quantity"] for c in bench}


def test_an_engine_that_cannot_be_built_is_dropped_and_named(tmp_path, capsys):
    broken = tmp_path / "broken.py"
    broken.write_text("from engines.base import Engine\n\nclass Broken(Engine):\n"
                      "    capabilities = frozenset({'mass_matrix'})\n"
                      "    def __init__(self, model):\n        raise RuntimeError('no bicycle today')\n")
    out = tmp_path / "r"
    assert main(["run", "--quick", "--scenarios", "check", "--engines",
                 f"reference,{broken}:Broken", "--out", str(out)]) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["dropped_engines"][0]["reason"].endswith("no bicycle today")
    assert "Dropped" in (out / "report.md").read_text()
    capsys.readouterr()
    assert main(["run", "--engines", f"{tmp_path / 'nope.py'}:X", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nope.py" in err[0]


def test_simulate_with_a_file_spec(tmp_path, capsys):
    out = tmp_path / "s.csv"
    assert main(["simulate", "--engine", FILE_SPEC, "--scenario", "stability-psid0",
                 "--fall-limit", "0.4", "--out", str(out)]) == 0
    assert "fell" in capsys.readouterr().out and out.stat().st_size > 0


def test_diagnose_localizes_the_planted_bug_to_its_term_and_body(capsys):
    assert main(["diagnose", "--model", "thesis", "--engine", FILE_SPEC,
                 "--engine-option", "bug=I3xz-sign"]) == 1
    text = capsys.readouterr().out
    assert "localized: M, Qv via I3xz (body 3 frame+rider)" in text
    assert main(["diagnose", "--model", "thesis", "--engine", FILE_SPEC]) == 0


@pytest.mark.slow
def test_conformance_plugin_passes_the_correct_engine_and_fails_the_buggy_one(tmp_path):
    sel = ["--model", "thesis-disc", "-k", "sweep"]
    # the buggy engine: the four terms the bug touches fail (listed as expected failures with
    # their reason, they are 'xfailed': failed as expected), gravity, D and dD dq pass ...
    xf = tmp_path / "xfails.txt"
    xf.write_text("".join(f"test_term_sweep[NumpyEngine-thesis-disc-{q}]  # planted: I3xz sign\n"
                          for q in ("mass_matrix", "inverse_dynamics", "generalized_forces",
                                    "forward_acceleration")))
    listed = _pytest("--engine", FILE_SPEC, "--engine-option", "bug=I3xz-sign", *sel,
                     "--xfails-file", str(xf), cwd=tmp_path)
    assert listed.returncode == 0, listed.stdout[-2000:]
    assert "3 passed" in listed.stdout and "4 xfailed" in listed.stdout, listed.stdout[-2000:]
    # ... and the correct engine passes all seven: the four listed ones pass, which strict
    # expected failures report (so a fixed engine's list cannot go stale)
    strict = _pytest("--engine", FILE_SPEC, *sel, "--xfails-file", str(xf), cwd=tmp_path)
    assert strict.returncode == 1, strict.stdout[-2000:]
    xpassed = set(re.findall(r"(test_term_sweep\[[^\]]+\]) - \[XPASS\(strict\)\]", strict.stdout))
    assert "3 passed" in strict.stdout and len(xpassed) == 4, strict.stdout[-2000:]


def test_an_entry_point_of_an_unknown_package_is_found_and_run(tmp_path, monkeypatch, capsys):
    """A temporary installed distribution (a dist-info with an entry point) naming the example's
    class, on the path as an installed package would be: `engines` lists it and `simulate`
    runs it by name."""
    dist = tmp_path / "acme_bike-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: acme-bike\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text(
        "[bicycle_xval.engines]\nacme = numpy_bicycle.engine:NumpyEngine\n")
    monkeypatch.syspath_prepend(str(EXAMPLE))
    monkeypatch.syspath_prepend(str(tmp_path))
    assert main(["engines"]) == 0
    assert "acme  (acme-bike 1.0" in capsys.readouterr().out
    assert main(["simulate", "--engine", "acme", "--scenario", "stability-psid0",
                 "--fall-limit", "0.4", "--out", str(tmp_path / "a.csv")]) == 0
    assert "fell" in capsys.readouterr().out


def test_diagnose_against_another_engine(capsys):
    """--against ENGINE: the user's engine against Pinocchio (built from the same parameters)
    instead of the reference; the dropped gyroscopic term is named all the same."""
    assert main(["diagnose", "--model", "thesis", "--engine", FILE_SPEC, "--engine-option",
                 "bug=gyroscopic", "--against", "pinocchio", "--states", "8"]) == 1
    text = capsys.readouterr().out
    assert "against engine pinocchio" in text
    assert "localized: Qv via gyroscopic terms w x (I w) (all bodies)" in text


COUNTING = """
import atexit
from pathlib import Path
from engines.reference import ReferenceEngine

CALLS = [0]
atexit.register(lambda: Path(__file__).with_suffix(".calls").write_text(str(CALLS[0])))

class Counting(ReferenceEngine):
    name = "counting"

    def mass_matrix(self, q):
        CALLS[0] += 1
        return super().mass_matrix(q)
"""


@pytest.mark.slow
def test_the_quick_depth_checks_fewer_states_and_one_trajectory_model(tmp_path):
    """--conformance-depth quick (make test's): each term at 5 hypothesis states, not 25, and
    the forward runs on thesis-disc only; the default is the full depth an engine author runs.
    Counted by an engine that counts its calls (one per state) and by the collected ids."""
    engine = tmp_path / "counting.py"
    engine.write_text(COUNTING)
    calls = {}
    for depth in ("quick", "full"):
        got = _pytest("--engine", f"{engine}:Counting", "--model", "thesis-disc", "-k",
                      "hypothesis_states and mass_matrix", "--conformance-depth", depth,
                      cwd=tmp_path)
        assert got.returncode == 0, got.stdout[-2000:]
        calls[depth] = int(engine.with_suffix(".calls").read_text())
    assert calls == {"quick": 5, "full": 25}, calls
    ids = {d: _pytest("--engine", FILE_SPEC, "--collect-only", "-k", "meaningful_horizon",
                      "--conformance-depth", d, cwd=tmp_path).stdout for d in ("quick", "full")}
    assert "thesis-disc-replay" in ids["quick"] and "general-replay" not in ids["quick"]
    assert "general-replay" in ids["full"], ids["full"][-2000:]
def test_an_engines_declared_scenario_run_times_order_its_runs(tmp_path):
    """`Costs.scenario_runs` replaces the per-second rate for the scenarios it names (on any
    model: `replay-on-<model>` is the replay), so a run several times the rate's estimate is
    queued first instead of last. Expected values: the declared numbers and the rate times the
    scenario's length (1.2 s of a stability run). Planted: the override read for the
    scenario's full name only fails the model's replay."""
    (tmp_path / "slow_replay.py").write_text(
        "from engines.base import Engine\nfrom engines.facts import Costs\n"
        "class SlowReplay(Engine):\n    name = 'slow-replay'\n"
        "    capabilities = frozenset({'simulate'})\n"
        "    costs = Costs(run_per_second=0.5, scenario_runs=(('replay', 9.0),))\n")
    from comparisons.stages.runs import cost, setup_of
    setup = setup_of(f"{tmp_path / 'slow_replay.py'}:SlowReplay")
    assert cost(setup, "replay") == cost(setup, "replay-on-my-bike") == 9.0
    assert cost(setup, "stability-psid5") == pytest.approx(0.5 * 1.2)
