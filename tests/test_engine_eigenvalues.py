"""The ``eigenvalues`` capability (engines/linear.py), its judgment
(comparisons/judgments/engine_eigenvalues.py) and the two stages reading it: every engine's
linearization against the reference's, and the option studies (a declared model difference
reported, never failed).

The expected values are the reference's exact linearization (`reference_model.linearize`:
complex-step derivatives of its own reduced equations, no truncation), never this code's
output. Engines here: Pinocchio's terms (0.01 s per call) and a wrapper of them; the crown
study's real SymBRiM run is the `slow` test at the end. About 0.6 s in all.
"""

from __future__ import annotations

import types

import numpy as np
import pytest

from comparisons.judgments.engine_eigenvalues import judge_eigenvalues, matched_error
from comparisons.judgments.tolerances import load_tolerances
from engines import load_engine
from engines.linear import critical_speeds, eigenvalues_by_differences
from reference_model import load_model
from reference_model.linearize import capsize_speed, weave_speed

TOL = load_tolerances()
V = np.linspace(0.0, 10.0, 21)


@pytest.fixture(scope="module")
def bench():
    m = load_model("benchmark")
    return m, load_engine("pinocchio", m)


def test_differences_of_an_engines_terms_are_the_exact_linearization(bench):
    """Central differences of Pinocchio's accelerations on its own constraints against the
    complex-step linearization over 0-10 m/s: measured 6.4e-14 /s at most; bound 1e-12 /s
    (the h^2 truncation at h = 1e-7 is ~4e-14, engines/linear.py), twenty times that."""
    model, eng = bench
    err = np.abs(eigenvalues_by_differences(eng, V) - model.eigenvalues(V))
    assert err.max() < 1e-12, err.max()


class _Wrapped:
    """Pinocchio's terms under another model's parameters (``model``): what a wrong speed
    scaling or a wrong sign in the reduction would compute."""

    def __init__(self, eng, model):
        self.name, self.model, self._eng = "wrapped", model, eng

    def constraint_residual(self, q, dq):
        return self._eng.constraint_residual(q, dq)

    def constraint_jacobian(self, q):
        return self._eng.constraint_jacobian(q)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._eng.forward_acceleration(q, dq, torques)


def test_a_wrong_speed_scaling_is_caught(bench):
    """Planted: the rear wheel's rate taken as v / (1.01 R_rear) (a 1 % speed-scaling error:
    the linearization is then at v / 1.01). The judgment fails by far: the error is ~1e-2
    relative, against [engine_eigenvalues] 1e-9."""
    model, eng = bench
    wrong = _Wrapped(eng, model.with_params(model.params.replace(R_rear=1.01 * model.params.R_rear)))
    err = matched_error(eigenvalues_by_differences(wrong, V), model.eigenvalues(V)).max()
    assert err > 1e3 * TOL["engine_eigenvalues"].tolerance, err


def test_drag_has_no_steady_motion_to_linearize():
    from reference_model.linearize import LinearizationError
    m = load_model("thesis-disc")        # cv = 0.8 kg/m
    with pytest.raises(LinearizationError, match="cv = 0.8"):
        eigenvalues_by_differences(load_engine("pinocchio", m), [1.0])


def test_critical_speeds_of_any_eigenvalues_are_the_references_own():
    """The generic root finding (the weave pair's real part, and the product of the four
    eigenvalues for the capsize) on the exact eigenvalues against `linearize`'s own (its
    grid, and det(g K0 + v^2 K2)): Meijaard et al.'s 4.2924 and 6.0243 m/s, within 1e-10 m/s
    (both brentq to 1e-12 or better on the same smooth functions)."""
    m = load_model("benchmark")
    w, c = critical_speeds(m.eigenvalues, (0.0, 10.0))
    assert abs(w - weave_speed(m, (0.0, 10.0))) < 1e-10
    assert abs(c - capsize_speed(m, (0.0, 10.0))) < 1e-10
    assert critical_speeds(m.eigenvalues, (0.0, 3.0)) == (None, None)
    # a bracket holding both speeds (3.33-6.67 m/s): the capsize search starts at the weave
    # speed itself, not at the next grid point (where it would miss it)
    w3, c3 = critical_speeds(m.eigenvalues, (0.0, 10.0), step=3.5)
    assert abs(w3 - w) < 1e-10 and c3 is not None and abs(c3 - c) < 1e-10


def test_a_capsize_crossing_on_a_grid_point_is_found():
    """Hand-made eigenvalues: a weave pair whose real part is 4 - v (crossing at 4 m/s, off
    the grid's 0.5 m/s points only by brentq's tolerance) and a real capsize root 6 - v, zero
    exactly at the grid point 6.0 m/s: the product of the four changes sign there, so the
    capsize speed is 6.0 (np.sign(0) = 0 had hidden the change from the neighbours' product,
    and the search returned None). Off the grid, brentq's root."""
    def lam(v):
        v = np.atleast_1d(np.asarray(v, dtype=float))
        return np.stack([(4.0 - v) + 2j, (4.0 - v) - 2j, (6.0 - v) + 0j, -3.0 + 0j * v], axis=1)

    w, c = critical_speeds(lam, (0.0, 10.0))
    assert abs(w - 4.0) < 1e-10
    assert c == 6.0
    # the grid 0, 0.7, ... 9.8 has no point at 6: brentq's root, to 1e-12
    w, c = critical_speeds(lam, (0.0, 9.8), step=0.7)
    assert abs(c - 6.0) < 1e-10
    # a zero at the top of the range with nothing above it is no crossing, nor is a root
    # that stays positive: none
    assert critical_speeds(lam, (0.0, 6.0))[1] is None
    assert critical_speeds(lam, (0.0, 5.5))[1] is None


def _check(got, model, difference=""):
    ref = model.eigenvalues(V)
    crit = (weave_speed(model, (0.0, 10.0)), capsize_speed(model, (0.0, 10.0)))
    mine = critical_speeds(lambda s: got(np.atleast_1d(s)), (0.0, 10.0))
    return judge_eigenvalues("engine", model.name, V, got(V), ref, mine, crit, (0.0, 10.0), TOL,
                             difference)


def test_the_judgment_passes_agreement_and_fails_a_small_modelling_error():
    """The reference's own eigenvalues pass; those of the benchmark with a 1 mm longer fork
    offset (another bicycle) fail, both the eigenvalues and the weave speed."""
    m = load_model("benchmark")
    assert _check(m.eigenvalues, m).passed
    other = m.with_params(m.params.replace(dx4=m.params.dx4 + 1e-3))
    c = _check(other.eigenvalues, m)
    assert c.passed is False and not c.eigenvalues_passed and not c.critical[0].passed


def test_a_declared_model_difference_is_reported_never_failed():
    """The same other bicycle declared as a model difference (an option study's value other
    than the reference's): every row passed None, with the difference named and its numbers
    kept; the reference value's rows judged."""
    from comparisons.judgments.engine_eigenvalues import check_rows
    m = load_model("benchmark")
    other = m.with_params(m.params.replace(dx4=m.params.dx4 + 1e-3))
    rows = check_rows(_check(other.eigenvalues, m, "a longer fork offset"))
    assert [r["passed"] for r in rows] == [None, None, None]
    assert all(r["declared_difference"] == "a longer fork offset" for r in rows)
    assert rows[0]["max_error"] > 1e-6
    assert [r["passed"] for r in check_rows(_check(m.eigenvalues, m))] == [True, True, True]


def _plan(engines, quick=False):
    from comparisons.stages.pipeline import Options
    from comparisons.stages.stage import Plan
    from engines.facts import engine_facts
    opts = Options(scenarios=("check",), engines=("reference", *engines), quick=quick)
    return Plan(opts, (), {e: engine_facts(e) for e in ("reference", *engines)})


def test_an_engine_without_the_capability_gets_no_rows():
    """Exudyn (mass matrix, forces, runs: no eigenvalues) gets no task in either stage, the
    engines with the capability one per default model; --quick runs neither stage (their
    cost), and the option study only where an engine declares one."""
    from comparisons.stages.engine_eigenvalues import EngineEigenvaluesStage
    from comparisons.stages.option_study import OptionStudyStage
    tasks = EngineEigenvaluesStage().tasks(_plan(("exudyn", "pinocchio")))
    assert sorted(t.key for t in tasks) == [("pinocchio", "benchmark"), ("pinocchio", "thesis-disc")]
    assert EngineEigenvaluesStage().tasks(_plan(("pinocchio",), quick=True)) == []
    assert OptionStudyStage().tasks(_plan(("exudyn", "pinocchio"))) == []


def test_the_engines_section_judges_and_names_what_was_not_run():
    """The section from one engine's value on the benchmark (Pinocchio's, computed by the
    stage's own task function) and one not run (a contact the engine does not model): a
    judged pass, a reported row, summary.json's entry under engine_eigenvalues."""
    from comparisons.stages.engine_eigenvalues import engine_eigenvalues_section, engine_linearization
    good = engine_linearization("pinocchio", {}, "benchmark", "pinocchio")
    skipped = {"engine": "other", "model": "thesis", "note": "", "speeds": (),
               "not_run": "not run on this model: its front contact is not modelled"}
    sec, summary = engine_eigenvalues_section([good, skipped], TOL)
    verdicts = [r["passed"] for r in sec.comparisons]
    assert verdicts == [True, True, True, None]
    assert summary["pinocchio"]["benchmark"]["passed"] is True
    assert summary["other"]["thesis"] == {"not_run": skipped["not_run"]}


def _value(model, x, lam_of):
    ref = model.eigenvalues(V)
    from comparisons.stages.option_study import CURVE
    crit = (weave_speed(model, (0.0, 10.0)), capsize_speed(model, (0.0, 10.0)))
    return {"value": x, "model": model.name, "note": "", "speeds": tuple(V), "lam": lam_of(V),
            "curve": lam_of(np.asarray(CURVE)),
            "critical": critical_speeds(lambda s: lam_of(np.atleast_1d(s)), (0.0, 10.0)),
            "seconds": 0.0, "ref_lam": ref, "ref_curve": model.eigenvalues(np.asarray(CURVE)),
            "ref_critical": crit}


def test_the_option_studys_verdict():
    """An option study's section: the reference value judged (a pass with the reference's own
    eigenvalues; planted, a 1e-6 /s offset there fails it), another value a declared model
    difference (another bicycle's eigenvalues: reported, never a failure), with the critical
    speeds' shifts in the table and a figure."""
    from comparisons.stages.option_study import option_study_section
    from engines.facts import OptionStudy
    m = load_model("benchmark")
    other = m.with_params(m.params.replace(dx4=m.params.dx4 + 1e-2))
    study = OptionStudy("crown_radius", "crown radius", "m", (0.0, 0.01), 0.0, "a torus")
    facts = types.SimpleNamespace(name="symbrim", label="SymBRiM")
    values = [_value(m, 0.0, m.eigenvalues), _value(m, 0.01, other.eigenvalues)]
    sec, summary = option_study_section(facts, study, m.name, values, TOL)
    assert [r["passed"] for r in sec.comparisons] == [True, True, True, None, None, None]
    assert all(r["declared_difference"].startswith("crown_radius = 0.01 m: a torus")
               for r in sec.comparisons[3:])
    assert summary["values"][1]["weave_speed"] != summary["reference_weave_speed"]
    assert [b.kind for b in sec.figures] == ["option_study"]
    off = [_value(m, 0.0, lambda s: m.eigenvalues(s) + 1e-6), values[1]]
    sec, _ = option_study_section(facts, study, m.name, off, TOL)
    assert sec.comparisons[0]["passed"] is False


def test_an_option_studys_reference_value_must_be_among_its_values():
    from engines.facts import OptionStudy
    with pytest.raises(ValueError, match="reference_value"):
        OptionStudy("crown_radius", "crown radius", "m", (0.01, 0.02), 0.0, "a torus")


def test_the_guard_refuses_eigenvalues_of_the_wrong_shape():
    from engines.guard import EngineCallError, check_eigenvalues
    assert check_eigenvalues(np.zeros((2, 4)), [1.0, 2.0]).dtype == complex
    for bad, speeds in ((np.zeros(4), 1.0), (np.zeros((1, 4)), [1.0, 2.0]), (None, [1.0]),
                        (np.full((1, 4), np.nan), [1.0])):
        with pytest.raises(EngineCallError):
            check_eigenvalues(bad, speeds)


@pytest.mark.slow
def test_the_crown_study_on_symbrim():
    """The declared study end to end on SymBRiM's toroidal front tyre (the cached second
    derivation): crown 0 judged and passing against the reference, every crown > 0 reported
    with the weave and capsize speeds falling as the crown grows (measured 4.292, 4.190,
    4.084, 3.863, 3.626 m/s weave and 6.024, 5.424, 4.959, 4.270, 3.774 m/s capsize at 0, 5,
    10, 20, 30 mm)."""
    pytest.importorskip("symbrim")
    from comparisons.stages.option_study import option_study_section, option_value
    from engines.facts import engine_facts
    facts = engine_facts("symbrim")
    study = facts.option_studies[0]
    values = [option_value("symbrim", {}, study.option, x, "benchmark") for x in study.values]
    sec, summary = option_study_section(facts, study, "benchmark", values, TOL)
    assert [r["passed"] for r in sec.comparisons[:3]] == [True, True, True]
    assert all(r["passed"] is None for r in sec.comparisons[3:])
    weave = [e["weave_speed"] for e in summary["values"]]
    capsize = [e["capsize_speed"] for e in summary["values"]]
    assert all(a > b for a, b in zip(weave, weave[1:])), weave
    assert all(a > b for a, b in zip(capsize, capsize[1:])), capsize


def test_an_option_studys_shared_work_is_prepared_once_when_it_runs():
    """The study's ``prepare`` (SymBRiM's: the toroidal code, a minute cold, more than one
    task's time limit allows) runs in the main process when the stage runs, not in --quick
    (where the study does not run)."""
    from comparisons.stages.option_study import OptionStudyStage
    from engines.facts import OptionStudy
    calls = []
    study = OptionStudy("crown_radius", "crown radius", "m", (0.0, 0.01), 0.0, "a torus",
                        prepare=lambda: calls.append(1))
    fake = types.SimpleNamespace(name="x", spec="x", label="X", capabilities={"eigenvalues"},
                                 option_studies=(study,))
    for quick, expected in ((True, []), (False, [1])):
        plan = _plan((), quick=quick)
        plan = type(plan)(plan.opts, (), {**plan.facts, "x": fake})
        calls.clear()
        OptionStudyStage().prepare(plan)
        assert calls == expected
        assert len(OptionStudyStage().tasks(plan)) == (0 if quick else 2)


def test_the_pipeline_prepares_each_stage_it_runs_before_making_its_tasks(monkeypatch):
    """`pipeline._stage_tasks` (run's main process, before the workers fork) calls each wanted
    stage's ``prepare`` once, before that stage's ``tasks``; a stage whose section is not
    wanted is neither prepared nor asked for tasks. Planted (the prepare call dropped from the
    pipeline): the calls list lacks it."""
    import dataclasses as dc

    from comparisons.stages import pipeline
    calls = []

    class Probe:
        def __init__(self, name, section):
            self.name, self.section = name, section

        def prepare(self, plan):
            calls.append(("prepare", self.name))

        def tasks(self, plan):
            calls.append(("tasks", self.name))
            return []

    monkeypatch.setattr(pipeline, "STAGES", (Probe("a", "eigenvalues"), Probe("b", "faults")))
    plan = _plan(())
    plan = type(plan)(dc.replace(plan.opts, sections=("eigenvalues",)), (), plan.facts)
    assert pipeline._stage_tasks(plan) == []
    assert calls == [("prepare", "a"), ("tasks", "a")]


# -- the judgment's arithmetic and rows on hand-made numbers (issue 24's mutation round) --------

def test_matched_error_pairs_the_eigenvalues_and_scales_per_speed():
    """Two speeds by hand. At the first the engine's four are the expected ones in another
    order with one 0.5 off: the best pairing leaves 0.5, over max(1, 10) = 10 -> 0.05. At the
    second every |expected| is below 1.5, so the scale is 1.5 (not 1, not the first speed's
    10): 0.3 / 1.5 = 0.2."""
    expected = [[10.0, 1 + 2j, 1 - 2j, -3.0], [0.5, -0.5, 0.25, -1.5]]
    got = [[1 - 2j, -3.0, 10.5, 1 + 2j], [0.8, -0.5, 0.25, -1.5]]
    np.testing.assert_allclose(matched_error(got, expected), [0.05, 0.2], rtol=1e-15)


def _judged(difference=None):
    """A check of 3 speeds whose worst is the middle one (error 0.4 / max(1, 8) = 0.05)."""
    expected = np.array([[2.0, 1.0, -1.0, -2.0], [8.0, 1.0, -1.0, -2.0],
                         [3.0, 1.0, -1.0, -2.0]])
    got = expected + np.array([[1e-3, 0, 0, 0], [0.4, 0, 0, 0], [0, 0, 0, 0]])
    kwargs = {} if difference is None else {"difference": difference}
    return judge_eigenvalues("pinocchio", "benchmark", [0.0, 5.0, 10.0], got, expected,
                             (4.25, None), (4.5, None), (0.0, 10.0), TOL, **kwargs)


def test_the_check_names_its_worst_speed_its_modes_and_its_range():
    c = _judged()
    assert (c.engine, c.model, c.speeds) == ("pinocchio", "benchmark", (0.0, 5.0, 10.0))
    assert c.error == pytest.approx(0.05, rel=1e-12) and c.worst_speed == 5.0
    assert [k.mode for k in c.critical] == ["weave", "capsize"]
    assert c.speed_range == (0.0, 10.0) and c.difference == ""
    assert c.passed is False        # 0.05 against [engine_eigenvalues] 1e-9: judged, failed
    # one scalar speed with its four eigenvalues is a grid of one
    one = judge_eigenvalues("e", "m", 5.0, [1.0, 2.0, 3.0, 4.0], [1.0, 2.0, 3.0, 4.0],
                            (None, None), (None, None), (0.0, 1.0), TOL)
    assert (one.speeds, one.worst_speed, one.error, one.passed) == ((5.0,), 5.0, 0.0, True)


def test_the_rows_of_a_judged_check_written_out():
    """Every field of the three rows, from the hand-made check above: the weave speeds 4.5
    and 4.25 m/s differ by 0.25 (fails [engine_critical_speeds]); no capsize speed on either
    side agrees."""
    from comparisons.judgments.engine_eigenvalues import check_rows
    eig, weave, capsize = (r.as_dict() for r in check_rows(_judged()))
    tol_eig = TOL["engine_eigenvalues"].tolerance
    tol_v = TOL["engine_critical_speeds"].tolerance
    assert eig == {
        "quantity": "eigenvalues: roll/steer eigenvalues", "scenario": "upright straight running",
        "model": "benchmark", "engines": ["reference", "pinocchio"],
        "max_error": eig["max_error"], "tolerance": tol_eig, "passed": False,
        "localized_to": "v = 5 m/s",
        "note": "largest |difference| of the matched eigenvalues / max(1, max |reference|), "
                "over 3 speeds 0-10 m/s",
        "speeds": [0.0, 10.0, 3]}
    assert eig["max_error"] == pytest.approx(0.05, rel=1e-12)
    assert weave == {
        "quantity": "eigenvalues: weave speed", "scenario": "upright straight running",
        "model": "benchmark", "engines": ["reference", "pinocchio"], "max_error": 0.25,
        "tolerance": tol_v, "passed": False,
        "localized_to": "reference 4.5000000000 m/s, engine 4.2500000000 m/s",
        "note": "in 0-10 m/s; none on both counts as agreement",
        "reference": 4.5, "engine_value": 4.25}
    assert capsize["quantity"] == "eigenvalues: capsize speed"
    assert (capsize["max_error"], capsize["passed"]) == (None, True)
    assert capsize["localized_to"] == "reference none m/s, engine none m/s"
    assert capsize["scenario"] == "upright straight running" and capsize["model"] == "benchmark"


def test_the_rows_of_a_declared_difference_are_reported_and_say_why():
    from comparisons.judgments.engine_eigenvalues import check_rows
    rows = [r.as_dict() for r in check_rows(_judged("crown"), quantity="crown study",
                                            scenario="s")]
    tail = "; reported, not judged: a declared model difference (crown)"
    assert [r["passed"] for r in rows] == [None, None, None]
    assert [r["quantity"] for r in rows] == ["crown study: roll/steer eigenvalues",
                                             "crown study: weave speed",
                                             "crown study: capsize speed"]
    for r in rows:
        assert r["scenario"] == "s" and r["note"].endswith(tail)
        assert (r["declared_difference"], r["why"]) == ("crown", "declared model difference")
    assert rows[1]["note"] == "in 0-10 m/s; none on both counts as agreement" + tail
