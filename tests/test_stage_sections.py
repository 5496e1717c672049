"""What a stage's section says, from judgments built by hand: the rows summary.json carries
(docs/report.md, "comparisons": the common keys in order, then a kind's own), the tables'
headers and verdict words a reader and a script rely on, and the numbers in each cell, every
one derived here from the hand-built inputs. Report prose (its wording) is not checked: only
what a caller reads by key or a reader reads as a verdict or a number."""

from __future__ import annotations

import math

import pytest

from comparisons.judgments.linear_check import LinearCheck, MatrixCheck, SpeedCheck
from comparisons.judgments.rows import COMMON
from comparisons.stages.linear_check import ENGINES, linear_check_section
from comparisons.stages.results import Table, Text


def _tables(sec):
    return [b for b in sec.blocks if isinstance(b, Table)]


def _texts(sec):
    return [b.text for b in sec.blocks if isinstance(b, Text)]


# -- the linear check's section (comparisons/stages/linear_check.py) ------------------------

def test_a_model_without_counterpart_gets_one_reported_row_and_says_why():
    check = LinearCheck("mine", "no benchmark counterpart: the fork-axis contact", "", (0.0, 10.0))
    sec = linear_check_section(check)
    assert sec.title == "Linearization of mine against the benchmark's closed form"
    assert _texts(sec) == ["Not applicable: no benchmark counterpart: the fork-axis contact."]
    assert not _tables(sec)
    (row,) = sec.comparisons
    assert row.as_dict() == {
        "quantity": "linearization vs closed form", "scenario": "mine, upright straight running",
        "model": "mine", "engines": ["linearize", "closed form (Meijaard 2007)"],
        "max_error": None, "tolerance": None, "passed": None, "localized_to": "-",
        "note": "not applicable: no benchmark counterpart: the fork-axis contact"}
    assert list(row.as_dict()) == list(COMMON)


CHECK = LinearCheck(
    "bike", "", "bike has drag", (0.5, 9.0),
    matrices=(MatrixCheck("M", 2.0e-16, 1e-12, "M[phi, delta]"),
              MatrixCheck("K2", 3.0e-9, 1e-12, "K2[delta, delta]")),
    speeds=(SpeedCheck("weave", 4.292382536341, 4.292382536345, 1e-9),   # 4e-12 apart: pass
            SpeedCheck("capsize", 6.0, None, 1e-9),                      # one side only: FAIL
            SpeedCheck("other", None, None, 1e-9)))                      # neither: agreement


def test_the_matrix_table_rows_and_their_verdicts():
    sec = linear_check_section(CHECK)
    matrices, speeds = _tables(sec)
    assert matrices.header == ("matrix", "max relative difference", "tolerance", "verdict",
                               "worst entry")
    assert matrices.rows == (("M", "2.0e-16", "1e-12", "pass", "M[phi, delta]"),
                             ("K2", "3.0e-09", "1e-12", "FAIL", "K2[delta, delta]"))
    rows = [r.as_dict() for r in sec.comparisons]
    assert [r["quantity"] for r in rows[:2]] == ["linearization vs closed form: M",
                                                 "linearization vs closed form: K2"]
    assert [r["passed"] for r in rows] == [True, False, True, False, True]
    assert [r["max_error"] for r in rows[:2]] == [2.0e-16, 3.0e-9]
    assert [r["tolerance"] for r in rows[:2]] == [1e-12, 1e-12]
    assert [r["localized_to"] for r in rows[:2]] == ["M[phi, delta]", "K2[delta, delta]"]
    for r in rows:
        assert list(r)[:len(COMMON)] == list(COMMON)
        assert r["engines"] == ENGINES
        assert r["model"] == "bike" and r["scenario"] == "bike, upright straight running"
    assert rows[0]["note"] == "max |difference| / max |closed form| over the matrix"
    # the drag note is part of the section's text
    assert "bike has drag." in _texts(sec)[0]
    assert "0.5-9 m/s" in _texts(sec)[0]


def test_the_speed_table_rows_say_none_where_a_side_found_no_speed():
    sec = linear_check_section(CHECK)
    speeds = _tables(sec)[1]
    assert speeds.header == ("critical speed", "closed form [m/s]", "linearization [m/s]",
                             "difference [m/s]", "tolerance", "verdict")
    assert speeds.rows == (
        ("weave speed", "4.292382536341", "4.292382536345", f"{4e-12:.1e}", "1e-09", "pass"),
        ("capsize speed", "6.000000000000", "none", "-", "1e-09", "FAIL"),
        ("other speed", "none", "none", "-", "1e-09", "pass"))
    weave, capsize, other = (r.as_dict() for r in sec.comparisons[2:])
    assert weave["quantity"] == "linearization vs closed form: weave speed"
    assert math.isclose(weave["max_error"], 4e-12, rel_tol=1e-3)
    assert (weave["closed_form"], weave["linearization"]) == (4.292382536341, 4.292382536345)
    assert weave["localized_to"] == ("closed form 4.292382536341 m/s, linearization "
                                     "4.292382536345 m/s")
    assert capsize["max_error"] is None and capsize["linearization"] is None
    assert capsize["localized_to"] == "closed form 6.000000000000 m/s, linearization none m/s"
    assert other["localized_to"] == "none in 0.5-9 m/s on both"
    assert weave["note"] == "in 0.5-9 m/s; none on both counts as agreement"
    assert [r["tolerance"] for r in (weave, capsize, other)] == [1e-9, 1e-9, 1e-9]


@pytest.mark.parametrize("note, ends", [("", "m/s, the closed form's by its own root finding "
                                                "on its eigenvalues."),
                                        ("checked with cv = 0", ". checked with cv = 0.")])
def test_the_text_ends_with_the_note_only_when_there_is_one(note, ends):
    check = LinearCheck("bike", "", note, (0.0, 10.0))
    assert _texts(linear_check_section(check))[0].endswith(ends)


def test_the_stage_asks_one_task_per_model_and_assembles_failures_as_failing_rows():
    from types import SimpleNamespace

    from comparisons.stages.linear_check import LinearCheckStage, linear_check
    from comparisons.stages.pool import TaskResult
    from comparisons.stages.stage import Plan

    models = (SimpleNamespace(spec="a.toml", name="A"), SimpleNamespace(spec="b.toml", name="B"))
    plan = Plan(SimpleNamespace(models=models, tolerances="TOLS"), (), {})
    tasks = LinearCheckStage().tasks(plan)
    assert [(t.key, t.func, t.args) for t in tasks] == [("a.toml", linear_check, ("TOLS", "a.toml")),
                                                        ("b.toml", linear_check, ("TOLS", "b.toml"))]
    assert [t.label for t in tasks] == ["A: linearization vs the closed form",
                                        "B: linearization vs the closed form"]
    assert [t.cost for t in tasks] == [0.1, 0.1]     # the scheduler's estimate (s)
    ok = linear_check_section(CHECK)
    out = LinearCheckStage().assemble(plan, {"a.toml": TaskResult("a.toml", ok, 0.1),
                                             "b.toml": TaskResult("b.toml", None, 0.1, "boom")})
    first, second = out.sections
    assert first is ok
    assert second.title == "B: linearization against the closed form"
    assert [r["passed"] for r in second.comparisons] == [False]
    assert second.comparisons[0]["localized_to"] == "boom"
    assert (LinearCheckStage.name, LinearCheckStage.section) == ("linear-check", None)


def test_the_stage_judges_over_the_stability_sections_speed_range(monkeypatch):
    """`linear_check` looks for the critical speeds where the stability section does
    (`stability.SPEED_RANGE`): moved to 1-5 m/s, the benchmark's weave speed (4.29 m/s) is
    still found and its capsize speed (6.02 m/s) is outside."""
    from comparisons.judgments.tolerances import load_tolerances
    from comparisons.stages import linear_check as lc
    monkeypatch.setattr(lc, "SPEED_RANGE", (1.0, 5.0))
    sec = lc.linear_check(load_tolerances(), "benchmark")
    speeds = {r["quantity"]: r for r in sec.comparisons if r["quantity"].endswith("speed")}
    assert all(r["note"].startswith("in 1-5 m/s;") for r in speeds.values())
    capsize = speeds["linearization vs closed form: capsize speed"]
    assert capsize["closed_form"] is None and capsize["linearization"] is None


# -- the engines' linearization section (comparisons/stages/engine_eigenvalues.py) ----------

import numpy as np  # noqa: E402
from types import SimpleNamespace  # noqa: E402

from comparisons.stages import engine_eigenvalues as ee  # noqa: E402

#: tolerances as the judgment reads them (``tolerances[name].tolerance``), chosen by hand
EE_TOL = {"engine_eigenvalues": SimpleNamespace(tolerance=1e-9),
          "engine_critical_speeds": SimpleNamespace(tolerance=1e-6)}


def _lam(v, re=lambda v: 1.0 - v / 4.0):
    """Hand-made roll/steer eigenvalues (n, 4): a pair re(v) +- 1j (its real part crosses zero
    from + to - at v = 4 by default: the weave speed), -10, and v - 6.25 (the product of the
    four, (re^2 + 1)(-10)(v - 6.25), changes sign at v = 6.25, on neither grid: the capsize
    speed)."""
    v = np.atleast_1d(np.asarray(v, dtype=float))
    r = re(v)
    return np.stack([r + 1j, r - 1j, np.full_like(v, -10.0) + 0j, v - 6.25 + 0j], axis=1)


class _FakeEngine:
    """An engine whose eigenvalues are `_lam`'s (or ``lam``), recording each call's speeds."""

    def __init__(self, lam=_lam, capabilities=("eigenvalues",)):
        self.calls, self._lam, self.capabilities = [], lam, set(capabilities)

    def supports(self, capability):
        return capability in self.capabilities

    def eigenvalues(self, v):
        v = np.atleast_1d(np.asarray(v, dtype=float))
        self.calls.append(v)
        return self._lam(v)


def test_the_comparisons_grid_range_and_default_models():
    """docs/report.md: 21 speeds 0-10 m/s every 0.5 m/s, critical speeds in 0-10 m/s, the
    benchmark and thesis-disc by default."""
    assert ee.GRID == tuple(0.5 * i for i in range(21))
    assert all(type(v) is float for v in ee.GRID)
    assert ee.SPEED_RANGE == (0.0, 10.0)
    assert ee.DEFAULT_MODELS == ("benchmark", "thesis-disc")


def test_a_model_with_drag_is_linearized_with_cv_zero_and_says_so():
    from reference_model import load_model
    disc = load_model("thesis-disc")
    assert disc.params.cv == 0.8            # kg/m: the premise of this test
    m, note = ee.linearization_model("thesis-disc")
    assert m.params == disc.params.replace(cv=0.0)
    assert note == "thesis-disc has drag (cv = 0.8 kg/m): linearized with cv = 0"
    bench, note = ee.linearization_model("benchmark")
    assert bench.params == load_model("benchmark").params and note == ""


def test_the_references_side_is_its_exact_eigenvalues_and_meijaards_speeds():
    """The benchmark's weave and capsize speeds (Meijaard et al. 2007: 4.2924 and 6.0243 m/s,
    `linearize`'s own root finding on a 0.01 m/s grid to brentq's 1e-12; 1e-10 m/s leaves
    round-off room)."""
    from reference_model import load_model
    from reference_model.linearize import capsize_speed, weave_speed
    m = load_model("benchmark")
    lam, (w, k) = ee.reference_linearization(m, [1.0, 5.0])
    assert np.array_equal(lam, m.eigenvalues(np.array([1.0, 5.0])))
    assert abs(w - weave_speed(m, (0.0, 10.0))) < 1e-10 and abs(w - 4.2924) < 1e-4
    assert abs(k - capsize_speed(m, (0.0, 10.0))) < 1e-10 and abs(k - 6.0243) < 1e-4


def test_linearized_finds_the_critical_speeds_on_the_engines_own_eigenvalues():
    """`_lam`'s weave speed is 4 m/s (a grid point: exact) and capsize 6.25 m/s (brentq to 1e-12:
    1e-9 is round-off room); the grid's eigenvalues are one batch call, the root finding
    calls of one speed each, and no curve without a fine grid."""
    eng = _FakeEngine()
    out = ee.linearized(eng, ee.GRID)
    assert set(out) == {"lam", "curve", "critical", "seconds"}
    assert np.array_equal(out["lam"], _lam(np.array(ee.GRID)))
    assert out["curve"] is None
    w, k = out["critical"]
    assert w == 4.0 and abs(k - 6.25) < 1e-9
    assert 0.0 <= out["seconds"] < 5.0      # a few ms; 5 s: any loaded machine
    batches = [c for c in eng.calls if c.size > 1]
    assert len(batches) == 1 and np.array_equal(batches[0], ee.GRID)


def test_linearized_brackets_on_the_fine_grid_when_given():
    """A weave pair unstable only in 4.2-4.4 m/s: the 0.5 m/s grid (4.0, 4.5) misses it, the
    0.1 m/s fine grid brackets it (4.3) and finds 4.4 (to brentq's 1e-12: 1e-9 round-off
    room); the fine grid's eigenvalues are the curve."""
    from comparisons.stages.option_study import CURVE
    narrow = lambda v: _lam(v, re=lambda v: -(v - 4.2) * (v - 4.4))   # noqa: E731
    coarse = ee.linearized(_FakeEngine(narrow), ee.GRID)
    assert coarse["critical"][0] is None and abs(coarse["critical"][1] - 6.25) < 1e-9
    eng = _FakeEngine(narrow)
    fine = ee.linearized(eng, ee.GRID, CURVE)
    assert abs(fine["critical"][0] - 4.4) < 1e-9 and abs(fine["critical"][1] - 6.25) < 1e-9
    assert np.array_equal(fine["curve"], narrow(np.array(CURVE)))
    assert np.array_equal(fine["lam"], narrow(np.array(ee.GRID)))
    batches = [c for c in eng.calls if c.size > 1]
    assert len(batches) == 2 and np.array_equal(batches[1], CURVE)


@pytest.fixture
def fake_load(monkeypatch):
    """`engines.load_engine` replaced: records (spec, model, options) and returns or raises
    what the test sets in ``result``."""
    import engines
    state = SimpleNamespace(calls=[], result=None)

    def load(spec, model, **options):
        state.calls.append((spec, model, options))
        if isinstance(state.result, Exception):
            raise state.result
        return state.result(model) if callable(state.result) else state.result

    monkeypatch.setattr(engines, "load_engine", load)
    return state


def test_an_engines_linearization_value_on_a_model_with_drag(fake_load):
    """The engine built on the cv = 0 model with the run's options; its eigenvalues (here the
    reference's own, so both sides agree: critical speeds within 1e-10 m/s of two root
    finders) and the reference's, under the keys the section reads."""
    from reference_model import load_model
    fake_load.result = lambda model: _FakeEngine(lam=model.eigenvalues)
    v = ee.engine_linearization("some.spec", {"k": 1}, "thesis-disc", "Label")
    ((spec, model, options),) = fake_load.calls
    assert spec == "some.spec" and options == {"k": 1}
    assert model.params == load_model("thesis-disc").params.replace(cv=0.0)
    assert set(v) == {"engine", "model", "note", "speeds", "lam", "critical", "seconds",
                      "ref_lam", "ref_critical"}
    assert v["engine"] == "Label" and v["model"] == "thesis-disc" and v["speeds"] == ee.GRID
    assert v["note"] == "thesis-disc has drag (cv = 0.8 kg/m): linearized with cv = 0"
    assert np.array_equal(v["lam"], model.eigenvalues(np.array(ee.GRID)))
    assert np.array_equal(v["ref_lam"], v["lam"])
    for mine, ref in zip(v["critical"], v["ref_critical"]):
        assert (mine is None and ref is None) or abs(mine - ref) < 1e-10
    assert 0.0 <= v["seconds"] < 5.0
    # no label: the spec names the engine
    assert ee.engine_linearization("some.spec", {}, "benchmark")["engine"] == "some.spec"


def test_a_declared_limitation_is_not_run_and_a_build_error_fails(fake_load):
    from engines import EngineError, UnsupportedModel
    from engines.base import CapabilityError
    base = {"engine": "e", "model": "benchmark", "note": "", "speeds": ee.GRID}
    for exc in (UnsupportedModel("no such contact"), CapabilityError("no such contact")):
        fake_load.result = exc
        assert ee.engine_linearization("s", {}, "benchmark", "e") == {
            **base, "not_run": "not run on this model: no such contact"}
    fake_load.result = EngineError("it broke")
    assert ee.engine_linearization("s", {}, "benchmark", "e") == {**base, "failed": "it broke"}
    fake_load.result = _FakeEngine(capabilities=())
    assert ee.engine_linearization("s", {}, "benchmark", "e") == {
        **base, "not_run": "its options leave it without the eigenvalues capability"}


def _ee_value(engine, model, err_at=None, err=0.0, critical=(4.25, 6.5),
              ref_critical=(4.25, 6.5), seconds=0.123, note=""):
    """A hand-built `engine_linearization` value: the reference's eigenvalues `_lam` on the
    grid (largest |eigenvalue| at each speed: 10, so the relative error is |offset| / 10),
    the engine's the same but for ``err`` * 10 added to the fourth at speed index ``err_at``."""
    ref = _lam(np.array(ee.GRID))
    lam = ref.copy()
    if err_at is not None:
        lam[err_at, 3] += 10.0 * err
    return {"engine": engine, "model": model, "note": note, "speeds": ee.GRID, "lam": lam,
            "ref_lam": ref, "critical": critical, "ref_critical": ref_critical,
            "seconds": seconds}


def test_check_of_judges_a_value_and_carries_a_declared_difference():
    v = _ee_value("e", "m", err_at=7, err=4e-10)
    c = ee.check_of(v, EE_TOL)
    assert (c.engine, c.model, c.speeds) == ("e", "m", ee.GRID)
    assert math.isclose(c.error, 4e-10, rel_tol=1e-6) and c.worst_speed == 3.5
    assert c.speed_range == (0.0, 10.0) and c.passed is True and c.difference == ""
    assert ee.check_of(v, EE_TOL, "a wider tyre").passed is None


EE_VALUES = [
    {"engine": "B", "model": "bench", "note": "", "speeds": (),
     "not_run": "not run on this model: no disc"},                          # first: not a stop
    _ee_value("A", "bench", err_at=7, err=4e-10, ref_critical=(4.25 + 3e-11, 6.5)),   # pass
    _ee_value("A", "disc", err_at=20, err=2e-6, critical=(None, 6.5),                # FAIL
              note="disc has drag (cv = 0.8 kg/m): linearized with cv = 0"),
    {"engine": "C", "model": "bench", "note": "", "speeds": (), "failed": "it broke"},
    _ee_value("D", "bench", critical=(None, None), ref_critical=(None, None), seconds=2.0,
              note="a note"),                                                # pass: none on both
]


def test_the_engines_table_cells_and_verdicts():
    sec, _ = ee.engine_eigenvalues_section(EE_VALUES, EE_TOL)
    assert sec.title == "Engines' linearizations against the reference's"
    (table,) = _tables(sec)
    assert table.header == ("engine", "model", "eigenvalue error (relative)",
                            "weave speed [m/s] (|difference|)",
                            "capsize speed [m/s] (|difference|)", "time [s]", "verdict", "why")
    assert table.rows == (
        ("B", "bench", "-", "-", "-", "-", "not run", "not run on this model: no disc"),
        ("A", "bench", "4.0e-10 at 3.5 m/s", "4.2500000000 (3e-11)", "6.5000000000 (0e+00)",
         "0.12", "pass", ""),
        ("A", "disc", "2.0e-06 at 10 m/s", "none (-)", "6.5000000000 (0e+00)", "0.12", "FAIL", ""),
        ("C", "bench", "-", "-", "-", "-", "FAIL", "it broke"),
        ("D", "bench", "0.0e+00 at 0 m/s", "none (-)", "none (-)", "2.00", "pass", ""))
    # the note under the table says what a 'none' cell means
    assert table.note.startswith("none: no such speed in the range")


def test_the_engines_rows_not_run_failed_and_judged():
    sec, _ = ee.engine_eigenvalues_section(EE_VALUES, EE_TOL)
    rows = [r.as_dict() for r in sec.comparisons]
    assert len(rows) == 1 + 3 + 3 + 1 + 3          # a not-run and a failed row, 3 per judged
    for r in rows:
        assert list(r)[:len(COMMON)] == list(COMMON)
    skipped, failed = rows[0], rows[7]
    assert skipped == {"quantity": "eigenvalues: roll/steer eigenvalues",
                       "scenario": "upright straight running", "model": "bench",
                       "engines": ["reference", "B"], "max_error": None, "tolerance": 1e-9,
                       "passed": None, "localized_to": "not run on this model: no disc",
                       "note": "not run on this model: no disc"}
    assert failed == {**skipped, "engines": ["reference", "C"], "passed": False,
                      "localized_to": "it broke", "note": "it broke"}
    assert [r["passed"] for r in rows] == [None, True, True, True, False, False, True, False,
                                           True, True, True]
    a_bench = rows[1:4]
    assert [r["quantity"] for r in a_bench] == ["eigenvalues: roll/steer eigenvalues",
                                                "eigenvalues: weave speed",
                                                "eigenvalues: capsize speed"]
    assert all(r["scenario"] == "upright straight running" and r["model"] == "bench"
               and r["engines"] == ["reference", "A"] for r in a_bench)
    assert math.isclose(a_bench[0]["max_error"], 4e-10, rel_tol=1e-6)
    assert a_bench[0]["localized_to"] == "v = 3.5 m/s"
    assert "declared_difference" not in a_bench[0]
    assert math.isclose(a_bench[1]["max_error"], 3e-11, rel_tol=1e-3)
    assert rows[4]["localized_to"] == "v = 10 m/s"


def test_the_engines_summary_entries():
    _, summary = ee.engine_eigenvalues_section(EE_VALUES, EE_TOL)
    assert list(summary) == ["B", "A", "C", "D"]
    assert summary["B"] == {"bench": {"not_run": "not run on this model: no disc"}}
    assert summary["C"] == {"bench": {"failed": "it broke"}}
    a = summary["A"]
    assert list(a) == ["bench", "disc"]
    assert list(a["bench"]) == ["max_error", "worst_speed", "weave_speed", "capsize_speed",
                                "reference_weave_speed", "reference_capsize_speed", "passed",
                                "seconds"]
    assert math.isclose(a["bench"]["max_error"], 4e-10, rel_tol=1e-6)
    assert {k: a["bench"][k] for k in list(a["bench"])[1:]} == {
        "worst_speed": 3.5, "weave_speed": 4.25, "capsize_speed": 6.5,
        "reference_weave_speed": 4.25 + 3e-11, "reference_capsize_speed": 6.5,
        "passed": True, "seconds": 0.123}
    assert a["disc"]["passed"] is False and a["disc"]["worst_speed"] == 10.0
    assert a["disc"]["weave_speed"] is None and a["disc"]["reference_weave_speed"] == 4.25
    assert summary["D"]["bench"]["passed"] is True and summary["D"]["bench"]["seconds"] == 2.0


def test_the_engines_text_names_the_tolerances_and_each_note_once():
    sec, _ = ee.engine_eigenvalues_section(EE_VALUES, EE_TOL)
    (text,) = _texts(sec)
    assert "21 speeds 0-10 m/s" in text and "tolerance 1e-09" in text
    assert "in 0-10 m/s" in text and "within 1e-06 m/s" in text
    assert text.endswith(" a note; disc has drag (cv = 0.8 kg/m): linearized with cv = 0.")
    (plain,) = _texts(ee.engine_eigenvalues_section(EE_VALUES[:2], EE_TOL)[0])
    assert plain.endswith("within 1e-06 m/s.")


def _ee_plan(models=(), quick=False):
    facts = {"reference": SimpleNamespace(spec="reference", name="reference", label="Ref",
                                          capabilities={"eigenvalues"}),
             "a.spec": SimpleNamespace(spec="a.spec", name="a", label="Engine A",
                                       capabilities={"eigenvalues", "runs"}),
             "x.spec": SimpleNamespace(spec="x.spec", name="x", label="X", capabilities={"runs"}),
             "b.spec": SimpleNamespace(spec="b.spec", name="b", label="Engine B",
                                       capabilities={"eigenvalues"})}
    opts = SimpleNamespace(models=tuple(SimpleNamespace(spec=s) for s in models), quick=quick,
                           tolerances=EE_TOL, options_for=lambda: {"a.spec": {"k": 1}})
    from comparisons.stages.stage import Plan
    return Plan(opts, (), facts)


def test_the_engines_stage_asks_one_task_per_model_and_engine_with_the_capability():
    stage = ee.EngineEigenvaluesStage()
    assert (stage.name, stage.section) == ("engine-eigenvalues", "eigenvalues")
    tasks = stage.tasks(_ee_plan(("m1.toml", "m2.toml")))
    assert [(t.key, t.func, t.args, t.cost, t.label, t.engine) for t in tasks] == [
        (("a.spec", "m1.toml"), ee.engine_linearization, ("a.spec", {"k": 1}, "m1.toml", "a"),
         0.5, "m1.toml: eigenvalues of Engine A", "a.spec"),
        (("b.spec", "m1.toml"), ee.engine_linearization, ("b.spec", {}, "m1.toml", "b"),
         0.5, "m1.toml: eigenvalues of Engine B", "b.spec"),
        (("a.spec", "m2.toml"), ee.engine_linearization, ("a.spec", {"k": 1}, "m2.toml", "a"),
         0.5, "m2.toml: eigenvalues of Engine A", "a.spec"),
        (("b.spec", "m2.toml"), ee.engine_linearization, ("b.spec", {}, "m2.toml", "b"),
         0.5, "m2.toml: eigenvalues of Engine B", "b.spec")]
    assert [t.key for t in stage.tasks(_ee_plan())] == [
        ("a.spec", "benchmark"), ("b.spec", "benchmark"), ("a.spec", "thesis-disc"),
        ("b.spec", "thesis-disc")]
    assert stage.tasks(_ee_plan(("m1.toml",), quick=True)) == []


def test_the_engines_stage_assembles_one_section_and_a_failed_task_as_a_failing_row():
    from comparisons.stages.pool import TaskResult
    stage, plan = ee.EngineEigenvaluesStage(), _ee_plan()
    assert stage.assemble(plan, {}).sections == [] and stage.assemble(plan, {}).summary == {}
    good = _ee_value("a", "bench")
    out = stage.assemble(plan, {("a.spec", "benchmark"): TaskResult(("a.spec", "benchmark"),
                                                                     good, 0.1),
                                ("b.spec", "benchmark"): TaskResult(("b.spec", "benchmark"),
                                                                     None, 0.1, "boom")})
    first, second = out.sections
    assert first.title == "Engines' linearizations against the reference's"
    assert [r["passed"] for r in first.comparisons] == [True, True, True]
    assert list(out.summary) == ["engine_eigenvalues"]
    assert out.summary["engine_eigenvalues"]["a"]["bench"]["passed"] is True
    assert second.title == "Eigenvalues of Engine B"
    assert [(r["passed"], r["localized_to"]) for r in second.comparisons] == [(False, "boom")]
    only_failed = stage.assemble(plan, {("b.spec", "m"): TaskResult(("b.spec", "m"), None, 0.1,
                                                                      "boom")})
    assert [s.title for s in only_failed.sections] == ["Eigenvalues of Engine B"]
    assert only_failed.summary == {}


# -- the option studies (comparisons/stages/option_study.py) --------------------------------

from comparisons.stages import option_study as os_  # noqa: E402


def test_the_option_studys_figure_grid_and_default_model():
    """docs: the figure's 0.1 m/s grid over 0-10 m/s (101 speeds, the ends included), the
    benchmark by default."""
    assert len(os_.CURVE) == 101 and os_.CURVE[0] == 0.0 and os_.CURVE[-1] == 10.0
    assert all(v == round(0.1 * k, 10) for k, v in enumerate(os_.CURVE))
    assert os_.DEFAULT_MODEL == "benchmark"


def test_an_option_value_is_the_engine_built_with_that_value(fake_load):
    """The engine built with the run's options and the option set to the value (overriding
    the run's); its eigenvalues on both grids, the reference's on both (here the engine is
    the reference's own eigenvalues: critical speeds within 1e-10 m/s of two root finders)."""
    from reference_model import load_model
    fake_load.result = lambda model: _FakeEngine(lam=model.eigenvalues)
    v = os_.option_value("s.spec", {"k": 1, "crown": 9.0}, "crown", 0.01, "thesis-disc")
    ((spec, model, options),) = fake_load.calls
    assert spec == "s.spec" and options == {"k": 1, "crown": 0.01}
    assert model.params == load_model("thesis-disc").params.replace(cv=0.0)
    assert set(v) == {"value", "model", "note", "speeds", "lam", "curve", "critical", "seconds",
                      "ref_lam", "ref_curve", "ref_critical"}
    assert v["value"] == 0.01 and type(v["value"]) is float
    assert v["model"] == "thesis-disc" and v["speeds"] == ee.GRID
    assert v["note"] == "thesis-disc has drag (cv = 0.8 kg/m): linearized with cv = 0"
    assert np.array_equal(v["lam"], model.eigenvalues(np.array(ee.GRID)))
    assert np.array_equal(v["curve"], model.eigenvalues(np.array(os_.CURVE)))
    assert np.array_equal(v["ref_lam"], v["lam"]) and np.array_equal(v["ref_curve"], v["curve"])
    for mine, ref in zip(v["critical"], v["ref_critical"]):
        assert (mine is None and ref is None) or abs(mine - ref) < 1e-10
    assert 0.0 <= v["seconds"] < 5.0
    assert type(os_.option_value("s", {}, "crown", 1, "benchmark")["value"]) is float


def test_an_option_value_the_engine_cannot_build_is_not_run(fake_load):
    from engines import UnsupportedModel
    from engines.base import CapabilityError
    for exc in (UnsupportedModel("no torus"), CapabilityError("no torus")):
        fake_load.result = exc
        assert os_.option_value("s", {}, "crown", 0.02, "benchmark") == {
            "value": 0.02, "model": "benchmark", "note": "", "speeds": ee.GRID,
            "not_run": "not run on this model: no torus"}


def _os_value(x, err_at=None, err=0.0, critical=(4.0, 6.25), ref_critical=(4.0, 6.25),
              note=""):
    """A hand-built `option_value`: `_ee_value`'s eigenvalues (relative error ``err`` at speed
    index ``err_at``) and a figure curve: the reference's `_lam` on CURVE plus ``x`` (so each
    value's curve is told apart)."""
    v = _ee_value("unused", "bench", err_at, err, critical, ref_critical, 0.3, note)
    curve = _lam(np.array(os_.CURVE))
    return {"value": x, "model": "bench", "note": note, "speeds": ee.GRID, "lam": v["lam"],
            "ref_lam": v["ref_lam"], "curve": curve + x, "ref_curve": curve,
            "critical": critical, "ref_critical": ref_critical, "seconds": 0.3}


def _study(**kw):
    from engines.facts import OptionStudy
    args = dict(option="crown_radius", quantity="crown radius", unit="m",
                values=(0.0, 0.01, 0.02), reference_value=0.0, difference="a torus",
                why="the tyres' range")
    return OptionStudy(**{**args, **kw})


SYM = SimpleNamespace(name="sym b", label="SymB", spec="sym.spec", capabilities={"eigenvalues"},
                      contacts=("knife-edge",))

OS_VALUES = [
    _os_value(0.0, err_at=4, err=3e-10, ref_critical=(4.0, 6.25 + 2e-7),
              note="bench has drag (cv = 0.8 kg/m): linearized with cv = 0"),   # judged: pass
    _os_value(0.01, err_at=20, err=2.5e-3, critical=(3.9, 6.0)),                 # reported
    {"value": 0.02, "model": "bench", "note": "", "speeds": ee.GRID,
     "not_run": "not run on this model: no torus"},
]


def test_the_option_studys_table():
    sec, _ = os_.option_study_section(SYM, _study(), "bench", OS_VALUES, EE_TOL)
    assert sec.title == "Option study: SymB's crown radius on bench"
    (table,) = _tables(sec)
    assert table.header == ("crown radius [m]", "eigenvalues vs reference (relative)",
                            "weave speed [m/s]", "shift [m/s]", "capsize speed [m/s]",
                            "shift [m/s]", "verdict")
    # shifts: 0 -> '+0e+00'; -2e-7 (below 5e-7: its size) -> '-2e-07'; -0.1 and -0.25 m/s
    assert table.rows == (
        ("0", "3.00e-10", "4.000000", "+0e+00", "6.250000", "-2e-07", "pass"),
        ("0.01", "2.50e-03", "3.900000", "-0.100000", "6.000000", "-0.250000",
         "reported: model difference"),
        ("0.02", "-", "-", "-", "-", "-", "not run"))
    # the note says how to read a shift and a 'none'
    assert table.note.startswith("shift: the engine's critical speed minus the reference's")
    assert table.note.endswith("; none: no such speed in 0-10 m/s")


def test_a_value_not_run_does_not_stop_the_values_after_it():
    sec, summary = os_.option_study_section(SYM, _study(), "bench", OS_VALUES[::-1], EE_TOL)
    assert [r[0] for r in _tables(sec)[0].rows] == ["0.02", "0.01", "0"]
    assert [e["value"] for e in summary["values"]] == [0.02, 0.01, 0.0]
    assert len(sec.comparisons) == 1 + 3 + 3


def test_a_shift_of_a_critical_speed_keeps_six_decimals_down_to_half_a_micrometre_per_second():
    assert os_._shift(4.000002, 4.0) == "+0.000002"
    # exactly 5e-7 (the float 4.99999999999999977e-7): 6 decimals, which round it down
    assert os_._shift(5e-7, 0.0) == "+0.000000"
    assert os_._shift(4.0, 4.0000004) == "-4e-07"      # under 5e-7: its size
    assert os_._shift(None, 4.0) == os_._shift(4.0, None) == "-"
    assert os_._speed(None) == "none" and os_._speed(1.23456789) == "1.234568"


def test_the_option_studys_rows_judge_the_reference_value_and_report_the_others():
    sec, _ = os_.option_study_section(SYM, _study(), "bench", OS_VALUES, EE_TOL)
    rows = [r.as_dict() for r in sec.comparisons]
    assert len(rows) == 3 + 3 + 1
    for r in rows:
        assert list(r)[:len(COMMON)] == list(COMMON)
        assert r["model"] == "bench" and r["engines"] == ["reference", "sym b"]
    assert [r["passed"] for r in rows] == [True, True, True, None, None, None, None]
    assert [r["quantity"] for r in rows[:3]] == [
        "option study crown_radius: roll/steer eigenvalues", "option study crown_radius: "
        "weave speed", "option study crown_radius: capsize speed"]
    assert [r["scenario"] for r in rows] == ["crown_radius = 0 m"] * 3 + \
        ["crown_radius = 0.01 m"] * 3 + ["crown_radius = 0.02 m"]
    assert all((r["option"], r["value"]) == ("crown_radius", 0.0) for r in rows[:3])
    assert all((r["option"], r["value"]) == ("crown_radius", 0.01) for r in rows[3:6])
    assert all("declared_difference" not in r for r in rows[:3])
    assert all(r["declared_difference"] == "crown_radius = 0.01 m: a torus" for r in rows[3:6])
    assert math.isclose(rows[0]["max_error"], 3e-10, rel_tol=1e-6)
    assert math.isclose(rows[3]["max_error"], 2.5e-3, rel_tol=1e-9)
    assert rows[6] == {"quantity": "option study crown_radius: roll/steer eigenvalues",
                       "scenario": "crown_radius = 0.02 m", "model": "bench",
                       "engines": ["reference", "sym b"], "max_error": None, "tolerance": None,
                       "passed": None, "localized_to": "not run on this model: no torus",
                       "note": "not run on this model: no torus"}
    # the reference value out of tolerance fails: 2e-9 relative against 1e-9
    bad = [_os_value(0.0, err_at=3, err=2e-9), OS_VALUES[1]]
    sec, summary = os_.option_study_section(SYM, _study(), "bench", bad, EE_TOL)
    assert sec.comparisons[0]["passed"] is False and _tables(sec)[0].rows[0][-1] == "FAIL"
    assert summary["values"][0]["passed"] is False


def test_the_option_studys_summary_entry():
    _, summary = os_.option_study_section(SYM, _study(), "bench", OS_VALUES, EE_TOL)
    first, second, third = summary.pop("values")
    assert summary == {"engine": "sym b", "option": "crown_radius", "unit": "m", "model": "bench",
                       "reference_value": 0.0, "reference_weave_speed": 4.0,
                       "reference_capsize_speed": 6.25 + 2e-7}
    assert math.isclose(first.pop("eigenvalue_distance"), 3e-10, rel_tol=1e-6)
    assert first == {"value": 0.0, "weave_speed": 4.0, "capsize_speed": 6.25, "passed": True,
                     "declared_difference": None}
    assert math.isclose(second.pop("eigenvalue_distance"), 2.5e-3, rel_tol=1e-9)
    assert second == {"value": 0.01, "weave_speed": 3.9, "capsize_speed": 6.0, "passed": None,
                      "declared_difference": "crown_radius = 0.01 m: a torus"}
    assert third == {"value": 0.02, "not_run": "not run on this model: no torus"}


def test_the_option_studys_figure_of_the_values_that_ran():
    sec, _ = os_.option_study_section(SYM, _study(), "bench", OS_VALUES, EE_TOL)
    (fig,) = sec.figures
    assert (fig.name, fig.kind) == ("option_study_sym-b_crown_radius_bench.png", "option_study")
    d = fig.data
    assert set(d) == {"engine", "label", "quantity", "unit", "values", "reference_value", "v",
                      "re", "ref_re", "critical", "ref_critical", "model"}
    assert (d["engine"], d["label"], d["quantity"], d["unit"], d["model"]) == (
        "sym b", "SymB", "crown radius", "m", "bench")
    assert d["values"] == [0.0, 0.01] and d["reference_value"] == 0.0
    assert np.array_equal(d["v"], os_.CURVE)
    curve = _lam(np.array(os_.CURVE)).real
    assert d["re"].shape == (2, 101, 4)
    assert np.array_equal(d["re"][0], curve) and np.array_equal(d["re"][1], curve + 0.01)
    assert np.array_equal(d["ref_re"], curve)
    assert d["critical"] == [(4.0, 6.25), (3.9, 6.0)] and d["ref_critical"] == (4.0, 6.25 + 2e-7)
    assert fig.caption
    # nothing ran: no figure, no reference speeds
    sec, summary = os_.option_study_section(SYM, _study(), "bench", OS_VALUES[2:], EE_TOL)
    assert sec.figures == [] and (summary["reference_weave_speed"],
                                  summary["reference_capsize_speed"]) == (None, None)


def test_the_option_studys_text_names_the_values_and_the_first_values_note():
    sec, _ = os_.option_study_section(SYM, _study(), "bench", OS_VALUES, EE_TOL)
    (text,) = _texts(sec)
    assert text.startswith("`crown_radius` = 0 m is the reference's bicycle; any other value "
                           "is a declared model difference: a torus. Values 0, 0.01, 0.02 m "
                           "(the tyres' range). At 0 m ")
    assert text.endswith(" bench has drag (cv = 0.8 kg/m): linearized with cv = 0.")
    (plain,) = _texts(os_.option_study_section(SYM, _study(why=""), "bench", OS_VALUES[1:],
                                               EE_TOL)[0])
    assert "Values 0, 0.01, 0.02 m. At 0 m " in plain and plain.endswith("quantify the difference.")
    (empty,) = _texts(os_.option_study_section(SYM, _study(), "bench", [], EE_TOL)[0])
    assert empty.endswith("quantify the difference.")


def _os_plan(models=(), quick=False, studies=None):
    """A plan with engine 'sym' (eigenvalues, a crown study, the knife-edge contact), 'plain'
    (eigenvalues, no study) and 'runs' (a study but no eigenvalues)."""
    studies = (_study(),) if studies is None else studies
    facts = {"reference": SimpleNamespace(spec="reference", capabilities={"eigenvalues"},
                                          option_studies=studies),
             "sym.spec": SimpleNamespace(**{**vars(SYM), "option_studies": studies}),
             "plain": SimpleNamespace(spec="plain", name="plain", label="Plain",
                                      capabilities={"eigenvalues"}, option_studies=()),
             "runs": SimpleNamespace(spec="runs", name="runs", label="Runs",
                                     capabilities={"runs"}, option_studies=studies)}
    opts = SimpleNamespace(models=tuple(models), quick=quick, tolerances=EE_TOL,
                           options_for=lambda: {"sym.spec": {"k": 1}})
    from comparisons.stages.stage import Plan
    return Plan(opts, (), facts)


def test_the_option_study_stage_asks_one_task_per_value_and_model_it_models():
    stage = os_.OptionStudyStage()
    assert (stage.name, stage.section) == ("option-study", "option-study")
    tasks = stage.tasks(_os_plan())
    assert [(t.key, t.func, t.args, t.cost, t.label, t.engine) for t in tasks] == [
        (("sym.spec", "crown_radius", "benchmark", x), os_.option_value,
         ("sym.spec", {"k": 1}, "crown_radius", x, "benchmark"), 0.4,
         f"benchmark: SymB at crown_radius = {x:g} m", "sym.spec") for x in (0.0, 0.01, 0.02)]
    models = (SimpleNamespace(spec="k.toml", name="K", contact="knife-edge"),
              SimpleNamespace(spec="t.toml", name="T", contact="torus"))
    assert [t.key[2:] for t in stage.tasks(_os_plan(models))] == [
        ("k.toml", 0.0), ("k.toml", 0.01), ("k.toml", 0.02)]
    assert stage._models(_os_plan(models), SYM) == (["k.toml"], [models[1]])
    assert stage._models(_os_plan(), SYM) == (["benchmark"], [])
    two = (models[0], SimpleNamespace(spec="k2.toml", name="K2", contact="knife-edge"))
    assert [t.key[2:] for t in stage.tasks(_os_plan(two))] == [
        ("k.toml", 0.0), ("k.toml", 0.01), ("k.toml", 0.02), ("k2.toml", 0.0), ("k2.toml", 0.01),
        ("k2.toml", 0.02)]
    # --quick: only the declared quick values, and no study without them
    assert stage.tasks(_os_plan(quick=True)) == []
    quick = _os_plan(quick=True, studies=(_study(quick_values=(0.0,)),))
    assert [t.key[3] for t in stage.tasks(quick)] == [0.0]


def test_the_option_study_stage_prepares_each_running_study_once():
    calls = []
    stage = os_.OptionStudyStage()
    stage.prepare(_os_plan(studies=(_study(prepare=lambda: calls.append("crown")),
                                    _study(option="other"))))
    assert calls == ["crown"]          # the study of 'runs' (no eigenvalues) is not prepared
    stage.prepare(_os_plan(quick=True, studies=(_study(prepare=lambda: calls.append("q")),)))
    assert calls == ["crown"]


def test_the_option_study_stage_assembles_per_model_failures_and_contacts_it_does_not_model():
    from comparisons.stages.pool import TaskResult
    models = (SimpleNamespace(spec="k.toml", name="K", contact="knife-edge"),
              SimpleNamespace(spec="t.toml", name="T", contact="torus"))
    plan, stage = _os_plan(models), os_.OptionStudyStage()
    results = {}
    for x, v in zip((0.0, 0.01), OS_VALUES):
        key = ("sym.spec", "crown_radius", "k.toml", x)
        results[key] = TaskResult(key, v, 0.3)
    bad = ("sym.spec", "crown_radius", "k.toml", 0.02)
    results[bad] = TaskResult(bad, None, 0.3, "boom")
    other = ("sym.spec", "other_option", "k.toml", 0.0)     # not a study of this plan
    results[other] = TaskResult(other, None, 0.3, "ignored")
    out = stage.assemble(plan, results)
    study, failed, limitation = out.sections
    assert study.title == "Option study: SymB's crown radius on bench"
    assert [r["passed"] for r in study.comparisons] == [True, True, True, None, None, None]
    assert failed.title == "Option study: SymB at crown_radius = 0.02 m"
    assert [(r["passed"], r["localized_to"]) for r in failed.comparisons] == [(False, "boom")]
    why = "not run on this model: SymB models the front contact(s) knife-edge, not 'torus'"
    assert limitation.title == "Option study: SymB's crown radius on T"
    assert _texts(limitation) == [why + "."]
    assert [r.as_dict() for r in limitation.comparisons] == [{
        "quantity": "option study crown_radius: roll/steer eigenvalues", "scenario": "-",
        "model": "T", "engines": ["reference", "sym b"], "max_error": None, "tolerance": None,
        "passed": None, "localized_to": why, "note": why}]
    (entry,) = out.summary["option_studies"]
    assert entry["engine"] == "sym b" and [e["value"] for e in entry["values"]] == [0.0, 0.01]
    # two models that ran: a section each, in the order their results came
    two = {("sym.spec", "crown_radius", m, 0.0): TaskResult(None, OS_VALUES[0], 0.3)
           for m in ("b.toml", "a.toml")}
    out = stage.assemble(_os_plan(), two)
    assert len(out.sections) == 2 and len(out.summary["option_studies"]) == 2
    assert stage.assemble(_os_plan(), {}).summary == {}
    # an engine modelling two contacts names both in the reason
    both = _os_plan(models)
    both.facts["sym.spec"].contacts = ("knife-edge", "disc")
    (limitation,) = stage.assemble(both, {}).sections
    assert limitation.comparisons[0]["localized_to"] == (
        "not run on this model: SymB models the front contact(s) knife-edge, disc, not 'torus'")
    only_failed = stage.assemble(_os_plan(), {bad: TaskResult(bad, None, 0.3, "boom")})
    assert [s.title for s in only_failed.sections] == ["Option study: SymB at crown_radius = 0.02 m"]
    assert only_failed.summary == {}


# -- a section's blocks and cells (comparisons/stages/results.py) ---------------------------

def test_a_sections_blocks_keep_their_order_and_cells_become_text():
    from comparisons.stages.results import Figure, Heading, Section
    sec = Section("T")
    assert (sec.blocks, sec.comparisons, sec.seconds) == ([], [], 0.0)
    sec.text("one", "two")
    sec.heading("H")
    sec.table(["a", "b"], [[1, None], (2.5, "x")], note="how to read it")
    sec.figure("f.png", "kind", "a caption", x=[1, 2], y="z")
    sec.table(("c",), ())
    assert sec.blocks[:3] == [Text("one"), Text("two"), Heading("H")]
    table = sec.blocks[3]
    assert table == Table(("a", "b"), (("1", "None"), ("2.5", "x")), "how to read it")
    assert type(table.header) is tuple and all(type(r) is tuple for r in table.rows)
    assert sec.blocks[4] == Figure("f.png", "kind", {"x": [1, 2], "y": "z"}, "a caption")
    assert sec.blocks[5] == Table(("c",), (), "")
    assert sec.figures == [sec.blocks[4]]
    sec.figure("g.png", "other")
    assert [f.name for f in sec.figures] == ["f.png", "g.png"] and sec.figures[1].caption == ""
    assert Section("U").figures == [] and Section("U").blocks is not Section("V").blocks


def test_verdict_words_and_number_cells():
    from comparisons.stages.results import FIGURE_POLICIES, num, verdict_word
    assert [verdict_word(p) for p in (True, False, None)] == ["pass", "FAIL", "reported"]
    assert verdict_word(None, "a declared difference") == "reported: a declared difference"
    assert verdict_word(False, "x") == "FAIL: x" and verdict_word(True, "") == "pass"
    assert num(None) == "-" and num(0.000123) == "1.2e-04" and num(2.0, ".3f") == "2.000"
    assert FIGURE_POLICIES == ("all", "failing", "none")


# -- the stage base (comparisons/stages/stage.py) -------------------------------------------

def test_a_plan_reads_the_runs_options():
    from comparisons.stages.stage import Plan
    opts = SimpleNamespace(tolerances="TOLS", quick=True, sections=("faults", "eigenvalues"),
                           options_for=lambda: {"a": {"k": 1}})
    facts = {"a": SimpleNamespace(n=1), "reference": SimpleNamespace(n=0),
             "b": SimpleNamespace(n=2)}
    plan = Plan(opts, ("s",), facts)
    assert (plan.cases, plan.critical) == ((), {})
    assert plan.tolerances == "TOLS" and plan.quick is True
    assert plan.wants(None) and plan.wants("faults") and not plan.wants("option-study")
    assert plan.engines() == [facts["a"], facts["b"]]          # the reference excluded
    assert plan.engines(lambda f: f.n == 2) == [facts["b"]]
    assert plan.options_for("a") == {"k": 1} and plan.options_for("b") == {}


def test_a_failed_stage_is_a_section_with_one_failing_row():
    from comparisons.stages.stage import failed_section
    sec = failed_section("Title", "ValueError: boom")
    assert sec.title == "Title"
    assert _texts(sec) == ["**This stage failed**: ValueError: boom"]
    assert [r.as_dict() for r in sec.comparisons] == [{
        "quantity": "stage", "scenario": "Title", "model": "-", "engines": ["-"],
        "max_error": None, "tolerance": None, "passed": False,
        "localized_to": "ValueError: boom", "note": ""}]


def test_the_stage_bases_defaults():
    from comparisons.stages.pool import TaskResult
    from comparisons.stages.stage import Assembled, Stage
    s = Stage()
    assert (s.name, s.section) == ("stage", None)
    assert s.tasks(None) == [] and s.prepare(None) is None
    out = s.assemble(None, {})
    assert (out.sections, out.faults, out.summary) == ([], [], {})
    assert Assembled().sections is not Assembled().sections
    claims = [{"claim": 1}]
    assert s.revise_claims(None, {}, claims) is claims
    ok = {"k": TaskResult("k", "value", 0.1), "bad": TaskResult("bad", None, 0.1, "boom")}
    assert Stage.value(ok, "k", "T") == ("value", None)
    value, sec = Stage.value(ok, "bad", "T")
    assert value is None and sec.title == "T" and sec.comparisons[0]["localized_to"] == "boom"


# -- term by term (comparisons/stages/terms.py) ---------------------------------------------

from comparisons.judgments.terms import TermComparison  # noqa: E402
from comparisons.stages import terms as tm  # noqa: E402

TERMS = [TermComparison("mass_matrix", ("reference", "x"), 2.0e-10, 1.0e-9, 1e-8, True, 3,
                        "M[theta, gamma]", 50),
         TermComparison("gravity", ("reference", "x"), 3.0e-6, 2.0e-5, 1e-8, False, 7,
                        "Qgrav[phi]", 50)]


def test_the_term_tables_header_and_defaults():
    assert tm.TERM_HEADER == ("model", "quantity", "max error", "tolerance", "verdict",
                              "worst entry")
    assert tm.THESIS_MODELS == ("thesis", "thesis-disc")
    assert (tm.N_STATES, tm.QUICK_N_STATES) == (200, 50)
    assert tm.plugin_terms is tm.engine_terms


def test_term_rows_are_table_rows_and_comparisons():
    from comparisons.stages.results import Section
    sec = Section("s")
    rows = tm.term_rows(sec, TERMS, "bike", ["reference", "X"], "random-states-50", ("bike",))
    assert rows == [("bike", "mass_matrix", "2.0e-10", "1e-08", "pass", "M[theta, gamma]"),
                    ("bike", "gravity", "3.0e-06", "1e-08", "FAIL", "Qgrav[phi]")]
    assert [r.as_dict() for r in sec.comparisons] == [
        {"quantity": q, "scenario": "random-states-50", "model": "bike",
         "engines": ["reference", "X"], "max_error": e, "tolerance": 1e-8, "passed": p,
         "localized_to": w, "note": ""}
        for q, e, p, w in (("mass_matrix", 2.0e-10, True, "M[theta, gamma]"),
                           ("gravity", 3.0e-6, False, "Qgrav[phi]"))]
    assert tm.term_rows(Section("t"), TERMS[:1], "m", ["a", "b"], "s")[0][0] == "mass_matrix"


class _TermsEngine:
    """The reference's mass matrix plus 0.5 at M[phi, theta] (a planted error of known size)."""

    def __init__(self, ref, caps=("mass_matrix",), broken=False):
        self._ref, self.caps, self.broken = ref, set(caps), broken

    def supports(self, cap):
        return cap in self.caps

    def mass_matrix(self, q):
        if self.broken:
            raise RuntimeError("no M today")
        M = np.array(self._ref.mass_matrix(q), dtype=float)
        M[:, 2, 3] += 0.5
        return M


@pytest.fixture
def terms_env(monkeypatch):
    """`engine_terms` with its engines and `compare_terms` replaced: per model name, an
    exception to raise or an engine maker; `compare_terms` returns `TERMS` (with the calls
    recorded)."""
    real = tm.load_engine
    env = SimpleNamespace(per_model={}, loads=[], compares=[])

    def load(spec, model, **options):
        env.loads.append((spec, model.name, options))
        if spec == "reference":
            return real("reference", model)
        what = env.per_model[model.name]
        if isinstance(what, Exception):
            raise what
        return what(real("reference", model))

    def compare(ref, eng, states, tolerances):
        env.compares.append((ref, eng, len(states), tolerances))
        return TERMS

    monkeypatch.setattr(tm, "load_engine", load)
    monkeypatch.setattr(tm, "compare_terms", compare)
    return env


TERM_TOL = {"mass_matrix": SimpleNamespace(tolerance=1e-8)}


def test_engine_terms_rows_not_run_failed_and_the_mass_matrix_figure(terms_env):
    from engines import UnsupportedModel
    terms_env.per_model = {"thesis": UnsupportedModel("no toroidal tyre"),
                           "thesis-disc": _TermsEngine}
    sec = tm.engine_terms(TERM_TOL, "pinocchio", {"k": 1}, 5)
    assert sec.title == "Reference vs Pinocchio, term by term"
    assert [(s, m, o) for s, m, o in terms_env.loads if s != "reference"] == [
        ("pinocchio", "thesis", {"k": 1}), ("pinocchio", "thesis-disc", {"k": 1})]
    assert [n for _, _, n, _ in terms_env.compares] == [5]
    ref, eng, _, tols = terms_env.compares[0]
    assert tols is TERM_TOL and isinstance(eng, _TermsEngine)
    assert (ref.name, ref.model.name) == ("reference", "thesis-disc")   # the reference's side
    (table,) = _tables(sec)
    assert table.header == tm.TERM_HEADER
    assert table.rows == (
        ("thesis", "-", "-", "-", "not run", "not run on this model: no toroidal tyre"),
        ("thesis-disc", "mass_matrix", "2.0e-10", "1e-08", "pass", "M[theta, gamma]"),
        ("thesis-disc", "gravity", "3.0e-06", "1e-08", "FAIL", "Qgrav[phi]"))
    assert [(r["scenario"], r["model"], r["engines"]) for r in sec.comparisons] == [
        ("random-states-5", "thesis-disc", ["reference", "pinocchio"])] * 2
    # the setup the terms were compared under: the spec, its options, the number of states
    assert _texts(sec)[0].startswith("`pinocchio` with {'k': 1} at 5 deterministic states")
    (fig,) = sec.figures
    assert (fig.name, fig.kind) == ("mass_matrix_error_pinocchio_thesis-disc.png", "matrix_error")
    assert set(fig.data) == {"relative", "labels", "tolerance", "title", "colorbar"}
    from comparisons.judgments.terms import random_states
    from reference_model import load_model
    M = load_model("thesis-disc").mass_matrix(random_states(5, seed=7).q)
    expected = np.zeros((8, 8))
    expected[2, 3] = 0.5 / np.abs(M).max()       # the planted 0.5 over the largest |M|
    np.testing.assert_allclose(fig.data["relative"], expected, rtol=1e-9, atol=1e-15)
    assert fig.data["labels"] == list(COORDINATES_) and fig.data["tolerance"] == 1e-8
    assert fig.data["title"] == ("mass matrix: reference vs Pinocchio on thesis-disc, max over "
                                 "the states")
    assert fig.data["colorbar"] == "log10 max |M_ref - M_engine| / max|M|"


COORDINATES_ = ("xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps")


def test_engine_terms_on_a_users_model_a_failed_build_and_no_figure_without_m(terms_env):
    terms_env.per_model = {"benchmark": RuntimeError("it   broke\n badly"),
                           "thesis": _TermsEngine}
    sec = tm.engine_terms(TERM_TOL, "pinocchio", {}, 3, ("benchmark", "thesis"))
    assert sec.title == "Reference vs Pinocchio on benchmark, thesis, term by term"
    assert _texts(sec)[0].startswith("`pinocchio` at 3 deterministic states")
    assert _tables(sec)[0].rows[0] == ("benchmark", "-", "-", "-", "FAIL",
                                       "RuntimeError: it broke badly")
    assert sec.comparisons[0].as_dict() == {
        "quantity": "engine build", "scenario": "-", "model": "benchmark",
        "engines": ["pinocchio"], "max_error": None, "tolerance": None, "passed": False,
        "localized_to": "RuntimeError: it broke badly", "note": ""}
    (fig,) = sec.figures           # on the thesis model: no model suffix
    assert fig.name == "mass_matrix_error_pinocchio.png"
    long = RuntimeError("y" * 400)
    terms_env.per_model = {"benchmark": long}
    sec = tm.engine_terms(TERM_TOL, "pinocchio", {}, 3, ("benchmark",))
    assert sec.comparisons[0]["localized_to"] == "RuntimeError: " + "y" * 300
    assert sec.figures == []                      # nothing built
    for engine in (lambda ref: _TermsEngine(ref, caps=()),            # no M declared
                   lambda ref: _TermsEngine(ref, broken=True)):       # M raises: no figure
        terms_env.per_model = {"benchmark": engine}
        sec = tm.engine_terms(TERM_TOL, "pinocchio", {}, 3, ("benchmark",))
        assert sec.figures == [] and len(sec.comparisons) == 2


def test_the_terms_stage_tasks_and_titles():
    from comparisons.stages.pool import TaskResult
    from comparisons.stages.stage import Plan
    facts = {"reference": SimpleNamespace(spec="reference", has_terms=True),
             "p.spec": SimpleNamespace(spec="p.spec", label="P", has_terms=True,
                                       costs=SimpleNamespace(terms=1.5)),
             "r.spec": SimpleNamespace(spec="r.spec", label="R", has_terms=False)}
    models = (SimpleNamespace(spec="m.toml", name="M"),)
    opts = lambda models, quick: SimpleNamespace(   # noqa: E731
        models=models, quick=quick, tolerances="TOLS", options_for=lambda: {"p.spec": {"k": 1}})
    stage = tm.TermsStage()
    assert (stage.name, stage.section) == ("terms", "terms")
    (t,) = stage.tasks(Plan(opts((), False), (), facts))
    assert (t.key, t.func, t.args, t.cost, t.label, t.engine) == (
        ("p.spec", None), tm.engine_terms, ("TOLS", "p.spec", {"k": 1}, 200), 1.5,
        "P term by term", "p.spec")
    (t,) = stage.tasks(Plan(opts(models, True), (), facts))
    assert (t.key, t.args, t.label) == (("p.spec", "m.toml"),
                                        ("TOLS", "p.spec", {"k": 1}, 50, ("m.toml",)),
                                        "P term by term on M")
    plan = Plan(opts(models, False), (), facts)
    ok = tm.Section("fine")
    out = stage.assemble(plan, {("p.spec", None): TaskResult(None, ok, 0.1),
                                ("p.spec", "m.toml"): TaskResult(None, None, 0.1, "boom"),
                                ("p.spec", "x.toml"): TaskResult(None, None, 0.1, "bang")})
    assert out.sections[0] is ok
    assert [s.title for s in out.sections[1:]] == ["M: reference vs P, term by term",
                                                   "x.toml: reference vs P, term by term"]
    assert out.sections[1].comparisons[0]["localized_to"] == "boom"
    out = stage.assemble(plan, {("p.spec", None): TaskResult(None, None, 0.1, "boom")})
    assert out.sections[0].title == "Reference vs P, term by term"


# -- fault injection (comparisons/stages/faults.py) -----------------------------------------

from comparisons.judgments.faults import FaultResult  # noqa: E402
from comparisons.stages import faults as fl  # noqa: E402


def _fault(name, detected, correct, observable):
    return FaultResult(name, detected, f"{name} here", f"{name} expected", correct, f"{name} ev",
                       ("reference", "x"), ("M[phi, phi]",), 0.99, observable)


FAULTS = [_fault("right", True, True, True), _fault("hidden", False, False, False),
          _fault("wrong place", True, False, True), _fault("missed", False, False, True)]


def test_the_term_quantities_localization_reads():
    assert fl.TERM_QUANTITIES == ("mass_matrix", "inverse_dynamics", "gravity",
                                  "generalized_forces", "constraint_jacobian", "constraint_bias",
                                  "forward_acceleration", "torques", "multipliers")


def test_faults_go_into_the_thesis_bicycle_or_its_disc_variant():
    # engines/facts.py: Pinocchio models both front contacts, Kane only the disc
    assert fl.fault_base("pinocchio") == "thesis" and fl.fault_base("kane") == "thesis-disc"


@pytest.fixture
def suite(monkeypatch):
    calls = []

    def run(**kw):
        calls.append(kw)
        if isinstance(suite.result, Exception):
            raise suite.result
        return suite.result

    suite = SimpleNamespace(calls=calls, result=FAULTS)
    monkeypatch.setattr(fl, "run_fault_suite", run)
    return suite


def test_fault_entries_verdicts_engine_and_model(suite):
    entries = fl.fault_entries("TOLS", "kane", None, (("k", 1),))
    assert suite.calls == [{"engines": ("kane",), "base": "thesis-disc", "tolerances": "TOLS",
                            "options": {"kane": {"k": 1}}}]
    assert [e["verdict"] for e in entries] == ["localized", "not observable",
                                               "detected, mislocalized", "missed"]
    assert all(e["engine"] == "kane" and e["model"] == "thesis-disc" for e in entries)
    assert {k: v for k, v in entries[0].items() if k not in ("engine", "model", "verdict")} == \
        FAULTS[0].to_dict()
    fl.fault_entries("TOLS", "pkg.mod:MyEngine", "benchmark")
    assert suite.calls[-1]["base"] == "benchmark" and suite.calls[-1]["options"] == {
        "pkg.mod:MyEngine": {}}
    assert fl.fault_entries("TOLS", "pkg.mod:MyEngine", "benchmark")[0]["engine"] == "MyEngine"


def test_a_model_the_engine_cannot_represent_is_one_not_run_entry(suite):
    from engines import UnsupportedModel
    suite.result = UnsupportedModel("no torus")
    assert fl.fault_entries("TOLS", "pkg:E", "benchmark") == [{
        "fault": "-", "engine": "E", "model": "benchmark", "detected": None,
        "localized_to": "-", "expected": "-", "correct": None, "observable": False,
        "evidence": "not run on this model: no torus", "verdict": "not run"}]


def test_the_fault_table():
    entries = [{"fault": "f1", "engine": "E", "model": "thesis", "detected": True,
                "localized_to": "M", "expected": "M", "verdict": "localized", "evidence": "ev"},
               {"fault": "f2", "engine": "E", "model": "bench", "detected": False,
                "localized_to": "-", "expected": "Qv", "verdict": "missed", "evidence": "ev2"},
               {"fault": "-", "engine": "F", "detected": None, "localized_to": "-",
                "expected": "-", "verdict": "not run", "evidence": "why"}]
    sec = fl.fault_section(entries)
    assert sec.title == "Fault injection: does the harness catch a broken model?"
    (table,) = _tables(sec)
    assert table.header == ("fault", "engine", "detected", "localized to", "expected", "verdict",
                            "evidence")
    (text,) = _texts(sec)          # what the 'not observable' verdict means
    assert "'not observable': the engine does not provide the terms the fault changes" in text
    assert table.rows == (("f1", "E", "yes", "M", "M", "localized", "ev"),
                          ("f2", "E (bench)", "no", "-", "Qv", "missed", "ev2"),
                          ("-", "F", "-", "-", "-", "not run", "why"))
    assert sec.comparisons == []


def test_the_faults_stage_tasks_and_assemble():
    from comparisons.stages.pool import TaskResult
    from comparisons.stages.stage import Plan
    facts = {"reference": SimpleNamespace(spec="reference", has_terms=True),
             "p": SimpleNamespace(spec="p", label="P", has_terms=True, contacts=("disc",),
                                  costs=SimpleNamespace(faults=4.0)),
             "r": SimpleNamespace(spec="r", label="R", has_terms=False, contacts=("disc",))}
    opts = lambda models: SimpleNamespace(models=models, tolerances="TOLS",   # noqa: E731
                                          options_for=lambda: {"p": {"k": 1}})
    stage = fl.FaultsStage()
    assert (stage.name, stage.section) == ("faults", "faults")
    (t,) = stage.tasks(Plan(opts(()), (), facts))
    assert (t.key, t.func, t.args, t.cost, t.label, t.engine) == (
        ("p", None), fl.fault_entries, ("TOLS", "p", None, (("k", 1),)), 4.0,
        "fault injection on P", "p")
    models = (SimpleNamespace(spec="d.toml", name="D", contact="disc"),
              SimpleNamespace(spec="t.toml", name="T", contact="torus"))
    (t,) = stage.tasks(Plan(opts(models), (), facts))
    assert (t.key, t.func, t.args, t.cost, t.label, t.engine) == (
        ("p", "d.toml"), fl.fault_entries, ("TOLS", "p", "d.toml", (("k", 1),)), 4.0,
        "D: fault injection on P", "p")
    plan = Plan(opts(()), (), facts)
    e1 = {"fault": "f1", "engine": "P", "detected": True, "localized_to": "M", "expected": "M",
          "verdict": "localized", "evidence": "ev"}
    out = stage.assemble(plan, {("p", None): TaskResult(None, [e1], 1.0),
                                ("p", "d.toml"): TaskResult(None, None, 1.0, "boom")})
    assert out.faults == [e1]
    failed, table = out.sections
    assert failed.title == "fault injection on P" and failed.comparisons[0]["passed"] is False
    assert table.title == "Fault injection: does the harness catch a broken model?"
    assert _tables(table)[0].rows[0][0] == "f1"
    out = stage.assemble(plan, {("p", None): TaskResult(None, None, 1.0, "boom")})
    assert out.faults == [] and [s.title for s in out.sections] == ["fault injection on P"]
    e2 = dict(e1, fault="f2")
    out = stage.assemble(plan, {("p", None): TaskResult(None, [e1], 1.0),
                                ("p", "d.toml"): TaskResult(None, [e2], 1.0)})
    assert out.faults == [e1, e2]                  # every task's entries, in one table
    assert [r[0] for r in _tables(out.sections[0])[0].rows] == ["f1", "f2"]


def test_localization_lines_for_the_pairs_whose_terms_failed(monkeypatch):
    from comparisons.judgments import diagnose
    from engines import UnsupportedModel
    localized = []

    from comparisons.judgments.terms import random_states
    seeded = random_states(16, seed=11).q       # the same 16 states every run

    def localize(model, states, engines, tolerances):
        assert np.array_equal(states.q, seeded)
        localized.append((model.name, len(states), engines, tolerances))
        if engines == ["raises"]:
            raise ValueError("no fit")
        return SimpleNamespace(describe=lambda: f"{model.name}: the fork")

    monkeypatch.setattr(diagnose, "localize", localize)

    def setup(built=None, exc=None):
        def build(model):
            if exc is not None:
                raise exc
            return built if built == "raises" else f"{built} on {model.name}"
        return SimpleNamespace(build=build)

    setups = {"A": setup("engine A"), "B": setup("raises"),
              "C": setup(exc=UnsupportedModel("no")), "CA": setup("engine CA"),
              "D": setup(exc=OSError("gone")), "Z": setup("engine Z")}
    row = lambda q, engines, passed, model="thesis": {   # noqa: E731
        "quantity": q, "engines": engines, "passed": passed, "model": model}
    comparisons = [row("mass_matrix", ["reference", "E"], False, "a-model"),   # no setup: skipped
                   row("mass_matrix", ["reference", "A"], False),
                   row("mass_matrix", ["reference", "CA"], False),
                   row("gravity", ["reference", "A"], False),        # the same pair: once
                   row("mass_matrix", ["reference", "A"], False, "mine"),
                   row("torques", ["reference", "B"], False),
                   row("multipliers", ["reference", "C"], False),
                   row("mass_matrix", ["reference", "D"], False),
                   row("mass_matrix", ["reference", "E"], False),     # no setup: skipped
                   row("mass_matrix", ["reference", "F"], True),      # passed: none
                   row("mass_matrix", ["reference", "G"], None),      # reported: none
                   row("trajectory", ["reference", "H"], False),      # not a term
                   row("mass_matrix", ["A"], False),                  # one engine
                   {"quantity": "gravity", "engines": ["reference", "A"], "passed": False},
                   {"quantity": "gravity", "engines": ["reference", "Z"], "passed": False}]
    lines = fl.localization_lines("TOLS", comparisons, setups, {"mine": "benchmark"})
    assert lines == [("mine: reference vs A", "benchmark: the fork"),
                     ("thesis: reference vs A", "thesis: the fork"),
                     ("thesis: reference vs B", "not localized: ValueError: no fit"),
                     ("thesis: reference vs CA", "thesis: the fork"),
                     ("thesis: reference vs Z", "thesis: the fork")]   # no model: the thesis's
    assert [(m, n, e, t) for m, n, e, t in localized] == [
        ("benchmark", 16, ["engine A on benchmark"], "TOLS"),
        ("thesis", 16, ["engine A on thesis"], "TOLS"), ("thesis", 16, ["raises"], "TOLS"),
        ("thesis", 16, ["engine CA on thesis"], "TOLS"), ("thesis", 16, ["engine Z on thesis"],
                                                           "TOLS")]
    assert fl.localization_lines("TOLS", comparisons[9:12], setups) == []
    # a model name that does not load: nothing to localize against
    assert fl.localization_lines("TOLS", [row("gravity", ["reference", "A"], False,
                                              "no-such-model")], setups) == []


# -- the energy drift (comparisons/stages/energy.py) ----------------------------------------

from comparisons.stages import energy as en  # noqa: E402

EN_TOL = {"energy_drift": SimpleNamespace(tolerance=0.01, reason="the reason")}


def _drift(engine, drift, status="success", settings="h = 0.001", t_end=1.0):
    return {"engine": engine, "status": status, "settings": settings, "E0": 12.34567,
            "drift_percent": drift, "drift_J": drift * 0.1234567, "drift_percent_of_T0": 2 * drift,
            "t_end": t_end}


EN_ROWS = [_drift("reference thesis-disc", 1e-9, settings="DOP853 rtol 1e-10, projection"),
           _drift("A", 0.01),                                   # at the tolerance: pass
           _drift("B", 0.0100001),                              # above it: FAIL
           _drift("C", 1e-6, status="failed", t_end=0.456),     # a run that failed: FAIL
           {"engine": "D", "not_run": "not run on this model: no disc"},
           {"engine": "E", "failed": "RuntimeError: boom"}]


def test_the_energy_table_and_verdicts():
    sec = en.energy_section(EN_TOL, (), "thesis-disc", EN_ROWS)
    assert sec.title == "Energy drift, torque-free and drag-free (IFToMM: 100 (Emax - Emin) / E0)"
    (table,) = _tables(sec)
    assert table.header == ("engine", "settings", "E0 [J]", "drift [% of E0]", "verdict", "status")
    assert table.rows == (
        ("reference thesis-disc", "DOP853 rtol 1e-10, projection", "12.346", "1.00e-09", "pass",
         "success at 1.00 s"),
        ("A", "h = 0.001", "12.346", "1.00e-02", "pass", "success at 1.00 s"),
        ("B", "h = 0.001", "12.346", "1.00e-02", "FAIL", "success at 1.00 s"),
        ("C", "h = 0.001", "12.346", "1.00e-06", "FAIL", "failed at 0.46 s"),
        ("D", "-", "-", "-", "not run", "not run on this model: no disc"),
        ("E", "-", "-", "-", "FAIL", "RuntimeError: boom"))
    text = _texts(sec)
    assert text[0].startswith("Free roll from the stability study's leaned and steered state at "
                              "psi_dot = 10 rad/s for 1 s")
    assert text[1] == "Tolerance 0.01 % (`tolerances.toml` [energy_drift]: the reason)"


def test_the_energy_rows():
    sec = en.energy_section(EN_TOL, (), "thesis-disc", EN_ROWS)
    rows = [r.as_dict() for r in sec.comparisons]
    assert [r["engines"] for r in rows] == [["reference thesis-disc"], ["A"], ["B"], ["C"], ["E"]]
    assert [r["passed"] for r in rows] == [True, True, False, False, False]
    for r in rows:
        assert list(r)[:len(COMMON)] == list(COMMON)
        assert (r["quantity"], r["scenario"], r["model"], r["tolerance"]) == (
            "energy drift percent", "free-roll", "thesis-disc (cv = 0)", 0.01)
    assert [r["max_error"] for r in rows] == [1e-9, 0.01, 0.0100001, 1e-6, None]
    assert rows[1]["localized_to"] == "h = 0.001"
    assert rows[1]["note"].startswith("A (h = 0.001; success at 1.00 s): E0 = 12.3457 J")
    assert rows[4] == {"quantity": "energy drift percent", "scenario": "free-roll",
                       "model": "thesis-disc (cv = 0)", "engines": ["E"], "max_error": None,
                       "tolerance": 0.01, "passed": False, "localized_to": "RuntimeError: boom",
                       "note": ""}


def test_the_free_roll_start_on_a_users_bicycle(monkeypatch):
    """v = the middle of the weave (4) and capsize (6 m/s) speeds, psi_dot = v / R_rear (0.3 m
    on the benchmark); 1.2 x the weave speed without a capsize speed; psi_dot = 10 rad/s
    without either, or for a contact the stability study does not linearize."""
    from comparisons.judgments.energy import free_roll_model
    from comparisons.stages import stability
    from reference_model import load_model
    assert en.free_roll_on("thesis-disc", None) == (
        None, "the stability study's leaned and steered state at psi_dot = 10 rad/s")
    free = free_roll_model(load_model("benchmark"))
    asked = []
    for crit, psi_dot, words in (
            ({"weave": 4.0, "capsize": 6.0}, 5.0 / 0.3, "psi_dot = 16.67 rad/s (v = 5.000 m/s, "
                                                        "the middle of its self-stable range)"),
            ({"weave": 4.0}, 4.8 / 0.3, "psi_dot = 16 rad/s (v = 4.800 m/s)"),
            ({}, 10.0, "psi_dot = 10 rad/s (v = 3.000 m/s)")):
        monkeypatch.setattr(stability, "critical", lambda spec, c=crit: asked.append(spec) or c)
        sc, start = en.free_roll_on("bench.toml", free)
        assert start == "lean and steer pi/32 at " + words
        assert math.isclose(sc.dq_ind0[1], psi_dot, rel_tol=1e-12)
        assert sc.q0[3] == sc.q0[6] == np.pi / 32 and sc.model == "benchmark"
    assert asked == ["bench.toml"] * 3
    torus = SimpleNamespace(contact="thesis", name="mine", params=SimpleNamespace(R_rear=0.3))
    sc, start = en.free_roll_on("mine.toml", torus)
    assert asked == ["bench.toml"] * 3 and sc.dq_ind0[1] == 10.0 and "(v = 3.000 m/s)" in start


def test_an_engines_energy_runs_are_its_fixed_step_variants_or_its_first_setup():
    # engines/facts.py: Exudyn's fixed step (h = 1e-3 s), variants tree and redundant
    assert en._runs_of("exudyn", {}) == [("exudyn tree", {"build": "tree", "step": 0.001}),
                                         ("exudyn redundant", {"build": "redundant",
                                                               "step": 0.001})]
    assert en._runs_of("exudyn", {"step": 0.002}) == [("exudyn", {"step": 0.002})]
    assert en._runs_of("pinocchio", {}) == [("pinocchio", {})]


def test_energy_rows_of_an_engine_not_run_failed_and_its_baumgarte_fallback(monkeypatch):
    from engines import EngineError, UnsupportedModel
    calls = []
    behaviour = {"ok": {"projection": "row"},
                 "baum": {"projection": EngineError("no\n  projection"), "baumgarte": "row"},
                 "both": {"projection": EngineError("no"), "baumgarte": RuntimeError("x  y")},
                 "bad": {"projection": RuntimeError("z" * 400)}}

    def drifts(free, sc, engines=()):
        if sc is None:       # the reference's: its default free roll
            calls.append((free.params.cv, None))
            return ["reference rows"]
        calls.append((free.params.cv, sc.constraints, sc.name, [e for e, _ in engines]))
        what = behaviour[engines[0][1]][sc.constraints]
        if isinstance(what, Exception):
            raise what
        return [{"engine": "reference"}, {"engine": engines[0][0], "settings": "h = 1"}]

    def load(spec, model, **opts):
        if opts["mode"] == "unsupported":
            raise UnsupportedModel("no disc")
        return opts["mode"]

    runs = [(f"x {m}", {"mode": m}) for m in ("unsupported", "ok", "baum", "both", "bad")]
    monkeypatch.setattr(en, "energy_drifts", drifts)
    monkeypatch.setattr(en, "load_engine", load)
    monkeypatch.setattr(en, "_runs_of", lambda spec, options: runs)
    assert en.energy_rows(None, {}) == ["reference rows"]
    assert calls == [(0.0, None)]
    rows = en.energy_rows("x", {})
    assert rows == [
        {"engine": "x unsupported", "not_run": "not run on this model: no disc"},
        {"engine": "x ok", "settings": "h = 1"},
        {"engine": "x baum", "settings": "h = 1; Baumgarte a1 = a2 = 10 (it refused "
                                         "projection: no projection)"},
        {"engine": "x both", "failed": "RuntimeError: x y"},
        {"engine": "x bad", "failed": "RuntimeError: " + "z" * 300}]
    assert [c[1] for c in calls[1:]] == ["projection", "projection", "baumgarte", "projection",
                                         "baumgarte", "projection"]
    assert all(c[0] == 0.0 and c[2] == "free-roll-psid10" for c in calls[1:])
    behaviour["long"] = {"projection": EngineError("w" * 200), "baumgarte": "row"}
    monkeypatch.setattr(en, "_runs_of", lambda spec, options: [("x long", {"mode": "long"})])
    (row,) = en.energy_rows("x", {})
    assert row["settings"].endswith("(it refused projection: " + "w" * 120 + ")")


def test_the_energy_stage_tasks_and_assemble():
    from comparisons.stages.pool import TaskResult
    from comparisons.stages.stage import Plan
    facts = {"reference": SimpleNamespace(spec="reference"),
             "p": SimpleNamespace(spec="p", label="P", capabilities={"simulate"},
                                  run_difference=None, fixed_step=None,
                                  costs=SimpleNamespace(run_per_second=0.6)),
             "x": SimpleNamespace(spec="x", label="X", capabilities={"simulate"},
                                  run_difference=None, fixed_step="a fixed step",
                                  costs=SimpleNamespace(run_per_second=0.5)),
             "soft": SimpleNamespace(spec="soft", label="S", capabilities={"simulate"},
                                     run_difference="soft contact"),
             "terms": SimpleNamespace(spec="terms", label="T", capabilities={"mass_matrix"},
                                      run_difference=None)}
    opts = lambda models: SimpleNamespace(models=models, tolerances=EN_TOL,   # noqa: E731
                                          options_for=lambda: {"p": {"k": 1}})
    stage = en.EnergyStage()
    assert (stage.name, stage.section) == ("energy", "energy")
    tasks = stage.tasks(Plan(opts(()), (), facts))
    assert [(t.key, t.func, t.args, t.cost, t.label, t.engine) for t in tasks] == [
        ((None, "thesis-disc"), en.energy_rows, (None, {}, "thesis-disc"), 0.5,
         "energy drift of the reference", None),
        (("p", "thesis-disc"), en.energy_rows, ("p", {"k": 1}, "thesis-disc"), 0.6,
         "energy drift on P", "p"),
        (("x", "thesis-disc"), en.energy_rows, ("x", {}, "thesis-disc"), 1.0,
         "energy drift on X", "x")]
    models = (SimpleNamespace(spec="m.toml", name="M"),)
    assert [(t.key, t.label) for t in stage.tasks(Plan(opts(models), (), facts))][:2] == [
        ((None, "m.toml"), "M: energy drift of the reference"),
        (("p", "m.toml"), "M: energy drift on P")]
    assert stage.tasks(Plan(opts(()), (), {"soft": facts["soft"]})) == []
    plan = Plan(opts(()), (), facts)
    out = stage.assemble(plan, {(None, "thesis-disc"): TaskResult(None, EN_ROWS[:1], 1.0),
                                ("p", "thesis-disc"): TaskResult(None, EN_ROWS[1:2], 1.0),
                                ("x", "thesis-disc"): TaskResult(None, None, 1.0, "boom")})
    sec, failed = out.sections
    assert [r["engines"] for r in sec.comparisons] == [["reference thesis-disc"], ["A"]]
    assert failed.title == "Energy drift on X"
    # the reference's task failed or was not run: no section of the engines' rows alone
    out = stage.assemble(plan, {(None, "thesis-disc"): TaskResult(None, None, 1.0, "boom"),
                                ("p", "thesis-disc"): TaskResult(None, EN_ROWS[1:2], 1.0)})
    assert [s.title for s in out.sections] == ["Energy drift"]
    out = stage.assemble(plan, {(None, "thesis-disc"): TaskResult(None, EN_ROWS[4:5], 1.0)})
    assert out.sections == []
    out = stage.assemble(plan, {(None, "thesis-disc"): TaskResult(None, [], 1.0)})
    assert out.sections == []


# -- the stability claims on thesis-disc (comparisons/stages/soft_contact_claims.py) ---------

from comparisons.stages import soft_contact_claims as scc  # noqa: E402


def _claim(cid, engine, verdict="holds", evidence="ev"):
    return {"claim_id": cid, "claim": f"claim {cid}", "engine": engine, "verdict": verdict,
            "evidence": evidence}


def test_the_disc_evidence_prefix_and_the_stability_scenarios():
    assert scc.MODEL == "thesis-disc"
    assert scc.on_disc("MuJoCo") == ("on thesis-disc (MuJoCo has no thesis fork-axis contact; the "
                                     "claim judged on its run of the same scenario with the disc "
                                     "contact): ")
    assert scc._stability(("check", "stability-psid0", "zigzag", "stability-psid5")) == (
        "stability-psid0", "stability-psid5")


def test_the_claims_judged_on_disc_runs(monkeypatch):
    """The runs of the stability scenarios only, on thesis-disc, by the engine built there;
    only the stability claims kept."""
    import engines.runs
    from comparisons.judgments import claims as jc
    runs, judged, built = [], [], []

    def run_scenario(name, engine, model, sc, kinds):
        runs.append((name, engine, model.name, sc.name, kinds))
        return f"run {sc.name}"

    def judge_claims(r, names, model, stab):
        judged.append((r, names, model.name, stab))
        return [_claim("stability-a", names[0]), _claim("zigzag-b", names[0]),
                _claim("stability-c", names[0])]

    monkeypatch.setattr(engines.runs, "run_scenario", run_scenario)
    monkeypatch.setattr(jc, "judge_claims", judge_claims)
    monkeypatch.setattr(scc, "load_engine",
                        lambda spec, model: built.append((spec, model.name)) or f"{spec} built")
    d = scc.claims_on_disc("pinocchio", ("check", "stability-psid0", "stability-psid5"))
    assert (d.engine, d.label) == ("pinocchio", "Pinocchio")
    assert [c["claim_id"] for c in d.claims] == ["stability-a", "stability-c"]
    assert built == [("pinocchio", "thesis-disc")]
    assert runs == [("pinocchio", "pinocchio built", "thesis-disc", n, ("forward",))
                    for n in ("stability-psid0", "stability-psid5")]
    (r, names, model, stab) = judged[0]
    assert r == {("pinocchio", n): f"run {n}" for n in ("stability-psid0", "stability-psid5")}
    assert (names, model, stab) == (["pinocchio"], "thesis-disc",
                                    ("stability-psid0", "stability-psid5"))
    ref = scc.reference_claims_on_disc(("stability-psid0", "zigzag"))
    assert (ref.engine, ref.label) == ("reference", "reference")
    assert built[-1] == ("reference", "thesis-disc")
    assert runs[-1][:4] == ("reference", "reference built", "thesis-disc", "stability-psid0")
    assert judged[-1][1:] == (["reference"], "thesis-disc", ("stability-psid0",))


def test_the_claims_table_a_column_per_engine_and_the_references():
    ref = scc.DiscClaims("reference", "reference", (_claim("s1", "reference", "holds", "r1"),
                                                    _claim("s2", "reference", "fails", "r2")))
    a = scc.DiscClaims("mujoco", "MuJoCo", (_claim("s2", "mujoco", "holds", "m2"),
                                           _claim("s3", "mujoco", "fails", "m3")))
    b = scc.DiscClaims("drake", "Drake", ())
    sec = scc.claims_section(ref, [a, b])
    assert sec.title == "The thesis's stability claims on thesis-disc: the soft-contact engines"
    (table,) = _tables(sec)
    assert table.header == ("claim", "reference thesis-disc", "mujoco thesis-disc",
                            "drake thesis-disc")
    assert table.rows == (("claim s1", "holds: r1", "-", "-"),
                          ("claim s2", "fails: r2", "holds: m2", "-"),
                          ("claim s3", "-", "fails: m3", "-"))
    assert sec.comparisons == []
    assert _texts(sec)[0].startswith("MuJoCo and Drake cannot run")
    c = scc.DiscClaims("dart", "DART", ())
    assert _texts(scc.claims_section(None, [a, b, c]))[0].startswith("MuJoCo, Drake and DART "
                                                                    "cannot")
    alone = scc.claims_section(None, [a])
    assert _texts(alone)[0].startswith("MuJoCo cannot run")
    assert _tables(alone)[0].header == ("claim", "mujoco thesis-disc")
    assert _texts(scc.claims_section(ref, []))[0].startswith("- cannot run")


def test_merge_claims_replaces_only_that_engines_judged_entries():
    claims = [_claim("s1", "mujoco", "not assessed", "-"), _claim("s2", "mujoco", "not assessed"),
              _claim("s1", "drake", "not assessed", "-"), _claim("s1", "reference", "holds")]
    disc = scc.DiscClaims("mujoco", "MuJoCo", (_claim("s1", "mujoco", "fails", "lean grows"),))
    merged = scc.merge_claims(claims, disc)
    assert merged == [dict(claims[0], verdict="fails", evidence=scc.on_disc("MuJoCo") +
                           "lean grows"), claims[1], claims[2], claims[3]]
    assert claims[0]["verdict"] == "not assessed"          # the input untouched


# -- engine setups and runs (comparisons/stages/runs.py) ------------------------------------

from comparisons.stages import runs as rn  # noqa: E402


def _facts(name="e", run_setups=None, has_inverse_runs=False, capabilities=("simulate",),
           costs=None):
    from engines.facts import Costs, RunSetup
    return SimpleNamespace(name=name, run_setups=run_setups or (RunSetup(),),
                           has_inverse_runs=has_inverse_runs, capabilities=set(capabilities),
                           costs=costs or Costs())


def test_an_engine_setups_defaults_and_build(monkeypatch):
    import engines
    s = rn.EngineSetup("lab", "eng")
    assert (s.options, s.kinds, s.settings) == ((), ("inverse", "forward"), "")
    monkeypatch.setattr(engines, "load_engine", lambda spec, model, **o: (spec, model, o))
    assert rn.EngineSetup("l", "eng", (("a", 1), ("b", 2))).build("M") == ("eng", "M",
                                                                           {"a": 1, "b": 2})
    assert rn.label_of("pinocchio") == "pinocchio"
    assert rn.label_of("pkg.mod:Engine") == "Engine" and rn.label_of("a:b.py:C") == "C"


def test_the_kinds_a_setup_runs():
    assert rn._kinds(_facts(), ("forward",)) == ("forward",)
    assert rn._kinds(_facts(), ["inverse"]) == ("inverse",)
    assert rn._kinds(_facts("reference", capabilities=()), None) == ("inverse", "forward")
    assert rn._kinds(_facts(has_inverse_runs=True), None) == ("inverse", "forward")
    assert rn._kinds(_facts(has_inverse_runs=True, capabilities=()), None) == ("inverse",)
    assert rn._kinds(_facts(), None) == ("forward",)
    assert rn._kinds(_facts(capabilities=("mass_matrix",)), None) == ()


def test_the_declared_setups_or_one_from_the_command_lines_options(monkeypatch):
    import engines.facts
    from engines.facts import RunSetup
    table = {"one": _facts("one", (RunSetup(kinds=("forward",), settings="its way"),)),
             "two": _facts("two", (RunSetup("a", (("x", 1),), settings="A"),
                                   RunSetup("b", (("x", 2),), ("inverse",)))),
             "pkg:Plain": _facts("plain", has_inverse_runs=True)}
    monkeypatch.setattr(engines.facts, "engine_facts", lambda spec: table[spec])
    assert rn.engine_setups("one") == [rn.EngineSetup("one", "one", (), ("forward",), "its way")]
    assert rn.engine_setups("two") == [
        rn.EngineSetup("two-a", "two", (("x", 1),), ("forward",), "A"),
        rn.EngineSetup("two-b", "two", (("x", 2),), ("inverse",), "two with its own defaults")]
    assert rn.engine_setups("pkg:Plain") == [
        rn.EngineSetup("Plain", "pkg:Plain", (), ("inverse", "forward"),
                       "pkg:Plain with its own defaults")]
    # command-line options: one setup, options sorted, the single declared setup's kinds
    assert rn.engine_setups("one", {"z": 1, "a": "b"}) == [
        rn.EngineSetup("one", "one", (("a", "b"), ("z", 1)), ("forward",),
                       "one with a = b, z = 1")]
    # several declared setups: the kinds from the capabilities
    assert rn.engine_setups("two", {"x": 3})[0].kinds == ("forward",)
    assert rn.engine_setups("one", {}) == rn.engine_setups("one")
    assert rn.setups_for(["two", "one"], {"one": {"k": 1}}) == [
        *rn.engine_setups("two"), *rn.engine_setups("one", {"k": 1})]
    assert rn.setups_for(["one"]) == rn.engine_setups("one")
    assert rn.setup_of("two") == rn.engine_setups("two")[0]
    assert rn.setup_of("one", {"k": 1}).options == (("k", 1),)


def test_a_runs_cost_from_the_declared_costs(monkeypatch):
    import engines.facts
    from engines.facts import Costs
    costs = Costs(run_per_second=2.0, short_run=0.3, scenario_runs=(("replay", 8.0),))
    monkeypatch.setattr(engines.facts, "engine_facts", lambda spec: _facts(costs=costs))
    s = rn.EngineSetup("l", "e")
    assert rn.cost(s, "replay") == 8.0 and rn.cost(s, "replay-on-mine") == 8.0
    assert rn.cost(s, "check") == rn.cost(s, "zigzag-on-mine") == 0.3
    assert rn.cost(s, "check-forward") == 2.0 * 6.3        # 6.3 s of simulated motion
    assert rn.cost(s, "stability-psid0") == 2.0 * 1.2


class _RunEnv(SimpleNamespace):
    pass


@pytest.fixture
def run_env(monkeypatch):
    """`run_one` with `run_scenario`, the engine loader and the registry replaced."""
    import engines
    import engines.registry
    from engines import CapabilityError, UnsupportedModel
    env = _RunEnv(calls=[], built=[], refuse=None, ctor=None)

    class Cls:
        contacts = ("disc", "thesis")

        def __init__(self, model, **options):
            if env.ctor is not None:
                raise env.ctor

    def load(spec, model, **options):
        env.built.append((spec, model.name, options))
        if env.refuse is not None:
            raise env.refuse
        return f"{spec} engine"

    monkeypatch.setattr(rn, "run_scenario", lambda label, eng, model, sc, kinds: env.calls.append(
        (label, eng, model.name, sc.name, sc.model, kinds)) or "a run")
    monkeypatch.setattr(engines, "load_engine", load)
    monkeypatch.setattr(engines.registry, "resolve", lambda spec: (Cls,))
    env.Cls, env.UnsupportedModel, env.CapabilityError = Cls, UnsupportedModel, CapabilityError
    return env


def test_run_one_builds_the_engine_on_the_runs_model(run_env):
    s = rn.EngineSetup("lab", "eng", (("k", 1),), ("forward",))
    assert rn.run_one(s, "check-forward") == "a run"
    assert run_env.built == [("eng", "thesis", {"k": 1})]
    assert run_env.calls == [("lab", "eng engine", "thesis", "check-forward", "thesis",
                              ("forward",))]
    rn.run_one(s, "check-forward", "thesis-disc")           # another model: the scenario's too
    assert run_env.calls[-1][2:5] == ("thesis-disc", "check-forward", "thesis-disc")
    rn.run_one(s, "check-forward", "thesis")
    assert run_env.calls[-1][2:5] == ("thesis", "check-forward", "thesis")
    from reference_model.scenarios import get_scenario
    rn.run_one(s, get_scenario("check-forward"))             # a Scenario as well as a name
    assert run_env.calls[-1][3] == "check-forward"


def test_a_kind_the_setup_does_not_run_and_the_references_inverse_build_nothing(run_env):
    rn.run_one(rn.EngineSetup("lab", "eng", (), ("forward",)), "check")      # inverse
    assert run_env.built == [] and run_env.calls[-1][:2] == ("lab", None)
    rn.run_one(rn.EngineSetup("reference", "reference"), "check")
    assert run_env.built == [] and run_env.calls[-1][:2] == ("reference", None)
    rn.run_one(rn.EngineSetup("reference", "reference"), "check-forward")
    assert run_env.built == [("reference", "thesis", {})]
    rn.run_one(rn.EngineSetup("other", "eng"), "check")
    assert run_env.built[-1] == ("eng", "thesis", {})


def test_a_model_the_engine_cannot_represent_is_a_not_run_run(run_env):
    from engines.runs import Run
    s = rn.EngineSetup("lab", "eng", (("k", 1),), ("forward",))
    run_env.refuse = run_env.UnsupportedModel("its bodies break A + B >= C")
    r = rn.run_one(s, "check-forward")
    assert isinstance(r, Run) and r.t.size == 0
    assert (r.engine, r.scenario, r.model, r.kind, r.status, r.message, r.seconds) == (
        "lab", "check-forward", "thesis", "forward", "not run",
        "not run on this model: its bodies break A + B >= C", 0.0)
    run_env.Cls.contacts = ("disc",)            # the thesis's contact is not the engine's
    run_env.ctor = run_env.CapabilityError("no fork-axis\n   contact")
    assert rn.run_one(s, "check-forward").message == "CapabilityError: no fork-axis contact"
    run_env.ctor = RuntimeError("anything else")
    assert rn.run_one(s, "check-forward").message == (
        "lab models the front contact(s) disc, not 'thesis' of model 'thesis'")
    run_env.ctor = None                          # its constructor accepts it: the plain statement
    assert rn.run_one(s, "check-forward").message == (
        "lab models the front contact(s) disc, not 'thesis' of model 'thesis'")
    assert run_env.calls == []


# -- the fixed-step integrators' study (comparisons/stages/fixed_step.py) -------------------

from comparisons.stages import fixed_step as fx  # noqa: E402
from engines.facts import FixedStep  # noqa: E402

FIXED = FixedStep(option="step", step=2e-3, order=2.0,
                  variants=(("tree", (("build", "tree"),)), ("red", (("build", "red"),))),
                  thesis_variant="tree")
FX_FACTS = SimpleNamespace(name="ex", label="Ex", spec="ex.spec", fixed_step=FIXED)


def test_the_fixed_step_studys_constants_and_steps():
    assert fx.CONVERGENCE_HORIZON == 0.5 and fx.DIVERGED == 1e-6
    assert fx.FORWARD == ("stability-psid0", "stability-psid1", "stability-psid5",
                          "stability-psid10", "replay")
    assert fx.QUICK_FORWARD == ("stability-psid5",)
    assert fx.TRAJECTORY_COSTS == {"replay": 2.4, "stability-psid10": 2.0}
    # 1e-3 s: 5e-3 ... 6.25e-4 s (halvings over 8x); --quick: each twice that
    assert fx.convergence_steps(False) == (5e-3, 2.5e-3, 1.25e-3, 6.25e-4)
    assert fx.convergence_steps(True) == (1e-2, 5e-3, 2.5e-3, 1.25e-3)
    np.testing.assert_allclose(fx.convergence_steps(False, FIXED), (1e-2, 5e-3, 2.5e-3, 1.25e-3),
                               rtol=1e-15)          # a declared 2e-3 s step: all doubled


def test_the_first_coordinate_past_the_threshold():
    t = np.array([0.0, 0.5, 1.0])
    err = {c: np.zeros(3) for c in COORDINATES_}
    err["t"] = t
    err["theta"] = np.array([0.0, 2e-6, 5e-6])
    err["xc"] = np.array([0.0, 1e-6, 9e-6])
    err["max"] = np.maximum(err["theta"], err["xc"])
    assert fx.first_past(err) == "theta at 0.50 s"
    assert fx.first_past(err, 3e-6) == "xc at 1.00 s"
    assert fx.first_past(err, 1e-5) == ""
    err["max"] = np.array([0.0, 1e-6, 1e-6])           # at the threshold: not past it
    assert fx.first_past(err) == ""


class _Sim:
    """A built engine recording its runs: (its spec, model, options, scenario, t_end)."""

    def __init__(self, log, spec, model, options):
        self.log, self.key = log, (spec, model.name, options)

    def simulate(self, sc, t_end=None):
        self.log.append((*self.key, sc.name, t_end, sc.grid))
        return SimpleNamespace(t_end=1.25, status="completed", key=len(self.log))


@pytest.fixture
def fx_env(monkeypatch):
    import engines.facts
    env = SimpleNamespace(sims=[], studies=[], verdicts={})
    monkeypatch.setattr(engines.facts, "engine_facts", lambda spec: {"ex.spec": FX_FACTS}[spec])
    monkeypatch.setattr(fx, "load_engine", lambda spec, model, **o: _Sim(env.sims, spec, model, o))
    env.factories = []

    def study(ref_model, factory, sc, steps, horizon, runs):
        env.studies.append((ref_model.name, sc.name, steps, horizon, [r.key for r in runs]))
        env.factories.append(factory(0.125).key)     # what the study would build at a step
        verdict = env.verdicts.get(ref_model.name, "converges")
        return SimpleNamespace(verdict=verdict, errors=(4e-4, 1e-4), order=2.004,
                               difference=1.5e-3, steps=steps, verdict_reason="why " + verdict)

    monkeypatch.setattr(fx, "convergence_study", study)
    return env


def test_the_convergence_study_on_the_thesis_bicycle(fx_env):
    fx_env.verdicts = {"thesis": "model difference"}
    sec = fx.convergence_section("ex.spec", False)
    assert sec.title == "Ex convergence: integrator error or model difference?"
    steps = fx.convergence_steps(False, FIXED)
    # each (variant, engine model) runs once at the four steps, however many references judge it
    runs = {(o["build"], m) for _, m, o, *_ in fx_env.sims}
    assert runs == {("tree", "thesis-disc"), ("red", "thesis-disc"), ("tree", "thesis")}
    assert len(fx_env.sims) == 3 * 4
    assert [o["step"] for _, _, o, *_ in fx_env.sims[:4]] == list(steps)
    assert all(s[0] == "ex.spec" and s[3] == "stability-psid10" and s[4] == 0.5
               for s in fx_env.sims)
    # the study's own factory builds the same engine at the step it is given
    assert fx_env.factories == [("ex.spec", "thesis-disc", {"build": "tree", "step": 0.125}),
                                ("ex.spec", "thesis-disc", {"build": "red", "step": 0.125}),
                                ("ex.spec", "thesis-disc", {"build": "tree", "step": 0.125}),
                                ("ex.spec", "thesis", {"build": "tree", "step": 0.125})]
    assert [(r, s, st, h) for r, s, st, h, _ in fx_env.studies] == [
        ("thesis-disc", "stability-psid10", steps, 0.5), ("thesis-disc", "stability-psid10", steps, 0.5),
        ("thesis", "stability-psid10", steps, 0.5), ("thesis", "stability-psid10", steps, 0.5)]
    assert fx_env.studies[2][4] == fx_env.studies[0][4]        # the disc tree's runs, reused
    (table,) = _tables(sec)
    assert table.header == fx.CONVERGENCE_HEADER == (
        "engine", "reference", "errors by step [rad, m]", "fitted order", "verdict", "expected",
        "as expected")
    from reference_model.scenarios import SCENARIOS
    (mismatch,) = SCENARIOS["stability-psid10"].expected_differences
    assert table.rows == (
        ("ex tree, disc contact", "thesis-disc", "4.00e-04, 1.00e-04", "2.00", "converges",
         "converges", "yes"),
        ("ex red, disc contact", "thesis-disc", "4.00e-04, 1.00e-04", "2.00", "converges",
         "converges", "yes"),
        ("ex tree, disc contact", "thesis", "4.00e-04, 1.00e-04", "2.00", "model difference",
         f"model difference (declared model difference: {mismatch.reason})", "yes"),
        ("ex tree, thesis contact", "thesis", "4.00e-04, 1.00e-04", "2.00", "model difference",
         "converges", "NO"))
    assert "0.5 s, at h = 0.01, 0.005, 0.0025, 0.00125 s" in table.note
    rows = [r.as_dict() for r in sec.comparisons]
    assert [r["passed"] for r in rows] == [True, True, True, False]
    assert rows[0] == {"quantity": "convergence order", "scenario": "stability-psid10",
                       "model": "thesis-disc", "engines": ["reference", "ex-tree-disc"],
                       "max_error": 1.5e-3, "tolerance": None, "passed": True,
                       "localized_to": "order 2.00: converges", "note": "", "order": 2.004,
                       "steps": list(steps), "errors": [4e-4, 1e-4], "verdict": "converges",
                       "expected": "converges", "reason": "why converges"}
    assert rows[2]["localized_to"] == ("order 2.00: model difference (expected: declared model "
                                       "difference)")
    assert rows[3]["engines"] == ["reference", "ex-tree-thesis"]
    (fig,) = sec.figures
    assert (fig.name, fig.kind) == ("ex_convergence.png", "convergence")
    assert fig.data["horizon"] == 0.5 and fig.data["title"] == ("Ex against the reference, "
                                                                "stability-psid10")
    assert [c["label"] for c in fig.data["curves"]] == [
        "ex tree (disc) vs reference thesis-disc: order 2.00",
        "ex red (disc) vs reference thesis-disc: order 2.00",
        "ex tree (disc) vs reference thesis: order 2.00",
        "ex tree (thesis) vs reference thesis: order 2.00"]
    assert fig.data["curves"][0]["steps"] == list(steps)
    assert fig.data["curves"][0]["errors"] == [4e-4, 1e-4]
    assert "twice the full run's" not in _texts(sec)[0]


def test_the_quick_convergence_study_leaves_out_the_thesis_contacts_own_run(fx_env):
    fx_env.verdicts = {"thesis": "model difference"}
    sec = fx.convergence_section("ex.spec", True)
    assert [r[:2] for r in _tables(sec)[0].rows] == [("ex tree, disc contact", "thesis-disc"),
                                                     ("ex red, disc contact", "thesis-disc"),
                                                     ("ex tree, disc contact", "thesis")]
    assert [o["step"] for _, _, o, *_ in fx_env.sims[:4]] == list(fx.convergence_steps(True, FIXED))
    assert "twice the full run's" in _texts(sec)[0]


def test_the_convergence_study_on_a_users_bicycle(fx_env):
    sec = fx.convergence_section("ex.spec", False, "benchmark")
    assert sec.title == "Ex convergence on benchmark: integrator error or model difference?"
    assert {(o["build"], m, name) for _, m, o, name, *_ in fx_env.sims} == {
        ("tree", "benchmark", "stability-psid10-on-benchmark")}
    assert [r[0] for r in fx_env.studies] == ["benchmark"]
    assert _tables(sec)[0].rows == (("ex tree, disc contact", "benchmark", "4.00e-04, 1.00e-04",
                                     "2.00", "converges", "converges", "yes"),)
    assert sec.figures[0].name == "ex_convergence_benchmark.png"
    assert "(h = 0.01, 0.005, 0.0025, 0.00125 s)" in _texts(sec)[0]


def test_a_trajectory_part_up_to_the_horizon(monkeypatch, fx_env):
    from reference_model.scenarios import SCENARIOS
    got = {}
    ref = SimpleNamespace(settings={"initial_correction": "theta_dot corrected by 1e-12"})
    hor = SimpleNamespace(t=1.234, limited_by="twin runs", reason="the twin separates")

    def errors(r, traj, coords, horizon):
        got.setdefault("errors", []).append((r, coords, horizon))
        t = np.array([0.0, 0.6, 1.2])
        e = {c: np.zeros(3) for c in COORDINATES_}
        e.update(t=t, theta=np.array([0.0, 3e-6, 1e-7]), xc=np.array([0.0, 1e-7, 2e-7]))
        if traj.key > 1:
            e["theta"] = e["theta"] * 0.1       # the second variant stays below 1e-6
        e["max"] = np.maximum(e["theta"], e["xc"])
        return e

    monkeypatch.setattr(fx, "reference_run", lambda model, sc: got.update(ref=(model.name, sc.name)) or ref)
    monkeypatch.setattr(fx, "reference_horizon", lambda model, sc, reference: got.update(
        hor=(model.name, sc.name, reference)) or hor)
    monkeypatch.setattr(fx, "error_vs_time", errors)
    part = fx.trajectory_part("ex.spec", "stability-psid0")
    assert got["ref"] == ("thesis-disc", "stability-psid0")
    assert got["hor"] == ("thesis-disc", "stability-psid0", ref)
    start, step, n = SCENARIOS["stability-psid0"].grid
    cut = int(np.ceil((1.234 - start) / step)) + 3             # to the horizon and two samples
    assert cut < n
    assert [(s, m, o, name, g) for s, m, o, name, _, g in fx_env.sims] == [
        ("ex.spec", "thesis-disc", {"build": "tree", "step": 2e-3}, "stability-psid0",
         (start, step, cut)),
        ("ex.spec", "thesis-disc", {"build": "red", "step": 2e-3}, "stability-psid0",
         (start, step, cut))]
    assert got["errors"][0][0] is ref and got["errors"][0][1:] == (COORDINATES_, 1.234)
    assert part.rows == [
        ("stability-psid0", "1.23", "twin runs", "ex-tree", "3.00e-06", "theta at 0.60 s",
         "1.250 s (completed, run to the horizon)"),
        ("stability-psid0", "1.23", "twin runs", "ex-red", "3.00e-07", "none (all below 1e-06)",
         "1.250 s (completed, run to the horizon)")]
    rows = [r.as_dict() for r in part.comparisons]
    assert rows[0] == {"quantity": "trajectory (disc builds)", "scenario": "stability-psid0",
                       "model": "thesis-disc", "engines": ["reference", "ex-tree"],
                       "max_error": 3e-6, "tolerance": None, "passed": None,
                       "localized_to": "theta at 0.60 s",
                       "note": "reported, not judged: the convergence study judges Ex's "
                               "trajectories", "horizon": 1.234,
                       "horizon_reason": "the twin separates"}
    assert rows[1]["localized_to"] == "-"
    assert (part.figure.name, part.figure.kind) == ("ex_error_stability-psid0.png", "error_vs_time")
    d = part.figure.data
    assert set(d) == {"curves", "horizon", "threshold", "engine_label", "title"}
    assert (d["horizon"], d["threshold"], d["engine_label"]) == (1.234, 1e-6, "Ex")
    assert d["title"] == "stability-psid0: Ex against the reference up to the horizon (1.23 s)"
    assert list(d["curves"]) == ["ex-tree", "ex-red"]
    assert set(d["curves"]["ex-tree"]) == {"t", "theta", "xc"}
    np.testing.assert_array_equal(d["curves"]["ex-tree"]["theta"], [0.0, 3e-6, 1e-7])
    np.testing.assert_array_equal(d["curves"]["ex-tree"]["xc"], [0.0, 1e-7, 2e-7])
    np.testing.assert_array_equal(d["curves"]["ex-tree"]["t"], [0.0, 0.6, 1.2])
    assert part.correction == "stability-psid0: theta_dot corrected by 1e-12"
    # a horizon past the scenario's end: the whole grid, no 'run to the horizon'
    hor.t = 1e3
    long = fx.trajectory_part("ex.spec", "stability-psid0")
    assert fx_env.sims[-1][5] == (start, step, n)
    assert long.rows[0][6] == "1.250 s (completed)"
    # a grid that starts later: the horizon counted from its start (0.5 s: 74 steps of 0.01 s
    # to 1.234 s, and two samples)
    import dataclasses
    hor.t = 1.234
    late = dataclasses.replace(SCENARIOS["stability-psid0"], name="late", grid=(0.5, 0.01, 500))
    monkeypatch.setitem(fx.SCENARIOS, "late", late)
    fx.trajectory_part("ex.spec", "late")
    assert fx_env.sims[-1][5] == (0.5, 0.01, 74 + 3)


def test_the_trajectory_section_merges_the_parts():
    fig_a, fig_b = (fx.Figure(f"{n}.png", "error_vs_time", {}) for n in "ab")
    parts = [fx.TrajectoryPart([("s1", "row")], [{"c": 1}], fig_a, "s1: none"),
             fx.TrajectoryPart([("s2", "row"), ("s2", "row2")], [{"c": 2}], fig_b, "s2: 1e-9")]
    sec = fx.merge_trajectories(parts, FX_FACTS)
    assert sec.title == "Reference vs Ex, forward trajectories (disc contact)"
    (table,) = _tables(sec)
    assert table.header == ("scenario", "horizon [s]", "horizon set by", "variant",
                            "max error, 8 coordinates, to the horizon [rad, m]",
                            "first coordinate past 1e-06", "end (status)")
    assert table.rows == (("s1", "row"), ("s2", "row"), ("s2", "row2"))
    assert sec.comparisons == [{"c": 1}, {"c": 2}]
    assert sec.figures == [fig_a, fig_b]
    first, last = _texts(sec)
    assert first.startswith("Every declared variant of Ex (tree, red) at step = 0.002 s against")
    assert last.endswith("every variant: s1: none; s2: 1e-9.")


def test_the_fixed_step_stage_tasks_and_assemble():
    from comparisons.stages.pool import TaskResult
    from comparisons.stages.stage import Plan
    facts = {"reference": SimpleNamespace(spec="reference", fixed_step=None, label="ref"),
             "ex.spec": FX_FACTS,
             "p": SimpleNamespace(spec="p", label="P", fixed_step=None)}
    opts = lambda models, quick: SimpleNamespace(models=models, quick=quick)   # noqa: E731
    stage = fx.FixedStepStage()
    assert (stage.name, stage.section) == ("fixed-step", "fixed-step")
    tasks = stage.tasks(Plan(opts((), False), (), facts))
    assert [(t.key, t.func, t.args, t.cost, t.label, t.engine) for t in tasks] == [
        *((("trajectory", "ex.spec", n), fx.trajectory_part, ("ex.spec", n),
           {"replay": 2.4, "stability-psid10": 2.0}.get(n, 0.5) * 2, f"Ex trajectories: {n}",
           "ex.spec") for n in fx.FORWARD),
        (("convergence", "ex.spec", None), fx.convergence_section, ("ex.spec", False), 5.0,
         "Ex convergence order", "ex.spec")]
    tasks = stage.tasks(Plan(opts((), True), (), facts))
    assert [(t.key, t.args, t.cost) for t in tasks] == [
        (("trajectory", "ex.spec", "stability-psid5"), ("ex.spec", "stability-psid5"), 1.0),
        (("convergence", "ex.spec", None), ("ex.spec", True), 3.0)]
    models = (SimpleNamespace(spec="m.toml", name="M"),)
    (t,) = stage.tasks(Plan(opts(models, False), (), facts))
    assert (t.key, t.func, t.args, t.cost, t.label, t.engine) == (
        ("convergence", "ex.spec", "m.toml"), fx.convergence_section, ("ex.spec", False, "m.toml"),
        3.0, "M: Ex convergence order", "ex.spec")
    part = fx.TrajectoryPart([("s", "r")], [], fx.Figure("a.png", "k", {}), "s: -")
    conv = fx.Section("conv")
    plan = Plan(opts((), False), (), facts)
    out = stage.assemble(plan, {
        ("convergence", "ex.spec", None): TaskResult(None, conv, 1.0),
        ("trajectory", "ex.spec", "s1"): TaskResult(None, part, 1.0),
        ("trajectory", "ex.spec", "s2"): TaskResult(None, None, 1.0, "boom"),
        ("trajectory", "ex.spec", "s3"): TaskResult(None, part, 1.0),
        ("convergence", "ex.spec", "m"): TaskResult(None, None, 1.0, "bang")})
    merged, failed, c1, c2 = out.sections
    assert merged.title == "Reference vs Ex, forward trajectories (disc contact)"
    assert _tables(merged)[0].rows == (("s", "r"), ("s", "r"))
    assert failed.title == "Ex trajectories: s2"
    assert c1 is conv and c2.title == "Ex convergence"
    assert c2.comparisons[0]["localized_to"] == "bang"
    out = stage.assemble(plan, {("trajectory", "ex.spec", "s2"): TaskResult(None, None, 1.0, "x")})
    assert [s.title for s in out.sections] == ["Ex trajectories: s2"]


# -- cases: scenarios on models (comparisons/stages/cases.py) -------------------------------

from comparisons.stages import cases as cs  # noqa: E402


def test_a_model_spec_of_a_named_model_and_of_a_file(monkeypatch, tmp_path):
    from reference_model import NAMED_MODELS, load_model
    m = cs.model_spec("benchmark")
    assert m == cs.ModelSpec("benchmark", "benchmark", str(NAMED_MODELS["benchmark"][0]), "disc",
                             0.0, ())
    assert type(m.cv) is float
    assert cs.model_spec("thesis").cv == 0.8 and cs.model_spec("thesis").contact == "thesis"
    folder = NAMED_MODELS["benchmark"][0].parent
    monkeypatch.chdir(folder)
    f = cs.model_spec("benchmark.toml")          # relative: made absolute for the workers
    assert f.spec == str(folder / "benchmark.toml") and f.source == "benchmark.toml"
    assert f.name == load_model("benchmark.toml").name
    assert cs.ModelSpec("s", "n", "src", "disc", 0.0, ("w1",)).as_dict() == {
        "name": "n", "source": "src", "contact": "disc", "warnings": ["w1"]}


def test_a_file_name_safe_slug():
    assert cs.slug("My bike (v2)") == "My-bike-v2"
    assert cs.slug("a.b_c-D9") == "a.b_c-D9"
    assert cs.slug("--x/y--") == "x-y"
    assert cs.slug(" ") == cs.slug("") == "model"


def test_which_scenarios_apply_to_another_bicycle_and_how_they_are_bound():
    from reference_model.scenarios import get_scenario
    assert cs.not_applicable(get_scenario("benchmark-v4")).startswith(
        "written for the benchmark bicycle's critical speeds")
    assert cs.not_applicable(get_scenario("check")) is None
    m = cs.ModelSpec("/abs/my bike.toml", "my bike", "my bike.toml", "disc", 0.0)
    psid10 = get_scenario("stability-psid10")
    assert psid10.expected_differences                   # the premise: it declares one
    bound = cs.on_model(psid10, m)
    assert (bound.name, bound.model, bound.expected_differences) == (
        "stability-psid10-on-my-bike", "/abs/my bike.toml", ())
    assert bound.q0 == psid10.q0 and bound.grid == psid10.grid
    kept = cs.on_model(psid10, m, keep_name=True)
    assert (kept.name, kept.model, kept.expected_differences) == (
        "stability-psid10", "/abs/my bike.toml", psid10.expected_differences)


def test_the_cases_without_models_are_the_built_ins():
    from reference_model.scenarios import get_scenario
    cases, skipped = cs.build_cases(["check", "benchmark-v4"], (), ())
    assert [(c.name, c.scenario, c.model, c.origin) for c in cases] == [
        ("check", get_scenario("check"), "thesis", "built-in"),
        ("benchmark-v4", get_scenario("benchmark-v4"), "benchmark", "built-in")]
    assert skipped == []


def test_the_cases_on_models():
    from reference_model.scenarios import get_scenario
    mine = cs.ModelSpec("/abs/mine.toml", "Mine", "mine.toml", "disc", 0.0)
    bench = cs.model_spec("benchmark")
    cases, skipped = cs.build_cases(["check", "benchmark-v4"], (mine, bench), ())
    assert [(c.name, c.model, c.origin) for c in cases] == [
        ("check-on-Mine", "/abs/mine.toml", "built-in"),
        ("check-on-benchmark", "benchmark", "built-in"),
        ("benchmark-v4", "benchmark", "built-in")]           # its own model: as built in
    assert cases[2].scenario == get_scenario("benchmark-v4")
    assert cases[0].scenario.model == "/abs/mine.toml"
    assert skipped == [cs.NotRun("benchmark-v4", "Mine",
                                 cs.not_applicable(get_scenario("benchmark-v4")))]


def test_a_scenario_file_runs_on_its_own_model_and_on_every_other(tmp_path):
    from reference_model.scenario_files import BUILTIN_DIR
    text = (BUILTIN_DIR / "check.toml").read_text().replace('name = "check"', 'name = "mine"')
    f = tmp_path / "mine.toml"
    f.write_text(text)
    bench = cs.model_spec("benchmark")
    thesis = cs.model_spec("thesis")
    cases, skipped = cs.build_cases([], (bench, thesis), (str(f),))
    assert [(c.name, c.model, c.origin) for c in cases] == [
        ("mine", "thesis", str(f)), ("mine-on-benchmark", "benchmark", str(f))]
    assert skipped == []
    with pytest.raises(ValueError, match=r"two scenarios named 'mine' \(.*mine.toml, .*mine.toml\)"):
        cs.build_cases([], (), (str(f), str(f)))
    clash = tmp_path / "check.toml"
    clash.write_text((BUILTIN_DIR / "check.toml").read_text())
    with pytest.raises(ValueError, match=r"two scenarios named 'check' \(built-in, "):
        cs.build_cases(["check"], (), (str(clash),))


# -- the scenario stages (comparisons/stages/scenarios.py) ----------------------------------

from comparisons.stages import scenarios as sn  # noqa: E402
from engines.runs import Run  # noqa: E402


def _run(engine, scenario, kind="forward", status="completed", n=5, message="", T=None,
         trajectory=None, model="thesis"):
    t = np.linspace(0.0, 0.04, n)
    return Run(engine, scenario, model, kind, status, message, 0.1, t=t, q=np.zeros((n, 8)),
               dq=np.zeros((n, 8)), T=T, trajectory=trajectory)


def test_the_scenario_stages_constants_and_horizon(monkeypatch):
    from reference_model.scenarios import get_scenario
    assert (sn.CHECK_RELATIVE, sn.M_STATES) == (1e-12, 100)
    seen = []
    monkeypatch.setattr(sn, "reference_horizon",
                        lambda model, sc: seen.append((model.name, sc.name)) or "hor")
    assert sn.horizon_of("check-forward") == "hor"
    assert sn.horizon_of(get_scenario("benchmark-v4")) == "hor"
    assert seen == [("thesis", "check-forward"), ("benchmark", "benchmark-v4")]


def test_the_check_scenarios_analytic_torques():
    """Mped = cv (R psi_dot)^2 R at psi_dot = 5 rad/s (the check's rolling), the others zero:
    a deviation of 1e-13 N m passes the 1e-12-relative bound, one of 1e-10 N m fails it."""
    from reference_model import load_model
    model = load_model("thesis")
    p = model.params
    mped = p.cv * (5.0 * p.R_rear) ** 2 * p.R_rear
    T = np.tile([0.0, mped, 0.0], (7, 1))
    T[3, 1] += 1e-13
    got = sn.analytic_check(_run("reference", "check", "inverse", n=7, T=T), model)
    assert set(got) == {"check", "value", "tolerance", "passed", "evidence"}
    assert got["check"] == "check: Mped = cv (R psi_dot)^2 R, Mdir = Mvue = 0"
    assert math.isclose(got["value"], 1e-13, rel_tol=1e-2)   # the sum's round-off at ~1 N m
    assert math.isclose(got["tolerance"], 1e-12 * mped, rel_tol=1e-12)
    assert got["passed"] is True
    assert got["evidence"] == (f"Mped = {mped:.12g} N m expected; max deviation "
                               f"{got['value']:.2e} N m over 7 samples")
    T[5, 0] = 1e-10                                            # Mdir not zero
    bad = sn.analytic_check(_run("reference", "check", "inverse", n=7, T=T), model)
    assert bad["passed"] is False and math.isclose(bad["value"], 1e-10, rel_tol=1e-12)


def test_the_reference_rows_checks_and_corrections():
    from reference_model import load_model
    model = load_model("thesis")
    p = model.params
    mped = p.cv * (5.0 * p.R_rear) ** 2 * p.R_rear
    q = np.zeros((5, 8))
    C = model.constraint_residual(q, np.zeros((5, 8)))     # the reference's own measure of it
    runs = {("reference", "check"): _run("reference", "check", "inverse",
                                         T=np.tile([0.0, mped, 0.0], (5, 1))),
            ("reference", "zigzag"): _run("reference", "zigzag", "inverse", T=None,
                                          message="ran; beta corrected by 1e-9 rad"),
            ("reference", "stability-psid0"): _run(
                "reference", "stability-psid0",
                trajectory=SimpleNamespace(settings={"initial_correction": "none needed"})),
            ("reference", "replay"): _run("reference", "replay", status="failed", n=0,
                                          trajectory=SimpleNamespace(settings={}))}
    rows, checks, corrections = sn.reference_rows(["check", "zigzag", "stability-psid0",
                                                   "replay"], runs)
    assert rows == [
        {"scenario": "check", "kind": "inverse", "status": "completed", "t_end": "0.040",
         "max_abs_C": f"{np.abs(C).max():.1e}"},
        {"scenario": "zigzag", "kind": "inverse", "status": "completed", "t_end": "0.040",
         "max_abs_C": f"{np.abs(C).max():.1e}"},
        {"scenario": "stability-psid0", "kind": "forward", "status": "completed",
         "t_end": "0.040", "max_abs_C": f"{np.abs(C).max():.1e}"},
        {"scenario": "replay", "kind": "forward", "status": "failed", "t_end": "0.000",
         "max_abs_C": "0.0e+00"}]
    assert [c["check"] for c in checks] == ["check: Mped = cv (R psi_dot)^2 R, Mdir = Mvue = 0"]
    assert corrections == {"zigzag": "beta corrected by 1e-9 rad",
                           "stability-psid0": "none needed"}
    # a case's own scenario (not a built-in) on its model
    from reference_model.scenarios import get_scenario
    mine = cs.on_model(get_scenario("check"), cs.model_spec("benchmark"))
    runs[("reference", mine.name)] = _run("reference", mine.name, "inverse", T=None)
    rows, checks, _ = sn.reference_rows([mine.name], runs, {mine.name: mine})
    bench = load_model("benchmark").constraint_residual(q, np.zeros((5, 8)))
    assert rows[0]["max_abs_C"] == f"{np.abs(bench).max():.1e}" and checks == []


def test_an_engine_that_cannot_be_built_is_skipped_or_its_failure_a_row():
    from engines import UnsupportedModel
    from reference_model import load_model
    model = load_model("thesis")

    def setup(exc=None):
        def build(m):
            if exc is not None:
                raise exc
            return ("built", m.name)
        return SimpleNamespace(label="E", build=build)

    failures = []
    assert sn._build_if_it_models(setup(), model, failures) == ("built", "thesis")
    assert sn._build_if_it_models(setup(UnsupportedModel("no")), model, failures) is None
    assert failures == []
    assert sn._build_if_it_models(setup(RuntimeError("bad\n  " + "x" * 400)), model,
                                  failures) is None
    assert [f.as_dict() for f in failures] == [{
        "quantity": "engine build", "scenario": "-", "model": "thesis", "engines": ["E"],
        "max_error": None, "tolerance": None, "passed": False,
        "localized_to": "RuntimeError: " + ("bad " + "x" * 400)[:300],   # the message cut
        "note": "E raised while being built on thesis"}]


def test_the_declared_run_difference_of_a_setup(monkeypatch):
    monkeypatch.setattr(sn, "engine_facts",
                        lambda spec: SimpleNamespace(run_difference=f"{spec}'s soft contact"))
    assert sn.run_difference(SimpleNamespace(engine="mujoco")) == "mujoco's soft contact"


class _MEngine:
    name, model = "m-engine", "its model"

    def __init__(self, supports=True, count=None, raises=None):
        self.calls, self._s, self._count, self._raises = [], supports, count, raises

    def supports(self, cap):
        return self._s and cap == "mass_matrix"

    def mass_matrix(self, q):
        self.calls.append(np.array(q))
        if self._raises:
            raise self._raises
        M = np.einsum("n,ij->nij", q[:, 0], np.eye(8))        # M of state k: q[k, 0] I
        return M if self._count is None else M[:self._count]


def test_the_mass_matrices_of_every_scenario_in_one_call():
    blocks = {"a": np.full((2, 8), 1.0), "b": np.full((3, 8), 2.0)}
    eng = _MEngine()
    batch = sn._MassInOneCall(eng, blocks)
    assert len(eng.calls) == 1 and eng.calls[0].shape == (5, 8)
    a, b = batch.at("a"), batch.at("b")
    assert (a.name, a.model, a.scenario) == ("m-engine", "its model", "a")
    assert a.supports("mass_matrix") and not a.supports("gravity")
    np.testing.assert_array_equal(a.mass_matrix(None), np.tile(np.eye(8), (2, 1, 1)))
    np.testing.assert_array_equal(b.mass_matrix(None), 2.0 * np.tile(np.eye(8), (3, 1, 1)))
    assert batch.error is None
    short = sn._MassInOneCall(_MEngine(count=4), blocks)
    assert str(short.error) == "mass_matrix returned 4 matrices for 5 states"
    with pytest.raises(ValueError, match="returned 4 matrices"):
        short.at("a").mass_matrix(None)
    boom = sn._MassInOneCall(_MEngine(raises=KeyError("k")), blocks)
    with pytest.raises(KeyError):
        boom.at("b").mass_matrix(None)
    none = _MEngine(supports=False)
    assert sn._MassInOneCall(none, blocks).values == {} and none.calls == []
    empty = _MEngine()
    assert sn._MassInOneCall(empty, {}).values == {} and empty.calls == []


def test_the_states_at_which_m_is_compared():
    ok = SimpleNamespace(name="ok", kind="inverse", compared=("mass_matrix",))
    no_m = SimpleNamespace(name="no_m", kind="inverse", compared=("torques",))
    fwd = SimpleNamespace(name="fwd", kind="forward", compared=("mass_matrix",))
    few = SimpleNamespace(name="few", kind="inverse", compared=("mass_matrix",))
    dead = SimpleNamespace(name="dead", kind="inverse", compared=("mass_matrix",))
    cases = {c.name: c for c in (ok, no_m, fwd, few, dead)}
    runs = {("reference", "ok"): _run("reference", "ok", n=250),
            ("reference", "no_m"): _run("reference", "no_m"),
            ("reference", "fwd"): _run("reference", "fwd"),
            ("reference", "few"): _run("reference", "few", n=50),
            ("reference", "dead"): _run("reference", "dead", n=0, status="failed")}
    runs[("reference", "ok")].q[:, 0] = np.arange(250)
    got = sn._mass_states(list(cases), cases, runs, {})     # fwd: no horizon, unjudgeable
    assert list(got) == ["ok", "few"]
    np.testing.assert_array_equal(got["ok"][:, 0], np.arange(0, 250, 2))   # every 250 // 100
    assert len(got["few"]) == 50
    assert list(sn._mass_states(["fwd"], cases, runs, {"fwd": "a horizon"})) == ["fwd"]


@pytest.fixture
def scen_env(monkeypatch):
    """`compare_scenarios` with every judgment replaced by a recorder returning one marked row
    (the judgments are tested on their own): what the stage asks for, and how it lays out."""
    from comparisons.judgments.rows import Comparison
    env = SimpleNamespace(calls=[], mass_raises=set())

    def row(quantity, scenario, engines, passed=True, **kw):
        return Comparison.of({"quantity": quantity, "scenario": scenario, "model": "thesis",
                              "engines": engines, "max_error": 1e-9, "tolerance": 1e-6,
                              "passed": passed, **kw})

    def mass(name, model, q, engines, tols):
        (label, eng), = engines.items()
        env.calls.append(("M", name, label, len(q)))
        if label in env.mass_raises:
            raise RuntimeError("M broke")
        return [row("mass_matrix", name, ["reference", label])]

    def inverse(ref, r, tols):
        env.calls.append(("inverse", r.scenario, r.engine))
        return [row("torques", r.scenario, ["reference", r.engine])]

    def constraints(model, r, tols):
        env.calls.append(("C", r.scenario, r.engine))
        return row("constraint_residual", r.scenario, [r.engine], localized_to="rD_z")

    def series(model, r):
        return np.full((len(r.t), 5), 0.5)

    def declared(ref, r, hor, difference, cmax, cwhere):
        env.calls.append(("declared", r.scenario, r.engine, difference, cmax, cwhere, hor.t))
        return [row("trajectory", r.scenario, ["reference", r.engine], None, why="declared"),
                row("slip", r.scenario, [r.engine], None)]

    def forward(model, ref, r, hor, tols, judged_by, reported_because):
        env.calls.append(("forward", r.scenario, r.engine, judged_by, reported_because))
        return ([row("trajectory", r.scenario, ["reference", r.engine], r.engine != "B")],
                SimpleNamespace(t=r.t, errors=np.full((len(r.t), 8), 2.0)))

    def traj_error(ref, r, t):
        env.calls.append(("trajectory_error", r.scenario, r.engine, t))
        return SimpleNamespace(t=r.t, errors=np.full((len(r.t), 8), 3.0))

    facts = {"a": SimpleNamespace(run_difference=None, trajectory_tolerance="trajectory",
                                  trajectory_judged_by=None),
             "b": SimpleNamespace(run_difference=None, trajectory_tolerance=None,
                                  trajectory_judged_by="its convergence order"),
             "s": SimpleNamespace(run_difference="a soft contact", trajectory_tolerance=None,
                                  trajectory_judged_by=None)}
    for name, f in (("compare_mass_matrix", mass), ("compare_inverse", inverse),
                    ("compare_constraints", constraints), ("constraint_series", series),
                    ("declared_difference_rows", declared), ("compare_forward", forward),
                    ("trajectory_error", traj_error), ("engine_facts", lambda spec: facts[spec])):
        monkeypatch.setattr(sn, name, f)
    env.builds = []

    def setup(label, spec):
        return SimpleNamespace(label=label, engine=spec, build=lambda m: env.builds.append(
            (label, m.name)) or _MEngine())

    env.setups = {"reference": setup("reference", "reference"), "A": setup("A", "a"),
                  "B": setup("B", "b"), "S": setup("S", "s")}
    return env


def _scen_runs():
    T = np.zeros((5, 3))
    runs = {}
    for name in ("check", "zigzag"):
        runs[("reference", name)] = _run("reference", name, "inverse", T=T)
        runs[("A", name)] = _run("A", name, "inverse", T=T)
        runs[("B", name)] = _run("B", name, "inverse", status="failed", message="diverged " * 60)
        runs[("S", name)] = _run("S", name, "inverse", status="not run")
    for name in ("stability-psid0", "replay"):
        for lab in ("reference", "A", "B", "S"):
            runs[(lab, name)] = _run(lab, name)
    runs[("reference", "check-forward")] = _run("reference", "check-forward", status="failed",
                                                n=0, message="it fell")
    runs[("A", "check-forward")] = _run("A", "check-forward")
    runs[("reference", "stability-psid1")] = _run("reference", "stability-psid1")
    return runs


SCEN_NAMES = ["check", "zigzag", "stability-psid0", "replay", "check-forward", "stability-psid1"]
SCEN_HORIZONS = {"stability-psid0": SimpleNamespace(t=0.03), "replay": SimpleNamespace(t=0.02)}


def test_compare_scenarios_rows(scen_env):
    scen_env.mass_raises = {"B"}
    sec = sn.compare_scenarios("TOLS", SCEN_NAMES, scen_env.setups, _scen_runs(), SCEN_HORIZONS)
    assert sec.title == "Every engine on every scenario"
    got = [(r["quantity"], r["scenario"], tuple(r["engines"]), r["passed"])
           for r in sec.comparisons]
    assert got == [
        ("engine run", "check", ("B",), False),
        ("mass_matrix", "check", ("reference", "A"), True),
        ("engine call", "check", ("B",), False),                 # its M raised: its own row
        ("mass_matrix", "check", ("reference", "S"), True),
        ("torques", "check", ("reference", "A"), True),
        ("engine run", "zigzag", ("B",), False),
        ("mass_matrix", "zigzag", ("reference", "A"), True),
        ("engine call", "zigzag", ("B",), False),
        ("mass_matrix", "zigzag", ("reference", "S"), True),
        ("torques", "zigzag", ("reference", "A"), True),
        *((q, n, e, p) for n in ("stability-psid0", "replay") for q, e, p in (
            ("mass_matrix", ("reference", "A"), True), ("engine call", ("B",), False),
            ("mass_matrix", ("reference", "S"), True),
            ("constraint_residual", ("reference",), True),
            ("constraint_residual", ("A",), True), ("trajectory", ("reference", "A"), True),
            ("constraint_residual", ("B",), True), ("trajectory", ("reference", "B"), False),
            ("trajectory", ("reference", "S"), None), ("slip", ("S",), None))),
        ("not compared", "check-forward", ("A",), False),
        ("not compared", "stability-psid1", ("-",), False)]
    failed_run = sec.comparisons[0]
    assert failed_run.as_dict() == {
        "quantity": "engine run", "scenario": "check", "model": "thesis", "engines": ["B"],
        "max_error": None, "tolerance": None, "passed": False,
        "localized_to": ("diverged " * 60)[:300],
        "note": "B did not complete the run it was asked for"}
    assert sec.comparisons[-2]["localized_to"] == "not compared: the reference's run failed (it fell)"
    assert sec.comparisons[-1]["localized_to"].startswith(
        "not compared: its meaningful-horizon stage failed")
    # the engines are built once per model, for M at every scenario's states in one call
    assert sorted(scen_env.builds) == [("A", "thesis"), ("B", "thesis"), ("S", "thesis")]
    calls = scen_env.calls
    assert ("declared", "stability-psid0", "S", "a soft contact", 1e-9, "rD_z", 0.03) in calls
    assert ("forward", "replay", "A", "trajectory", "a study") in calls
    assert ("forward", "replay", "B", None, "its convergence order") in calls
    assert ("trajectory_error", "replay", "S", 0.02) in calls
    assert not any(c[0] in ("forward", "declared", "trajectory_error") and c[2] == "reference"
                   for c in calls)


def test_compare_scenarios_table_and_figures(scen_env):
    runs = _scen_runs()
    sec = sn.compare_scenarios("TOLS", SCEN_NAMES, scen_env.setups, runs, SCEN_HORIZONS)
    (table,) = _tables(sec)
    assert table.header == ("quantity", "scenario", "engines", "max error", "tolerance",
                            "verdict", "where")
    assert table.rows[0] == ("engine run", "check", "B", "-", "-", "FAIL", ("diverged " * 60)[:300])
    assert table.rows[1] == ("mass_matrix", "check", "reference vs A", "1.0e-09", "1.0e-06",
                             "pass", "-")
    by_q = {(r[0], r[1], r[2]): r for r in table.rows}
    assert by_q[("trajectory", "replay", "reference vs S")][5] == "reported: declared"
    assert by_q[("slip", "replay", "S")][5] == "reported"
    from reference_model import CONSTRAINT_NAMES
    assert f"({', '.join(CONSTRAINT_NAMES)})" in table.note     # the residuals' units named
    assert [(f.name, f.kind) for f in sec.figures] == [
        ("check_torques.png", "torque_overlay"), ("zigzag_torques.png", "torque_overlay"),
        ("stability-psid0_trajectories.png", "trajectory_overlay"),
        ("replay_trajectories.png", "trajectory_overlay"),
        ("constraint_residuals.png", "constraint_residuals"),
        ("stability_theta.png", "stability_study"), ("replay_vs_zigzag.png", "replay_vs_zigzag")]
    torques, _, traj, _, resid, stab, replay = sec.figures
    # the runs with torques (B's failed run has none)
    assert torques.data["scenario"] == "check" and list(torques.data["runs"]) == ["reference", "A"]
    assert set(traj.data) == {"scenario", "runs", "errors", "horizon", "threshold"}
    assert list(traj.data["runs"]) == ["reference", "A", "B", "S"]
    assert traj.data["horizon"] == 0.03 and traj.data["threshold"] == sn.HORIZON_THRESHOLD
    assert list(traj.data["errors"]) == ["A", "B", "S"]
    np.testing.assert_array_equal(traj.data["errors"]["A"][1], np.full(5, 2.0))   # compare_forward's
    np.testing.assert_array_equal(traj.data["errors"]["S"][1], np.full(5, 3.0))   # trajectory_error's
    assert resid.data["bound"] == 2e-3 and list(resid.data["panels"]) == ["stability-psid0", "replay"]
    t, c0, rest = resid.data["panels"]["replay"]["A"]
    assert np.array_equal(t, runs[("A", "replay")].t) and np.all(c0 == 0.5) and np.all(rest == 0.5)
    assert list(stab.data["runs"]) == ["reference", "A", "B", "S"]
    assert list(stab.data["runs"]["A"]) == ["stability-psid0"]
    t, theta, status, t_end = stab.data["runs"]["A"]["stability-psid0"]
    assert status == "completed" and t_end == 0.04 and theta.shape == (5,)
    assert list(replay.data["replays"]) == ["reference", "A", "B", "S"]
    assert len(replay.data["zigzag"]) == 3
    # the table comes before the figures
    kinds = [type(b).__name__ for b in sec.blocks]
    assert kinds.index("Table") < kinds.index("Figure")


def test_compare_scenarios_without_forward_or_replay_runs_draws_only_what_it_has(scen_env):
    runs = {k: r for k, r in _scen_runs().items() if k[1] != "replay"}
    sec = sn.compare_scenarios("TOLS", ["check"], scen_env.setups, runs, {})
    assert [f.name for f in sec.figures] == ["check_torques.png"]     # no replay: no overlay
    runs[("reference", "check")] = _run("reference", "check", "inverse", T=None)
    runs[("A", "check")] = _run("A", "check", "inverse", T=None)
    sec = sn.compare_scenarios("TOLS", ["check"], scen_env.setups, runs, {})
    assert sec.figures == []


# -- the stages in report order (comparisons/stages/catalog.py) -----------------------------

def test_the_stages_in_report_order_and_the_sections_words():
    """`run --sections` takes these words (README, docs/engines.md: 'contact' selects the
    soft-contact study); the stages without one always run."""
    from comparisons.stages.catalog import SECTIONS, STAGES
    assert [(s.name, s.section) for s in STAGES] == [
        ("stability", None), ("terms", "terms"), ("fixed-step", "fixed-step"),
        ("energy", "energy"), ("soft-contact", "contact"), ("benchmark", "benchmark"),
        ("linear-check", None), ("engine-eigenvalues", "eigenvalues"),
        ("option-study", "option-study"), ("faults", "faults")]
    assert SECTIONS == ("terms", "fixed-step", "energy", "contact", "benchmark", "eigenvalues",
                        "option-study", "faults")


# -- the soft-contact study's stage and ranking (comparisons/stages/soft_contact.py) --------

from comparisons.judgments.contact_ranking import ContactRow  # noqa: E402
from comparisons.stages import soft_contact as sct  # noqa: E402


def _contact_row(engine, error, reached=True, model="thesis-disc", lift=0.45, simulated=0.5,
                 error_max=None):
    return ContactRow(engine, engine.upper(), model, "stability-psid10", 0.43, reached, error,
                      2 * error if error_max is None else error_max, 1e-3, 2e-3, 3e-5, 1e-5, lift,
                      simulated, 1.5, "its defaults")


def test_the_contact_studys_windows_and_simulated_seconds():
    from engines.facts import Refinement, SoftContact
    assert (sct.SCENARIO, sct.MODEL, sct.STUDY_TIME) == ("stability-psid10", "thesis-disc", 0.2)
    assert sct.window(False) == sct.WINDOW == 0.5 and sct.window(True) == sct.QUICK_WINDOW == 0.5
    soft = SoftContact(refinements=(Refinement("h", "k", (1, 2, 3, 4), dict, (1, 2)),
                                    Refinement("k", "h", (1, 2, 3, 4), dict, None)))
    # full: the default run (0.5 s) and 8 refinement runs of 0.2 s; quick: 2 of the first series
    assert math.isclose(sct._study_seconds(soft, False), 0.5 + 8 * 0.2)
    assert math.isclose(sct._study_seconds(soft, True), 0.5 + 2 * 0.2)
    assert sct._per_second(1.5, SimpleNamespace(t_end=0.5)) == 3.0
    assert math.isnan(sct._per_second(1.5, SimpleNamespace(t_end=0.0)))
    run, seconds = sct._timed(lambda **o: o, a=1)
    assert run == {"a": 1} and 0.0 <= seconds < 5.0
    facts = SimpleNamespace(run_setups=(SimpleNamespace(settings=""),
                                        SimpleNamespace(settings="h = 1e-4 s")))
    assert sct._settings_line(facts) == "h = 1e-4 s"
    assert sct._settings_line(SimpleNamespace(run_setups=())) == ""


def test_the_ranking_table_and_summary():
    rows = [_contact_row("b", 2e-3), _contact_row("a", 1e-3),
            _contact_row("c", None, reached=False, lift=None, simulated=0.31, error_max=5e-2)]
    sec = sct.ranking_section(rows)
    assert sec.title == "Soft-contact engines side by side: how close to ideal rolling"
    (table,) = _tables(sec)
    assert table.header == ("rank", "engine", "error at 0.43 s [rad, m]", "max error up to it",
                            "slip RMS [m/s]", "slip max [m/s]", "penetration max [m]",
                            "penetration RMS [m]", "first lift-off [s]",
                            "run time per simulated second [s]")
    assert table.rows == (
        ("1", "A", "1.00e-03", "2.00e-03", "1.00e-03", "2.00e-03", "3.00e-05", "1.00e-05",
         "0.45", "3"),
        ("2", "B", "2.00e-03", "4.00e-03", "1.00e-03", "2.00e-03", "3.00e-05", "1.00e-05",
         "0.45", "3"),
        ("3", "C", "ends at 0.31 s", "5.00e-02", "1.00e-03", "2.00e-03", "3.00e-05", "1.00e-05",
         "-", "4.8"))
    assert "(3: A, B, C)" in _texts(sec)[0]
    summary = sct.ranking_summary(rows)
    assert [r.pop("rank") for r in summary["rows"]] == [1, 2, 3]
    assert summary == {"model": "thesis-disc", "scenario": "stability-psid10", "horizon_s": 0.43,
                       "ranked_by": "error_at_horizon, then slip_rms; runs ending before the "
                                    "horizon last",
                       "rows": [rows[1].as_dict(), rows[0].as_dict(), rows[2].as_dict()]}
    other = sct.ranking_section([_contact_row("a", 1e-3, model="mine")])
    assert other.title.endswith("how close to ideal rolling on mine")


def _soft_plan(models=(), quick=False, scenarios=("check", "stability-psid0", "stability-psid5")):
    from engines.facts import Refinement, SoftContact
    soft = SoftContact(refinements=(Refinement("h", "k", (1, 2), dict, (1,)),))
    facts = {"reference": SimpleNamespace(spec="reference", soft_contact=None),
             "mj": SimpleNamespace(spec="mj", label="MJ", soft_contact=soft,
                                   costs=SimpleNamespace(run_per_second=2.0)),
             "p": SimpleNamespace(spec="p", label="P", soft_contact=None)}
    opts = SimpleNamespace(models=models, quick=quick, scenarios=scenarios)
    from comparisons.stages.stage import Plan
    return Plan(opts, (), facts)


def test_the_soft_contact_stage_tasks():
    stage = sct.SoftContactStage()
    assert (stage.name, stage.section) == ("soft-contact", "contact")
    stab = ("stability-psid0", "stability-psid5")
    tasks = stage.tasks(_soft_plan())
    assert [(t.key, t.func, t.args, t.label, t.engine) for t in tasks] == [
        (("claims-reference", "reference", "thesis-disc"), scc.reference_claims_on_disc, (stab,),
         "reference: the stability runs on thesis-disc", None),
        (("study", "mj", "thesis-disc"), sct.contact_study, ("mj", False),
         "MJ contact study", "mj"),
        (("claims", "mj", "thesis-disc"), scc.claims_on_disc, ("mj", stab),
         "MJ: the stability claims on thesis-disc", "mj")]
    assert [t.cost for t in tasks] == pytest.approx([0.3 * 2, 2.0 * (0.5 + 2 * 0.2),
                                                     2.0 * 2.0 * 2])
    quick = stage.tasks(_soft_plan(quick=True))             # no claims in --quick
    assert [t.key for t in quick] == [("study", "mj", "thesis-disc")]
    assert quick[0].args == ("mj", True) and quick[0].cost == pytest.approx(2.0 * (0.5 + 0.2))
    assert [t.key for t in stage.tasks(_soft_plan(scenarios=("check",)))] == [
        ("study", "mj", "thesis-disc")]                     # no stability scenario: no claims
    models = (SimpleNamespace(spec="d.toml", contact="disc"),
              SimpleNamespace(spec="t.toml", contact="thesis"))
    on = stage.tasks(_soft_plan(models))
    assert [(t.key, t.args, t.label) for t in on] == [
        (("study", "mj", "d.toml"), ("mj", False, "d.toml"), "d.toml: MJ contact study")]
    assert stage.tasks(_soft_plan(models[1:])) == []        # no disc-contact model
    no_soft = _soft_plan()
    no_soft.facts.pop("mj")
    assert stage.tasks(no_soft) == []


def test_the_soft_contact_stage_assembles_rankings_studies_claims_and_failures():
    from comparisons.stages.pool import TaskResult
    stage, plan = sct.SoftContactStage(), _soft_plan()
    plan.facts["mj2"] = SimpleNamespace(spec="mj2", label="MJ2", soft_contact=None)
    s1, s2, s3 = (sct.Section(f"study {i}") for i in (1, 2, 3))
    ref = scc.DiscClaims("reference", "reference", (_claim("stability-a", "reference"),))
    mine = scc.DiscClaims("mj", "MJ", (_claim("stability-a", "mj", "fails", "it fell"),))
    results = {
        ("study", "mj", "thesis-disc"): TaskResult(None, sct.ContactStudy(s1, _contact_row(
            "mj", 2e-3)), 1.0),
        ("study", "mj2", "thesis-disc"): TaskResult(None, sct.ContactStudy(s2, _contact_row(
            "mj2", 1e-3)), 1.0),
        ("study", "mj", "d.toml"): TaskResult(None, sct.ContactStudy(s3, None), 1.0),
        ("study", "p", "thesis-disc"): TaskResult(None, None, 1.0, "boom"),
        ("claims-reference", "reference", "thesis-disc"): TaskResult(None, ref, 1.0),
        ("claims", "mj", "thesis-disc"): TaskResult(None, mine, 1.0),
        ("claims", "mj2", "thesis-disc"): TaskResult(None, None, 1.0, "bang")}
    out = stage.assemble(plan, results)
    titles = [s.title for s in out.sections]
    assert titles == ["Soft-contact engines side by side: how close to ideal rolling",
                      "study 1", "study 2", "study 3", "P contact study",
                      "The thesis's stability claims on thesis-disc: the soft-contact engines",
                      "MJ2 claims on thesis-disc"]
    ranking = out.sections[0]
    assert [r[1] for r in _tables(ranking)[0].rows] == ["MJ2", "MJ"]
    assert [s["model"] for s in out.summary["soft_contact_ranking"]] == ["thesis-disc"]
    claims = out.sections[5]
    assert _tables(claims)[0].header == ("claim", "reference thesis-disc", "mj thesis-disc")
    # the reference's claims task failed: the table without its column, and its failure
    results[("claims-reference", "reference", "thesis-disc")] = TaskResult(None, None, 1.0, "x")
    out = stage.assemble(plan, results)
    assert [s.title for s in out.sections][-3:] == [
        "The thesis's stability claims on thesis-disc: the soft-contact engines",
        "MJ2 claims on thesis-disc", "reference: the stability runs on thesis-disc"]
    assert _tables(out.sections[-3])[0].header == ("claim", "mj thesis-disc")
    only = stage.assemble(plan, {("study", "mj", "d.toml"): TaskResult(None, sct.ContactStudy(
        s3, None), 1.0)})
    assert [s.title for s in only.sections] == ["study 3"]
    assert only.summary == {"soft_contact_ranking": []}


def test_the_soft_contact_stage_revises_the_claims_of_the_engines_it_judged():
    from comparisons.stages.pool import TaskResult
    claims = [_claim("stability-a", "mj", "not assessed"), _claim("stability-a", "p", "holds")]
    mine = scc.DiscClaims("mj", "MJ", (_claim("stability-a", "mj", "fails", "it fell"),))
    results = {("claims", "mj", "thesis-disc"): TaskResult(None, mine, 1.0),
               ("claims", "x", "thesis-disc"): TaskResult(None, None, 1.0, "bang"),
               ("study", "mj", "thesis-disc"): TaskResult(None, "not claims", 1.0)}
    revised = sct.SoftContactStage().revise_claims(_soft_plan(), results, claims)
    assert revised[0]["verdict"] == "fails"
    assert revised[0]["evidence"] == scc.on_disc("MJ") + "it fell"
    assert revised[1] == claims[1]


def test_the_energy_section_runs_the_reference_and_each_engine_when_given_no_rows(monkeypatch):
    asked = []
    monkeypatch.setattr(en, "energy_rows", lambda spec, options, model: asked.append(
        (spec, options, model)) or ([EN_ROWS[0]] if spec is None else [_drift(spec, 1e-4)]))
    sec = en.energy_section(EN_TOL, (("p", {"k": 1}), ("q", {})), "thesis-disc")
    assert asked == [(None, {}, "thesis-disc"), ("p", {"k": 1}, "thesis-disc"),
                     ("q", {}, "thesis-disc")]
    assert [r["engines"] for r in sec.comparisons] == [["reference thesis-disc"], ["p"], ["q"]]


def test_the_energy_section_on_a_users_bicycle_and_a_not_run_row_first(monkeypatch):
    from comparisons.stages import stability
    monkeypatch.setattr(stability, "critical", lambda spec: {})
    rows = [{"engine": "D", "not_run": "not run on this model: no disc"}, _drift("A", 1e-4)]
    sec = en.energy_section(EN_TOL, (), "benchmark", rows)
    assert sec.title.endswith("(IFToMM: 100 (Emax - Emin) / E0) on benchmark")
    assert [r[0] for r in _tables(sec)[0].rows] == ["D", "A"]      # the row after it kept
    assert [r["model"] for r in sec.comparisons] == ["benchmark (cv = 0)"]
    assert _texts(sec)[0].startswith("Free roll from lean and steer pi/32 at psi_dot = 10 rad/s")


def test_the_energy_stage_draws_no_section_when_the_reference_was_not_run():
    from comparisons.stages.pool import TaskResult
    from comparisons.stages.stage import Plan
    plan = Plan(SimpleNamespace(models=(), tolerances=EN_TOL, options_for=dict), (),
                {"reference": SimpleNamespace(spec="reference")})
    ref_not_run = [{"engine": "reference thesis-disc", "not_run": "not run on this model: x"}]
    out = en.EnergyStage().assemble(plan, {(None, "thesis-disc"): TaskResult(None, ref_not_run,
                                                                            1.0)})
    assert out.sections == []
