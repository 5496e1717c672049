"""The energy-drift stage (comparisons/stages/energy.py) held to the parts of its contract that
tests/test_stage_sections.py leaves open: the reference's roll on a user's bicycle is the
gentler start `free_roll_on` describes (not the thesis's default), an engine is asked for its
runs with its own spec and options and loaded on the drag-free model (the free roll told that
model's name), an engine refusing projection gets its Baumgarte run with the settings naming the
a1 = a2 it actually ran at, an engine's error message reaches the report with its whitespace
collapsed and cut at 300 characters on both failure paths, `energy_section` defaults to
thesis-disc, and a failed engine's row does not end the table. Fake engines and a recording
`energy_drifts` (no simulation), ~0.1 s. Each test names the planted bugs (mutmut's survivors
of the stage's measurement) it fails on.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from comparisons.stages import energy as en
from comparisons.stages.results import Table, Text
from engines import EngineError

TOL = {"energy_drift": SimpleNamespace(tolerance=0.1, reason="IFToMM's 0.1 %")}

#: Meijaard et al. (2007)'s benchmark bicycle: weave speed 4.292 m/s, capsize 6.024 m/s
BENCHMARK_CRITICAL = {"weave": 4.292, "capsize": 6.024}


class _Recorder:
    """A stand-in for `energy_drifts`: it records what it was given and runs each engine's
    ``simulate`` on the scenario, so a fake engine's refusal reaches the stage as a real
    engine's would; the reference row first, then one row per engine."""

    def __init__(self):
        self.calls = []

    def __call__(self, model, scenario=None, engines=()):
        self.calls.append((model, scenario, list(engines)))
        rows = [{"engine": f"reference {model.name}", "settings": "DOP853"}]
        for label, eng in engines:
            eng.simulate(scenario)
            rows.append({"engine": label, "settings": "h = 0.001"})
        return rows


class _Engine:
    """A fake engine: ``simulate`` records the scenario and raises what ``refuses`` maps its
    constraint handling to (nothing: it runs)."""

    def __init__(self, refuses=None):
        self.refuses, self.seen = refuses or {}, []

    def simulate(self, sc):
        self.seen.append(sc)
        if sc.constraints in self.refuses:
            raise self.refuses[sc.constraints]


def _stage_with(monkeypatch, engine):
    """The stage with a recording `energy_drifts` and a loader handing out ``engine``."""
    drifts, loaded = _Recorder(), []
    monkeypatch.setattr(en, "energy_drifts", drifts)
    monkeypatch.setattr(en, "load_engine", lambda spec, model, **opts: loaded.append(
        (spec, model, opts)) or engine)
    return drifts, loaded


def test_the_reference_rolls_from_the_users_bicycles_own_start(monkeypatch):
    """On the benchmark bicycle (R_rear = 0.3 m) with Meijaard et al.'s weave and capsize speeds
    (4.292, 6.024 m/s), the reference's roll starts at the middle of that range, v = 5.158 m/s,
    psi_dot = v / 0.3, leaned and steered by pi/32, on the drag-free benchmark model (not the
    thesis's default roll, which `energy_drifts` runs when given no scenario). Planted: the
    reference's run given no scenario (the thesis's default start); the bicycle handed to
    `free_roll_on` replaced by None (no contact to look up)."""
    from comparisons.stages import stability
    monkeypatch.setattr(stability, "critical", lambda spec: dict(BENCHMARK_CRITICAL))
    drifts, _ = _stage_with(monkeypatch, None)
    assert en.energy_rows(None, {}, "benchmark") == [{"engine": "reference benchmark",
                                                      "settings": "DOP853"}]
    ((model, sc, engines),) = drifts.calls
    assert (model.name, model.params.cv, engines) == ("benchmark", 0.0, [])
    assert sc is not None
    v = (4.292 + 6.024) / 2
    assert math.isclose(sc.dq_ind0[1], v / 0.3, rel_tol=1e-12)
    assert sc.q0[3] == sc.q0[6] == np.pi / 32 and sc.model == "benchmark"
    assert sc.torques == (0.0, 0.0, 0.0)


def test_an_engine_is_asked_for_its_runs_and_loaded_with_its_own_spec_options_and_model(
        monkeypatch):
    """Exudyn given a step on the command line runs once, as 'exudyn', loaded as ``exudyn``
    with that step (not its two fixed-step variants at h = 1e-3, engines/facts.py) on the
    drag-free thesis-disc model (cv = 0, the one its drift is measured with), and asked to
    simulate the thesis's free roll told the model's name: psi_dot = 10 rad/s, lean pi/16.
    Planted: the runs asked for with no spec, or with no options (its two variants instead);
    the engine loaded with no spec or no model; the free roll's model name dropped."""
    eng = _Engine()
    drifts, loaded = _stage_with(monkeypatch, eng)
    rows = en.energy_rows("exudyn", {"step": 0.002}, "thesis-disc")
    assert rows == [{"engine": "exudyn", "settings": "h = 0.001"}]
    ((spec, model, opts),) = loaded
    assert (spec, opts) == ("exudyn", {"step": 0.002})
    assert (model.name, model.params.cv) == ("thesis-disc", 0.0)
    ((measured_on, sc, engines),) = drifts.calls
    assert measured_on is model and engines == [("exudyn", eng)]
    assert eng.seen == [sc]
    assert (sc.model, sc.name, sc.constraints) == ("thesis-disc", "free-roll-psid10", "projection")
    assert sc.dq_ind0 == (0.0, 10.0, 0.0) and sc.q0[3] == sc.q0[6] == np.pi / 16


def test_an_engine_refusing_projection_gets_its_baumgarte_run_and_says_at_which_gains(
        monkeypatch):
    """An engine whose projection run raises EngineError is run again with Baumgarte
    stabilisation; the row's settings append the gains the engine was actually given (the
    scenario it simulated: a1 = a2, printed %g) and the refusal with its whitespace collapsed.
    Planted: the settings replaced by the Baumgarte note instead of extended (= for +=); the
    engine left out of its Baumgarte run. (The second gain printed for the first cannot show
    here: the free roll's gains are always the equal THESIS_BAUMGARTE, a listed equivalent.)"""
    eng = _Engine({"projection": EngineError("projection is\n   not   supported\there")})
    _stage_with(monkeypatch, eng)
    (row,) = _rows_of(monkeypatch, "x")
    first, second = eng.seen
    assert (first.constraints, second.constraints) == ("projection", "baumgarte")
    a1, a2 = second.baumgarte
    assert a1 == a2 > 0
    assert row == {"engine": "x", "settings": f"h = 0.001; Baumgarte a1 = a2 = {a1:g} (it "
                                              "refused projection: projection is not supported "
                                              "here)"}


def _rows_of(monkeypatch, spec):
    """``energy_rows`` of ``spec`` on thesis-disc with one run, labelled by the spec, no
    options."""
    monkeypatch.setattr(en, "_runs_of", lambda s, options: [(s, {})])
    return en.energy_rows(spec, {}, "thesis-disc")


def _words(n):
    """n words 'w0 w1 ...' separated by runs of blanks, tabs and newlines, and what the
    report should show of them: single spaces, the first 300 characters."""
    raw = " \n\t ".join(f"w{i}" for i in range(n))
    shown = " ".join(f"w{i}" for i in range(n))
    return raw, shown[:300]


def test_an_engines_long_error_is_shown_on_one_line_cut_at_300_characters(monkeypatch):
    """An engine whose run raises a 100-word error (590 characters once its runs of blanks,
    tabs and newlines are single spaces) gets a FAIL row 'RuntimeError: ' and the first 300
    characters of the single-spaced message. Planted: the words joined by 'XX XX' instead of a
    space (the existing test's one-word message could not tell)."""
    raw, shown = _words(100)
    assert len(shown) == 300 and "\n" not in shown and "  " not in shown
    _stage_with(monkeypatch, _Engine({"projection": RuntimeError(raw)}))
    assert _rows_of(monkeypatch, "x") == [{"engine": "x", "failed": "RuntimeError: " + shown}]


def test_a_long_error_of_the_baumgarte_run_is_cut_at_300_characters_too(monkeypatch):
    """An engine that refuses projection and whose Baumgarte run then raises the same long
    error: the FAIL row names the second error, single-spaced and cut at 300 characters as on
    the first path. Planted: the cut at 301 characters on this path."""
    raw, shown = _words(100)
    _stage_with(monkeypatch, _Engine({"projection": EngineError("no projection"),
                                      "baumgarte": ValueError(raw)}))
    (row,) = _rows_of(monkeypatch, "x")
    assert row == {"engine": "x", "failed": "ValueError: " + shown}
    assert len(row["failed"]) == len("ValueError: ") + 300


def _measured(engine, drift):
    return {"engine": engine, "status": "success", "settings": "h = 0.001", "E0": 1472.0,
            "drift_percent": drift, "drift_J": drift * 14.72, "drift_percent_of_T0": 3 * drift,
            "t_end": 1.0}


def test_the_section_defaults_to_thesis_disc():
    """energy_section with no model is the thesis-disc section: no ' on <model>' in the title,
    the stability study's start, the zero level of the potential energy the ground (E0's, as
    comparisons/judgments/energy.py defines it), rows judged on 'thesis-disc (cv = 0)'.
    Planted: the default model name mangled ('XXthesis-discXX', 'THESIS-DISC'); 'the ground.'
    mangled ('XXthe ground.XX', 'THE GROUND.')."""
    sec = en.energy_section(TOL, (), rows=[_measured("reference thesis-disc", 1e-9)])
    assert sec.title == "Energy drift, torque-free and drag-free (IFToMM: 100 (Emax - Emin) / E0)"
    text = [b.text for b in sec.blocks if isinstance(b, Text)]
    assert text[0] == ("Free roll from the stability study's leaned and steered state at "
                       "psi_dot = 10 rad/s for 1 s, cv = 0, no torques; potential energy zero at "
                       "the ground.")
    assert [r.as_dict()["model"] for r in sec.comparisons] == ["thesis-disc (cv = 0)"]


def test_a_failed_engine_does_not_end_the_table():
    """A failed engine's row between measured ones: the table and the judged rows go on after
    it (reference, FAIL, the engine after it at 0.05 % < 0.1 %: pass). Planted: the loop left
    at the first failed row (break for continue)."""
    rows = [_measured("reference thesis-disc", 1e-9), {"engine": "F", "failed": "RuntimeError: x"},
            _measured("A", 0.05)]
    sec = en.energy_section(TOL, (), "thesis-disc", rows)
    (table,) = [b for b in sec.blocks if isinstance(b, Table)]
    assert [(r[0], r[4]) for r in table.rows] == [("reference thesis-disc", "pass"), ("F", "FAIL"),
                                                  ("A", "pass")]
    assert [(r.as_dict()["engines"], r.as_dict()["passed"]) for r in sec.comparisons] == [
        (["reference thesis-disc"], True), (["F"], False), (["A"], True)]
