"""The convergence study's edges (comparisons/judgments/convergence.py), on synthetic runs whose
errors and separations are set by hand: the output grid of runs that do not start at 0, samples
just off the grid, horizons just short of a grid time, the separation rule's boundaries, every
verdict's precondition, and every field of the study and the horizon. Written from the
survivors of `make mutants` on the module (each test names the kind of bug it kills); the
expected values are the definitions in the module's docstrings, computed here by hand.

Two tests run the reference (0.05 s and 0.3 s of stability-psid10 on thesis-disc, DOP853 with
projection): together about 1 s.
"""

import dataclasses

import numpy as np
import pytest

from comparisons.judgments.convergence import (COMPARED, HORIZON_THRESHOLD, MIN_SPAN,
                                               ORDER_BAND, convergence_study, error_vs_time,
                                               fit_order, meaningful_horizon,
                                               perturbed_scenario, reference_horizon,
                                               reference_run)
from reference_model import COORDINATES, load_model
from reference_model.scenarios import SCENARIOS
from reference_model.solvers import Trajectory

THETA, GAMMA, PSI = (COORDINATES.index(c) for c in ("theta", "gamma", "psi"))


def _traj(t, q=None, status="completed", settings=None):
    t = np.asarray(t, dtype=float)
    q = np.zeros((t.size, 8)) if q is None else np.asarray(q, dtype=float)
    z = np.zeros((t.size, 5))
    return Trajectory(t=t, q=q, dq=np.zeros_like(q), ddq=np.zeros_like(q), C=z,
                      T=np.zeros((t.size, 3)), status=status, message="", t_end=float(t[-1]),
                      settings=dict(settings or {}))


class _Offset:
    """An 'engine' whose run is ``ref`` plus ``error`` in theta (and ``error/2`` in psi, not a
    compared coordinate, unless ``psi`` says otherwise)."""

    def __init__(self, ref, error, settings=None, psi=None, coord=THETA, whole=False):
        self.ref, self.error, self.psi, self.coord, self.whole = ref, error, psi, coord, whole
        self.settings = {"engine": "fake"} if settings is None else settings

    def simulate(self, scenario, t_end=None):
        k = self.ref.t <= (np.inf if self.whole else t_end) + 1e-12
        q = self.ref.q[k].copy()
        q[:, self.coord] += self.error
        q[:, PSI] += self.error / 2 if self.psi is None else self.psi
        return dataclasses.replace(self.ref, t=self.ref.t[k], q=q, dq=self.ref.dq[k],
                                   t_end=float(self.ref.t[k][-1]), settings=self.settings)


def _study(errors_of_h, steps, *, settings=None, horizon=0.5, psi=None, **kw):
    t = 0.01 * np.arange(101)
    ref = _traj(t, settings={"integrator": "exact", "rtol": 1e-13, "constraints": "none"})
    return convergence_study(load_model("thesis-disc"),
                             lambda h: _Offset(ref, errors_of_h(h), settings, psi),
                             SCENARIOS["stability-psid10"], steps=steps, horizon=horizon,
                             reference=ref, **kw)


# -- the output grid ---------------------------------------------------------------------------

def test_the_common_grid_of_runs_that_start_after_zero():
    """A grid starting at t0 = 1.5 s (dt 0.01): the times are t0 + k dt, not k dt or
    (t - t0) computed as (t + t0). Planted: t + t0 in the grid keys, or dt = t1 + t0."""
    t = 1.5 + 0.01 * np.arange(11)
    q = np.zeros((11, 8))
    q[:, THETA] = np.arange(11.0)
    err = error_vs_time(_traj(t), _traj(t[3:], q[3:]))
    np.testing.assert_allclose(err["t"], t[3:], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(err["theta"], np.arange(3.0, 11.0))


def test_a_sample_a_nanosecond_off_the_grid_is_not_compared():
    """On the grid means within 1e-9 dt (1e-11 s at dt = 0.01 s): a row 1e-9 s off it (an
    event row, say) is left out, a row 1e-13 s off is kept. Planted: 1e-9 / dt (1e-7 s)."""
    t = 0.01 * np.arange(6)
    off = t.copy()
    off[4] += 1e-9
    off[2] += 1e-13
    err = error_vs_time(_traj(t), _traj(off))
    np.testing.assert_allclose(err["t"], t[[0, 1, 2, 3, 5]], rtol=0, atol=1e-15)


def test_a_horizon_just_short_of_a_grid_time_leaves_it_out():
    """The horizon includes a grid time within 1e-9 dt of it and no more: 0.03 - 1e-9 stops at
    0.02; 0.03 - 1e-13 keeps 0.03. Planted: the tolerance as 1e-9 / dt."""
    t = 0.01 * np.arange(6)
    assert error_vs_time(_traj(t), _traj(t), horizon=0.03 - 1e-9)["t"][-1] == pytest.approx(0.02)
    assert error_vs_time(_traj(t), _traj(t), horizon=0.03 - 1e-13)["t"][-1] == pytest.approx(0.03)


def test_two_samples_make_a_grid_one_does_not():
    two = _traj([0.0, 0.01])
    assert error_vs_time(two, two)["t"].size == 2
    with pytest.raises(ValueError, match="^the reference trajectory needs at least 2 samples to "
                                         "define its grid$"):
        error_vs_time(_traj([0.0]), two)


def test_runs_that_share_no_grid_time_are_refused():
    with pytest.raises(ValueError, match="^the two trajectories share no output-grid time up to "
                                         "the horizon$"):
        error_vs_time(_traj([0.0, 0.01, 0.02]), _traj([0.005, 0.015]))
    with pytest.raises(ValueError, match="share no output-grid time"):
        error_vs_time(_traj([1.0, 1.01]), _traj([1.0, 1.01]), horizon=0.5)


def test_an_unknown_coordinate_is_named_with_the_choices():
    t = _traj([0.0, 0.01])
    with pytest.raises(ValueError, match=r"unknown coordinate\(s\) \['lean'\]; choose from") as e:
        error_vs_time(t, t, coords=("theta", "lean"))
    assert "theta" in str(e.value) and "gamma" in str(e.value)


# -- the meaningful horizon --------------------------------------------------------------------

def _apart(sep_theta, t=None):
    """Two runs on 0.01 k whose theta differ by ``sep_theta[k]``."""
    sep_theta = np.asarray(sep_theta, dtype=float)
    t = 0.01 * np.arange(sep_theta.size) if t is None else t
    q = np.zeros((t.size, 8))
    q[:, THETA] = sep_theta
    return _traj(t), _traj(t, q)


def test_runs_apart_at_the_start_end_the_horizon_there():
    a, b = _apart([2e-6, 3e-6, 4e-6])
    hz = meaningful_horizon(a, b, threshold=1e-6, what="A and B")
    assert (hz.t, hz.limited_by, hz.threshold, hz.separation_at_t) == (0.0, "separation", 1e-6, 2e-6)
    assert hz.end_times == (0.02, 0.02)
    assert hz.reason == "A and B already differ by 2.0e-06 > 1e-06 at the start"


def test_runs_that_part_at_the_second_sample_stop_at_the_first():
    """k = 1: the horizon is t[0] with the separation there (not the start's message)."""
    a, b = _apart([1e-7, 5e-6, 6e-6])
    hz = meaningful_horizon(a, b, threshold=1e-6)
    assert (hz.t, hz.limited_by, hz.threshold, hz.separation_at_t) == (0.0, "separation", 1e-6, 1e-7)
    assert hz.reason.startswith("the two runs separate by more than 1e-06 in theta, gamma, xc, yc "
                                "at t = 0.01 s (5.0e-06)")


def test_a_separation_equal_to_the_threshold_is_not_past_it():
    """'differ by more than the threshold': exactly 0.5 is still within 0.5 (the grid time
    before the first sample past it, with its own separation). Planted: >=."""
    a, b = _apart([0.0, 0.25, 0.5, 0.75, 1.0])
    hz = meaningful_horizon(a, b, threshold=0.5)
    assert hz.t == pytest.approx(0.02) and hz.separation_at_t == 0.5 and "0.03 s" in hz.reason


def test_runs_that_never_part_end_at_the_shorter_run():
    a, b = _apart([0.0, 1e-8, 3e-8, 2e-8])
    b = dataclasses.replace(b, t_end=0.035)
    hz = meaningful_horizon(a, b, threshold=1e-6)
    assert (hz.t, hz.limited_by, hz.threshold, hz.separation_at_t) == (0.03, "end", 1e-6, 2e-8)
    assert hz.end_times == (0.03, 0.035)
    assert "max 3.0e-08" in hz.reason and "(0.030 s; the last common grid time 0.03 s)" in hz.reason


def test_the_horizon_reads_only_the_coordinates_it_is_given():
    """A separation in psi alone ends nothing by default (psi is not compared) and ends the
    horizon when psi is asked for. Planted: the coordinates not passed on."""
    t = 0.01 * np.arange(4)
    q = np.zeros((4, 8))
    q[2:, PSI] = 1.0
    a, b = _traj(t), _traj(t, q)
    assert meaningful_horizon(a, b, threshold=1e-6).limited_by == "end"
    hz = meaningful_horizon(a, b, threshold=1e-6, coords=("psi",))
    assert hz.limited_by == "separation" and hz.t == pytest.approx(0.01) and "in psi at" in hz.reason


def test_the_threshold_must_be_positive():
    a, b = _apart([0.0, 0.0])
    with pytest.raises(ValueError, match="threshold must be positive; got 0"):
        meaningful_horizon(a, b, threshold=0.0)


def test_the_twin_scenario_adds_to_the_initial_lean_rate():
    sc = dataclasses.replace(SCENARIOS["stability-psid10"],
                             dq_ind0=(0.25,) + tuple(SCENARIOS["stability-psid10"].dq_ind0[1:]))
    twin = perturbed_scenario(sc, 1e-3)
    assert twin.dq_ind0[0] == 0.25 + 1e-3 and twin.dq_ind0[1:] == sc.dq_ind0[1:]
    assert twin.name == "stability-psid10+dtheta0.001"
    with pytest.raises(ValueError, match="'zigzag' is not a forward scenario"):
        perturbed_scenario(SCENARIOS["zigzag"])


# -- the reference ---------------------------------------------------------------------------

def test_the_reference_is_cut_at_t_end_projected_at_the_asked_tolerance():
    """0.05 s of stability-psid10 on thesis-disc: six samples (0 to 0.05 s), DOP853 at the
    rtol asked for, with projection. On a grid that starts at 1 s, t_end = 1.05 s gives the same
    six samples (the cut counts from the grid's start). Planted: t_end + start, one sample
    more, rtol or projection not passed."""
    disc, sc = load_model("thesis-disc"), SCENARIOS["stability-psid10"]
    ref = reference_run(disc, sc, rtol=1e-9, atol=1e-10, t_end=0.05)
    np.testing.assert_allclose(ref.t, 0.01 * np.arange(6), atol=1e-12)
    assert ref.settings["rtol"] == 1e-9 and ref.settings["atol"] == 1e-10
    assert ref.settings["constraints"] == "projection"
    start, step, n = sc.grid
    late = dataclasses.replace(sc, grid=(1.0, step, n))
    assert reference_run(disc, late, t_end=1.05).t.size == 6
    with pytest.raises(ValueError, match="t_end = 0.005 leaves fewer than 2 grid samples"):
        reference_run(disc, sc, t_end=0.005)


def test_the_reference_horizon_compares_the_given_reference_with_its_twin():
    """A given reference that is the true one plus 1e-3 rad in theta from 0.1 s on parts from
    the twin at 0.1 s: the horizon is 0.09 s, so the given run was used (not a fresh one), and
    the reason names the rtol. Planted: the given reference ignored, the rtol not passed."""
    disc = load_model("thesis-disc")
    sc = dataclasses.replace(SCENARIOS["stability-psid10"],
                             grid=(0.0, 0.01, 31))          # 0.3 s: fast
    true = reference_run(disc, sc, rtol=1e-10)
    q = true.q.copy()
    q[true.t >= 0.1 - 1e-12, THETA] += 1e-3
    hz = reference_horizon(disc, sc, rtol=1e-10, reference=dataclasses.replace(true, q=q))
    assert hz.limited_by == "separation" and hz.t == pytest.approx(0.09)
    assert hz.threshold == HORIZON_THRESHOLD
    assert "two reference runs (rtol 1e-10) 1e-09 rad/s apart in theta_dot(0)" in hz.reason
    free = reference_horizon(disc, sc, rtol=1e-10, reference=true)
    assert free.limited_by == "end" and free.t == pytest.approx(0.3)


# -- fitting and verdicts ----------------------------------------------------------------------

def test_two_steps_are_enough_for_a_fitted_line():
    order, intercept = fit_order([2e-3, 1e-3], [4e-6, 1e-6])
    assert order == pytest.approx(2.0, abs=1e-12) and np.exp(intercept) == pytest.approx(1.0)
    assert np.isnan(fit_order([1e-3], [1e-6])[0])


@pytest.mark.parametrize("errors", [[1.0, np.inf, 1.0], [1.0, np.nan, 1.0], [1.0, 0.0, 1.0],
                                    [1.0, -1.0, 1.0]])
def test_no_line_through_an_error_that_has_no_log(errors):
    """Zero, negative, infinite or NaN errors: (nan, nan), never a number, never a warning."""
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        order, intercept = fit_order([4e-3, 2e-3, 1e-3], errors)
    assert np.isnan(order) and np.isnan(intercept)


def test_a_verdict_needs_three_steps_and_an_eight_fold_span():
    """Two steps spanning 8x, and four spanning 4x, are inconclusive with the reason; three
    spanning 8x exactly reach a verdict. Planted: 'or' as 'and', 3 as 4, the span's margin
    lost."""
    two = _study(lambda h: 40.0 * h ** 2, (8e-3, 1e-3))
    assert two.verdict == "inconclusive" and "2 steps spanning 8x" in two.verdict_reason
    narrow = _study(lambda h: 40.0 * h ** 2, (4e-3, 2e-3, 1.5e-3, 1e-3))
    assert narrow.verdict == "inconclusive" and f"spanning >= {MIN_SPAN:g}x" in narrow.verdict_reason
    three = _study(lambda h: 40.0 * h ** 2, (4e-3, 2e-3, 5e-4))
    assert three.verdict == "converges", three.verdict_reason
    assert f"in [{ORDER_BAND[0]}, {ORDER_BAND[1]}]" in three.verdict_reason
    assert "at h = 0.0005" in three.verdict_reason


def test_a_zero_error_gives_no_order_and_says_so():
    s = _study(lambda h: 0.0 if h < 1e-3 else 40.0 * h ** 2, (4e-3, 2e-3, 1e-3, 5e-4))
    assert s.verdict == "inconclusive"
    assert s.verdict_reason == "an error is zero or not finite: no order can be fitted"


def test_a_model_difference_reports_the_ratio_of_its_errors():
    """error(h_max) / error(h_min) for an offset plus a small first-order part: computed here."""
    steps = (4e-3, 2e-3, 1e-3, 5e-4)
    s = _study(lambda h: 0.05 + h, steps)
    assert s.verdict == "model difference"
    ratio = (0.05 + 4e-3) / (0.05 + 5e-4)
    assert f"error(h_max)/error(h_min) = {ratio:.3g} over 8x in h" in s.verdict_reason


# -- the study's fields --------------------------------------------------------------------------

def test_every_field_of_a_study_on_synthetic_runs():
    """Errors over the compared coordinates and over all eight (psi carries twice the theta
    error, so errors_all is twice errors), the worst coordinate, the horizon and its reason,
    the statuses, the engine and reference labels."""
    steps = (4e-3, 2e-3, 1e-3, 5e-4)
    settings = {"engine": "toy", "build": "tree", "contact": "disc", "solver_type": "GA",
                "spectral_radius": 0.9}
    s = _study(lambda h: 40.0 * h ** 2, steps, settings=settings, horizon=0.3,
               psi=None)
    expect = tuple(40.0 * h ** 2 for h in steps)
    np.testing.assert_allclose(s.errors, expect, rtol=1e-12)
    np.testing.assert_allclose(s.errors_all, expect, rtol=1e-12)   # psi's is half: theta's wins
    assert s.worst == ("theta",) * 4 and s.coordinates == COMPARED
    assert s.horizon == pytest.approx(0.3) and s.horizon_reason == "given"
    assert s.statuses == ("completed",) * 4
    assert s.engine == "toy tree (disc contact), GA rho_inf 0.9"
    assert s.reference == "reference thesis-disc (disc contact), exact rtol 1e-13, none"
    assert s.order_all == pytest.approx(2.0, abs=1e-9)


def test_errors_all_reads_the_coordinates_that_are_not_compared():
    steps = (4e-3, 2e-3, 1e-3, 5e-4)
    s = _study(lambda h: 40.0 * h ** 2, steps, psi=0.25)
    np.testing.assert_allclose(s.errors_all, (0.25,) * 4)
    assert np.all(np.asarray(s.errors) < 1e-3) and s.order_all == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("settings, label", [
    ({"integrator": "DOP853"}, "DOP853"),
    ({}, "engine"),
    ({"engine": "e", "solver_type": "RK4"}, "e, RK4"),
    ({"engine": "e", "contact": "thesis"}, "e (thesis contact)"),
])
def test_the_engine_label_says_what_the_settings_say(settings, label):
    s = _study(lambda h: 40.0 * h ** 2, (4e-3, 2e-3, 1e-3, 5e-4), settings=settings)
    assert s.engine == label


def test_runs_that_end_early_cut_every_step_to_the_earliest_end():
    """One run falls at 0.2 s: every step is judged up to 0.2 s, and the reason says so."""
    t = 0.01 * np.arange(101)
    ref = _traj(t, settings={"integrator": "exact", "rtol": 1e-13, "constraints": "none"})

    class Early(_Offset):
        def simulate(self, scenario, t_end=None):
            run = super().simulate(scenario, t_end=0.2 if self.error < 1e-4 else t_end)
            return dataclasses.replace(run, status="fell")

    s = convergence_study(load_model("thesis-disc"), lambda h: Early(ref, 40.0 * h ** 2),
                          SCENARIOS["stability-psid10"], steps=(4e-3, 2e-3, 1e-3, 5e-4),
                          horizon=0.5, reference=ref)
    assert s.horizon == pytest.approx(0.2)
    assert s.horizon_reason == "given; cut to 0.20 s, the last grid time every run reached"
    full = _study(lambda h: 40.0 * h ** 2, (4e-3, 2e-3, 1e-3, 5e-4))
    assert full.horizon_reason == "given"


def test_the_steps_must_be_two_or_more_and_positive():
    for steps in ((1e-3,), (1e-3, 0.0), (1e-3, -1e-3)):
        with pytest.raises(ValueError, match=r"steps must be >= 2 positive time steps; got"):
            _study(lambda h: h, steps)


def test_runs_given_must_match_the_steps():
    t = 0.01 * np.arange(11)
    ref = _traj(t)
    with pytest.raises(ValueError, match="1 runs given for 2 steps"):
        convergence_study(load_model("thesis-disc"), None, SCENARIOS["stability-psid10"],
                          steps=(2e-3, 1e-3), horizon=0.1, reference=ref, runs=[ref])


def test_a_study_without_a_reference_runs_one_to_its_horizon():
    """No reference given: the study runs it (projection, the asked rtol) up to the horizon,
    and an engine equal to it has errors at the reference's own size. Planted: the reference
    not run, or run at another rtol."""
    disc, sc = load_model("thesis-disc"), SCENARIOS["stability-psid10"]
    ref = reference_run(disc, sc, rtol=1e-9, t_end=0.05)
    s = convergence_study(disc, lambda h: _Offset(ref, 0.0, psi=0.0), sc, steps=(2e-3, 1e-3),
                          horizon=0.05, reference_rtol=1e-9)
    assert "rtol 1e-09, projection" in s.reference
    assert max(s.errors) < 1e-12 and s.horizon == pytest.approx(0.05)


def _exact(errors, steps, **kw):
    """A study whose runs are given, each offset in theta by exactly ``errors[i]`` from a zero
    reference: the errors are those floats exactly (|e - 0|)."""
    t = 0.01 * np.arange(51)
    ref = _traj(t, settings={"integrator": "exact", "rtol": 1e-13, "constraints": "none"})
    runs = []
    for e in errors:
        q = np.zeros((t.size, 8))
        q[:, THETA] = e
        runs.append(_traj(t, q, settings={"engine": "given"}))
    return convergence_study(load_model("thesis-disc"), None, SCENARIOS["stability-psid10"],
                             steps=steps, horizon=0.5, reference=ref, runs=runs, **kw)


STEPS = (4e-3, 2e-3, 1e-3, 5e-4)


def test_an_error_exactly_at_the_convergence_bound_is_not_below_it():
    """Order 2 with 1e-3 exactly at the smallest step: 'converges' needs the error below 1e-3,
    so this is inconclusive; 1e-8 exactly (the reference's floor) is not below the floor, so
    that one converges. Planted: <= for < on either bound."""
    s = _exact((1.6e-2, 4e-3, 1e-3, 2.5e-4), STEPS)
    assert s.verdict == "converges"
    at = _exact((6.4e-2, 1.6e-2, 4e-3, 1e-3), STEPS)
    assert at.verdict == "inconclusive" and "still 1.0e-03 >= 1e-03" in at.verdict_reason
    floor = _exact((6.4e-7, 1.6e-7, 4e-8, 1e-8), STEPS)
    assert floor.verdict == "converges", floor.verdict_reason


def test_the_ratio_reads_the_largest_step_wherever_it_is_listed():
    """Steps listed smallest first: error(h_max) is the last error, not the first. Planted:
    argmax of nothing (index 0)."""
    steps = tuple(reversed(STEPS))
    s = _exact((0.0505, 0.051, 0.052, 0.054), steps)
    assert s.verdict == "model difference"
    assert f"= {0.054 / 0.0505:.3g} over 8x in h" in s.verdict_reason
    assert s.verdict_reason.endswith("not the integrator's error")


def test_the_worst_coordinate_is_the_one_with_the_largest_error():
    s = _study(lambda h: 40.0 * h ** 2, STEPS, psi=0.0)
    assert s.worst == ("theta",) * 4
    t = 0.01 * np.arange(101)
    ref = _traj(t, settings={"integrator": "exact", "rtol": 1e-13, "constraints": "none"})
    g = convergence_study(load_model("thesis-disc"),
                          lambda h: _Offset(ref, 40.0 * h ** 2, psi=0.0, coord=GAMMA),
                          SCENARIOS["stability-psid10"], steps=STEPS, horizon=0.5, reference=ref)
    assert g.worst == ("gamma",) * 4


def test_the_engine_is_named_after_its_first_run():
    """Settings that name the step: the study's engine is the first step's."""
    t = 0.01 * np.arange(101)
    ref = _traj(t, settings={"integrator": "exact", "rtol": 1e-13, "constraints": "none"})
    s = convergence_study(load_model("thesis-disc"),
                          lambda h: _Offset(ref, 40.0 * h ** 2, settings={"engine": f"h{h:g}"}),
                          SCENARIOS["stability-psid10"], steps=STEPS, horizon=0.5, reference=ref)
    assert s.engine == "h0.004"


def test_a_run_past_the_horizon_is_judged_up_to_the_horizon_only():
    """An engine that ignores t_end and runs the whole second: the study still compares up to
    its 0.3 s horizon (planted: the horizon not passed when finding the common end or the
    rows)."""
    t = 0.01 * np.arange(101)
    ref = _traj(t, settings={"integrator": "exact", "rtol": 1e-13, "constraints": "none"})
    q = np.zeros((101, 8))
    q[t > 0.3 + 1e-9, THETA] = 1.0                  # a large error after the horizon only

    class Late(_Offset):
        def simulate(self, scenario, t_end=None):
            run = super().simulate(scenario, t_end)
            return dataclasses.replace(run, q=run.q + q)

    s = convergence_study(load_model("thesis-disc"),
                          lambda h: Late(ref, 40.0 * h ** 2, whole=True),
                          SCENARIOS["stability-psid10"], steps=STEPS, horizon=0.3, reference=ref)
    assert s.horizon == pytest.approx(0.3) and s.horizon_reason == "given"
    np.testing.assert_allclose(s.errors, [40.0 * h ** 2 for h in STEPS], rtol=1e-12)


def test_a_reference_without_settings_is_labelled_with_question_marks():
    t = 0.01 * np.arange(101)
    s = convergence_study(load_model("thesis-disc"), lambda h: _Offset(_traj(t), 40.0 * h ** 2),
                          SCENARIOS["stability-psid10"], steps=STEPS, horizon=0.5,
                          reference=_traj(t))
    assert s.reference == "reference thesis-disc (disc contact), ? rtol nan, ?"


SHORT = dataclasses.replace(SCENARIOS["stability-psid10"], grid=(0.0, 0.01, 31))   # 0.3 s


def test_without_a_horizon_the_study_finds_the_reference_s_own():
    """No horizon, no reference: the study runs the reference at the rtol asked for, then its
    twin, and compares up to where they part or end (0.3 s here: the twins stay within 1e-6);
    the engine's errors are those planted on the same reference. Planted: the reference, its
    rtol, the model or the scenario not passed on; the horizon not read."""
    disc = load_model("thesis-disc")
    ref = reference_run(disc, SHORT, rtol=1e-10)
    s = convergence_study(disc, lambda h: _Offset(ref, 40.0 * h ** 2, psi=0.0), SHORT,
                          steps=STEPS, reference_rtol=1e-10)
    assert s.horizon == pytest.approx(0.3)
    assert s.horizon_reason.startswith("two reference runs (rtol 1e-10) 1e-09 rad/s apart")
    assert "rtol 1e-10, projection" in s.reference
    np.testing.assert_allclose(s.errors, [40.0 * h ** 2 for h in STEPS], rtol=1e-9)
    assert s.verdict == "converges"


def test_the_reference_horizon_runs_both_twins_at_the_asked_tolerance():
    """With no reference given: twins 0 rad/s apart at the same rtol are the same run (they
    never part, even at a 1e-13 threshold); 1e-9 rad/s apart they part above 1e-13 at once.
    Planted: the reference or its twin at the default rtol (they then differ by the tolerance),
    the threshold not passed on."""
    disc = load_model("thesis-disc")
    same = reference_horizon(disc, SHORT, delta=0.0, threshold=1e-13, rtol=1e-9)
    assert same.limited_by == "end" and same.separation_at_t == 0.0
    apart = reference_horizon(disc, SHORT, delta=1e-9, threshold=1e-13, rtol=1e-9)
    assert apart.limited_by == "separation" and apart.t < 0.3
