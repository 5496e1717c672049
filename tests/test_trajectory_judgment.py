"""Trajectory comparisons up to the meaningful horizon, on hand-made runs.

comparisons/convergence.py `error_vs_time` and `meaningful_horizon`, comparisons/
scenario_compare.py `trajectory_error` and `compare_forward`: synthetic `Run`s on the 0.01 s
output grid whose differences are placed exactly (before or after a horizon, on or off the
grid), so each expected number is known by construction of the input, not read from the code.
No engine runs.
"""

import numpy as np
import pytest

from comparisons.judgments.convergence import (Horizon, _verdict, error_vs_time, fit_order,
                                     meaningful_horizon)
from comparisons.judgments.scenario_compare import compare_forward, trajectory_error
from engines.runs import Run
from comparisons.judgments.tolerances import load_tolerances

DT = 0.01
THETA, GAMMA, YC = 3, 6, 1
TOLS = load_tolerances()
TRAJ_TOL = TOLS["trajectory"].tolerance      # 1e-6 absolute (rad or m), see tolerances.toml


def _motion(t):
    """A smooth reference motion (its values do not matter: only differences are judged)."""
    q = np.zeros((t.size, 8))
    q[:, 0] = 1.6 * t
    q[:, THETA] = 0.2 * np.sin(2 * t)
    q[:, GAMMA] = 0.1 * np.sin(3 * t)
    return q


def make_run(engine="reference", t_end=2.0, part_at=None, size=1e-2, coord=THETA, fall=None,
             t0=0.0):
    """A run of _motion on the grid t0, t0 + 0.01, ... to t_end; from ``part_at`` on,
    ``coord`` is off by ``size``; ``fall`` adds an event row off the grid at that time
    (status 'fell')."""
    t = np.round(np.arange(t0, t_end + DT / 2, DT), 10)
    if fall is not None:
        t = np.append(t[t < fall], fall)
    q = _motion(t)
    if part_at is not None:
        q[t >= part_at - 1e-12, coord] += size
    return Run(engine, "stability-psid10", "thesis", "forward",
               "fell" if fall is not None else "completed", "", 0.0, t, q, np.zeros_like(q))


def horizon(t):
    return Horizon(t, "separation", 1e-6, 0.0, (2.0, 2.0), f"test horizon at {t} s")


# -- error_vs_time and trajectory_error: cut at the horizon ---------------------------------

def test_error_vs_time_stops_at_the_horizon():
    ref, other = make_run(), make_run(part_at=1.5)
    err = error_vs_time(ref, other, coords=("theta",), horizon=1.0)
    assert err["t"][-1] == pytest.approx(1.0) and err["t"].size == 101
    assert err["theta"].max() == 0.0       # identical up to 1.0 s
    full = error_vs_time(ref, other, coords=("theta",))
    assert full["t"][-1] == pytest.approx(2.0)
    assert full["theta"].max() == pytest.approx(1e-2)   # the parting after the horizon


def test_event_rows_off_the_grid_are_not_compared():
    """A fall at 1.234 s ends the run with a row off the grid; only grid times are matched."""
    ref, other = make_run(), make_run(fall=1.234, part_at=1.234, size=1.0)
    err = error_vs_time(ref, other, coords=("theta",))
    assert err["t"][-1] == pytest.approx(1.23)
    assert err["theta"].max() == 0.0


def test_trajectory_error_names_the_first_coordinate_past_the_threshold():
    ref, other = make_run(), make_run(part_at=0.5, size=3e-6, coord=GAMMA)
    te = trajectory_error(ref, other, horizon=1.0)
    assert te.first == "gamma at 0.50 s"
    assert te.worst == pytest.approx(3e-6) and te.worst_coordinate == "gamma"
    assert te.t[-1] == pytest.approx(1.0)
    same = trajectory_error(ref, make_run(part_at=1.5), horizon=1.0)
    assert same.first == "-" and same.worst == 0.0


# -- compare_forward: the judged comparison (same integrator: Pinocchio) ------------------------

@pytest.mark.parametrize("part_at", [1.01, 1.5])   # the first grid time after it, and later
def test_runs_parting_only_after_the_horizon_pass(part_at):
    """Pinocchio parts from the reference by 1 cm after the 1.0 s horizon: past the horizon
    the reference itself is not reproducible, so this must not count."""
    ref, other = make_run(), make_run("pinocchio", part_at=part_at)
    (c,), te = compare_forward(None, ref, other, horizon(1.0), TOLS)
    assert c["passed"] is True and c["max_error"] == 0.0, c
    assert c["horizon"] == 1.0 and c["horizon_reason"] == "test horizon at 1.0 s"
    assert c["tolerance"] == TRAJ_TOL
    # the summary.json contract of a comparison entry
    assert {"quantity", "scenario", "model", "engines", "max_error", "tolerance", "passed",
            "localized_to", "horizon", "horizon_reason", "note"} <= set(c)
    assert (c["quantity"], c["scenario"], c["model"]) == ("trajectory", "stability-psid10",
                                                          "thesis")
    assert c["engines"] == ["reference", "pinocchio"] and "judged" in c["note"]
    assert te.t[-1] == pytest.approx(1.0)


@pytest.mark.parametrize("part_at", [0.3, 1.0])   # well inside, and at the horizon itself
def test_runs_parting_before_the_horizon_fail_and_say_where(part_at):
    ref, other = make_run(), make_run("pinocchio", part_at=part_at, size=1e-4, coord=YC)
    (c,), _ = compare_forward(None, ref, other, horizon(1.0), TOLS)
    assert c["passed"] is False and c["max_error"] == pytest.approx(1e-4), c
    assert c["localized_to"] == f"first past 1e-6: yc at {part_at:.2f} s; largest: yc"


def test_difference_below_the_tolerance_passes():
    """Within the horizon but below 1e-6: numerics, not a model difference."""
    ref, other = make_run(), make_run("pinocchio", part_at=0.3, size=0.5 * TRAJ_TOL)
    (c,), _ = compare_forward(None, ref, other, horizon(1.0), TOLS)
    assert c["passed"] is True and c["max_error"] == pytest.approx(0.5 * TRAJ_TOL)


def test_fixed_step_engine_is_reported_not_judged():
    """Exudyn's error is judged by its convergence order elsewhere: reported, passed None."""
    ref, other = make_run(), make_run("exudyn-tree", part_at=0.3, size=1e-3)
    (c,), _ = compare_forward(None, ref, other, horizon(1.0), TOLS, judged_by=None,
                              reported_because="its convergence order (the fixed-step study)")
    assert c["passed"] is None and c["tolerance"] is None
    assert c["max_error"] == pytest.approx(1e-3)
    assert "convergence order" in c["note"]


# -- meaningful_horizon: where two runs part ------------------------------------------------------

def test_horizon_is_the_grid_time_before_the_runs_part():
    twin = make_run(part_at=0.73, size=2e-6)
    h = meaningful_horizon(make_run(), twin)
    assert h.limited_by == "separation" and h.t == pytest.approx(0.72)
    assert h.separation_at_t == 0.0 and h.threshold == 1e-6
    assert h.end_times == (pytest.approx(2.0), pytest.approx(2.0))
    assert "0.73 s" in h.reason and "theta, gamma, xc, yc" in h.reason


def test_runs_already_apart_at_the_start_have_no_horizon_beyond_it():
    h = meaningful_horizon(make_run(), make_run(part_at=0.0, size=3e-6))
    assert h.limited_by == "separation" and h.t == 0.0
    assert h.separation_at_t == pytest.approx(3e-6) and h.threshold == 1e-6
    assert h.end_times == (pytest.approx(2.0), pytest.approx(2.0))
    assert "at the start" in h.reason


def test_horizon_watches_only_the_given_coordinates_at_the_given_threshold():
    twin = make_run(part_at=0.5, size=2e-6)           # theta parts at 0.5 s
    assert meaningful_horizon(make_run(), twin, coords=("gamma",)).limited_by == "end"
    assert meaningful_horizon(make_run(), twin, threshold=1e-5).limited_by == "end"
    with pytest.raises(ValueError, match="threshold must be positive"):
        meaningful_horizon(make_run(), twin, threshold=0.0)


def test_grids_need_not_start_at_zero():
    """Runs on 1.00, 1.01, ... s (and an event row at 1.234 s) are matched on that grid."""
    ref = make_run(t0=1.0)
    other = make_run(t0=1.0, fall=1.234, part_at=1.1, size=1e-3)
    err = error_vs_time(ref, other, coords=("theta",))
    np.testing.assert_allclose(err["t"], 1.0 + 0.01 * np.arange(24), rtol=0, atol=1e-12)
    assert err["theta"][:10].max() == 0.0 and err["theta"][10:].min() == pytest.approx(1e-3)
    # a reference of two samples still defines the grid
    two = make_run(t_end=0.01)
    assert error_vs_time(two, make_run(), coords=("theta",))["t"].size == 2


def test_horizon_ignores_coordinates_it_does_not_compare_and_tiny_differences():
    """The horizon watches theta, gamma, xc, yc (COMPARED) at 1e-6: a 1 mm change of the
    frame pitch beta, or 5e-7 in theta, does not end it; then it is the end of the shorter run."""
    twin = make_run(part_at=0.5, size=1e-3, coord=5)
    twin.q[make_run().t >= 0.2, THETA] += 5e-7
    h = meaningful_horizon(make_run(), twin)
    assert h.limited_by == "end" and h.t == pytest.approx(2.0)
    assert h.separation_at_t == pytest.approx(5e-7)


def test_horizon_ends_at_the_shorter_run():
    h = meaningful_horizon(make_run(), make_run(fall=1.234))
    assert h.limited_by == "end" and h.t == pytest.approx(1.23)
    assert h.end_times == (pytest.approx(2.0), pytest.approx(1.234))


# -- the convergence verdict's rules (the part of a convergence study that needs no engine) ----

def test_fit_order_with_two_steps_and_with_a_zero_error():
    assert fit_order([2e-3, 1e-3], [4e-6, 1e-6]) == (pytest.approx(2.0), pytest.approx(0.0,
                                                                                    abs=1e-9))
    assert np.isnan(fit_order([2e-3], [4e-6])[0])                   # one point: no line
    assert np.isnan(fit_order([2e-3, 1e-3], [4e-6, 0.0])[0])        # log(0)
    assert np.isnan(fit_order([2e-3, 1e-3], [4e-6, np.inf])[1])


@pytest.mark.parametrize("steps, verdict", [
    ((4e-3, 2e-3, 1e-3, 5e-4), "converges"),   # 4 steps over 8x
    ((4e-3, 1e-3, 5e-4), "converges"),         # 3 steps over 8x: enough
    ((2e-3, 1e-3, 5e-4), "inconclusive"),      # 3 steps over only 4x
    ((4e-3, 5e-4), "inconclusive"),            # 8x but 2 steps
])
def test_verdict_needs_three_steps_over_eightfold(steps, verdict):
    h = np.array(steps)
    e = 40.0 * h ** 2
    got, why = _verdict(h, e, fit_order(h, e)[0])
    assert got == verdict, why


def test_model_difference_reports_the_error_ratio():
    h = np.array([4e-3, 2e-3, 1e-3, 5e-4])
    e = np.array([0.052, 0.051, 0.0505, 0.05])
    got, why = _verdict(h, e, fit_order(h, e)[0])
    assert got == "model difference"
    assert "= 1.04 over 8x" in why and "5.00e-02" in why


# -- compare_forward's row, field by field (issue 24's mutation round) --------------------------

def test_an_error_exactly_at_the_tolerance_passes_and_is_not_past_the_threshold():
    """yc is 0 in the reference motion, so yc off by exactly 1e-6 gives an error of exactly
    1e-6: [trajectory]'s tolerance is the largest accepted error (tolerances.toml), and the
    threshold names what goes past it, not what reaches it."""
    assert TRAJ_TOL == 1e-6
    ref, other = make_run(), make_run("pinocchio", part_at=0.3, size=1e-6, coord=YC)
    (c,), te = compare_forward(None, ref, other, horizon(1.0), TOLS)
    assert c["max_error"] == 1e-6 and c["passed"] is True
    assert c["localized_to"] == "none past 1e-6; largest: yc"
    assert te.first == "-"
    # the errors themselves: (grid times, 8 coordinates), yc off from 0.3 s on
    assert te.errors.shape == (101, 8)
    assert np.all(te.errors[te.t >= 0.3 - 1e-12, YC] == 1e-6)
    assert np.all(te.errors[te.t < 0.3 - 1e-12] == 0.0)


def test_the_rows_note_and_why_say_who_judges_it():
    ref, other = make_run(), make_run("pinocchio", part_at=0.3, size=1e-3)
    (same,), _ = compare_forward(None, ref, other, horizon(1.0), TOLS)
    assert same["note"] == "same integrator and formulation as the reference: judged"
    assert same["why"] == "" and same["localized_to"] == "first past 1e-6: theta at 0.30 s; largest: theta"
    (own,), _ = compare_forward(None, ref, other, horizon(1.0), TOLS,
                                judged_by="trajectory_conformance")
    assert own["note"] == "its own integrator: judged by [trajectory_conformance]"
    assert own["tolerance"] == TOLS["trajectory_conformance"].tolerance and own["why"] == ""
    assert own["passed"] is True       # 1e-3 against 5e-2
    (rep,), _ = compare_forward(None, ref, other, horizon(1.0), TOLS, judged_by=None)
    assert rep["note"] == "reported here, judged by its convergence order"
    assert rep["why"] == "judged by its convergence order"


def test_thresholds_are_written_short():
    from comparisons.judgments.scenario_compare import _short
    assert (_short(1e-6), _short(2.5e-12), _short(1e6), _short(3e15)) == (
        "1e-6", "2e-12", "1e+6", "3e+15")


# -- the horizon's fields and words, and the study's plumbing (issue 24's mutation round) -------

def test_the_horizons_fields_and_reasons_written_out():
    """Separation: theta off by 3e-6 from 0.3 s (first past 1e-6 at 0.30 s): the horizon is
    0.29 s, where the separation is still 0. At the start: two sizes, 3e-6 then 4e-6 from
    0.01 s, so the start's 3e-6 is the one reported. Never past: the end of the shorter run."""
    h = meaningful_horizon(make_run(), make_run(part_at=0.3, size=3e-6))
    assert (h.t, h.separation_at_t, h.threshold) == (pytest.approx(0.29), 0.0, 1e-6)
    assert h.reason == ("the two runs separate by more than 1e-06 in theta, gamma, xc, yc at "
                        "t = 0.30 s (3.0e-06); the comparison stops at the grid time before")
    assert h.describe() == "horizon 0.29 s: " + h.reason
    # one sample before the parting is 2e-7 apart: that is the horizon's separation
    twin = make_run(part_at=0.3, size=3e-6)
    twin.q[make_run().t >= 0.28 - 1e-12, THETA] += 2e-7
    assert meaningful_horizon(make_run(), twin).separation_at_t == pytest.approx(2e-7)
    start = make_run(part_at=0.0, size=3e-6)
    start.q[start.t >= 0.01 - 1e-12, THETA] += 1e-6
    h = meaningful_horizon(make_run(), start, what="A and B")
    assert h.separation_at_t == pytest.approx(3e-6)
    assert h.reason == "A and B already differ by 3.0e-06 > 1e-06 at the start"
    h = meaningful_horizon(make_run(), make_run(fall=1.234, part_at=0.5, size=4e-7))
    assert (h.limited_by, h.threshold) == ("end", 1e-6)
    assert h.reason == ("the two runs stay within 1e-06 (max 4.0e-07) up to the end of the "
                        "shorter run (1.234 s; the last common grid time 1.23 s)")


def test_exactly_at_the_threshold_the_runs_have_not_parted():
    """yc is 0 in the reference motion: off by exactly 1e-6 it is at, not past, 1e-6."""
    h = meaningful_horizon(make_run(), make_run(part_at=0.3, size=1e-6, coord=YC))
    assert h.limited_by == "end" and h.separation_at_t == 1e-6


def test_unknown_coordinates_and_grids_without_common_times_are_refused():
    with pytest.raises(ValueError, match=r"unknown coordinate\(s\) \['roll'\]; choose from"):
        error_vs_time(make_run(), make_run(), coords=("theta", "roll"))
    with pytest.raises(ValueError, match="at least 2 samples"):
        error_vs_time(make_run(t_end=0.0), make_run())
    with pytest.raises(ValueError, match="share no output-grid time up to the horizon"):
        error_vs_time(make_run(t0=1.0), make_run(t0=1.0), horizon=0.5)
    # a sample a millionth of a step off the grid is not on it; a billionth of one is
    other = make_run()
    other.t[10] += 1e-6 * DT
    assert error_vs_time(make_run(), other, coords=("theta",))["t"].size == 200
    other.t[10] -= 1e-6 * DT - 1e-12 * DT
    assert error_vs_time(make_run(), other, coords=("theta",))["t"].size == 201


def test_the_perturbed_twin_and_the_cut_reference_run(thesis):
    import dataclasses

    from comparisons.judgments.convergence import (perturbed_scenario, reference_horizon,
                                                   reference_run)
    from reference_model.scenarios import SCENARIOS
    sc = SCENARIOS["stability-psid10"]
    twin = perturbed_scenario(sc, 1e-6)
    assert twin.name == "stability-psid10+dtheta1e-06"
    assert twin.dq_ind0 == (sc.dq_ind0[0] + 1e-6, *sc.dq_ind0[1:]) and twin.grid == sc.grid
    assert perturbed_scenario(sc).dq_ind0[0] == sc.dq_ind0[0] + 1e-9     # the default
    inverse = next(s for s in SCENARIOS.values() if s.kind != "forward")
    with pytest.raises(ValueError, match="is not a forward scenario"):
        perturbed_scenario(inverse)
    # the tight reference cut at 0.05 s: the grid's first six samples, DOP853 at 1e-11
    run = reference_run(thesis, sc, t_end=0.05)
    assert run.t.tolist() == pytest.approx([0.0, 0.01, 0.02, 0.03, 0.04, 0.05], abs=1e-12)
    assert (run.settings["rtol"], run.settings["atol"], run.settings["constraints"]) == (
        1e-11, 1e-12, "projection")
    assert reference_run(thesis, sc, t_end=0.0599).t.size == 6     # cut at the grid time before
    with pytest.raises(ValueError, match="fewer than 2 grid samples"):
        reference_run(thesis, sc, t_end=0.005)
    # the horizon of a 0.1 s scenario: 1e-9 rad/s apart never part by 1e-6 in 0.1 s; 1e-3
    # rad/s apart are 1e-5 rad apart at 0.01 s already
    short = dataclasses.replace(sc, grid=(0.0, 0.01, 11))
    ref = reference_run(thesis, short)
    h = reference_horizon(thesis, short, reference=ref)
    assert (h.limited_by, h.t) == ("end", pytest.approx(0.1))
    assert h.reason.startswith("two reference runs (rtol 1e-11) 1e-09 rad/s apart in "
                               "theta_dot(0) stay within 1e-06")
    h = reference_horizon(thesis, short, delta=1e-3, reference=ref)
    assert (h.limited_by, h.t) == ("separation", 0.0)


def test_the_engines_label_and_the_studys_numbers():
    from types import SimpleNamespace

    from comparisons.judgments.convergence import ConvergenceStudy, _engine_label
    lab = lambda s: _engine_label(SimpleNamespace(settings=s))  # noqa: E731  (a run's settings)
    assert lab({}) == "engine"
    assert lab({"integrator": "DOP853"}) == "DOP853"
    assert lab({"engine": "exudyn", "integrator": "x", "build": "tree", "contact": "disc",
                "solver_type": "GeneralizedAlpha", "spectral_radius": 0.8}) == \
        "exudyn tree (disc contact), GeneralizedAlpha rho_inf 0.8"
    assert lab({"engine": "exudyn", "solver_type": "TrapezoidalIndex2"}) == \
        "exudyn, TrapezoidalIndex2"
    s = ConvergenceStudy("sc", "eng", "ref", ("theta",), (4e-3, 2e-3, 1e-3), (1.6e-5, 4e-6, 1e-6),
                         (1.6e-5, 4e-6, 1e-6), ("theta",) * 3, 2.0, 0.0, 2.0, 0.5, "given",
                         ("completed",) * 3, "converges", "why")
    assert s.ratios == pytest.approx((4.0, 4.0), rel=1e-12)
    assert s.difference == 1e-6                     # the error at the smallest step
    assert s.describe() == ("eng vs ref, sc up to 0.50 s: max error in theta by step "
                            "{0.004: 1.60e-05, 0.002: 4.00e-06, 0.001: 1.00e-06}, fitted order "
                            "2.00 -> converges (why)")
