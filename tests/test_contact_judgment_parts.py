"""comparisons/judgments/contact.py, the parts tests/test_contact.py leaves open: the edges of
the horizon's window and of error_at's grid-time check (a billionth of a step, on grids that
do not start at 0, of two samples and of one), the refinement verdict's thresholds hit
exactly (3 values over 4x, a span a billionth short of 8x, a finest error of exactly 1e-8,
a fitted order of exactly 0.5), diagnostics in float32 or missing from an older trajectory
object, the messages and fields a reader sees, and local orders without warnings.

Expected values: the module's docstrings (the thresholds MIN_SPAN = 8, REFERENCE_FLOOR =
1e-8, NO_SHRINK_ORDER = 0.5 of comparisons/judgments/convergence.py, the window's and the
grid check's round-off of 1e-9 of a step), times and errors chosen exactly representable in
binary so each boundary is hit exactly, and RMS values worked by hand. Each test names the
planted bugs (mutmut's survivors of the module's measurement) it was seen failing on.
~0.2 s."""

from __future__ import annotations

import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

from comparisons.judgments.contact import (contact_fidelity, declared_difference_rows,
                                           error_at, lift_off_time, local_orders,
                                           refinement_study)
from comparisons.judgments.convergence import Horizon
from engines.runs import Run
from reference_model.solvers import Trajectory

#: a grid that starts at 1 s, step 1/64 s (every time exact in binary)
DT = 1.0 / 64
T1 = 1.0 + np.arange(41) * DT
#: test_contact.py's grid: 0 .. 1 s on 0.01 s
T0 = np.round(np.arange(0, 101) * 0.01, 12)


def _traj(t, q=None, diagnostics=None):
    t = np.asarray(t, dtype=float)
    q = np.zeros((t.size, 8)) if q is None else np.asarray(q, dtype=float)
    z = np.zeros_like(q)
    return Trajectory(t=t, q=q, dq=z, ddq=z, C=np.zeros((t.size, 5)), T=np.zeros((t.size, 3)),
                      status="completed", message="", t_end=float(t[-1]),
                      diagnostics={} if diagnostics is None else diagnostics)


def _diag(n, slip_rear=None, pen_front=None, dtype=float):
    zero = np.zeros(n, dtype=dtype)
    return {"slip_speed_rear": zero if slip_rear is None else slip_rear,
            "slip_speed_front": zero, "penetration_rear": zero,
            "penetration_front": zero if pen_front is None else pen_front}


def _spike(t, k, value=5.0):
    slip = np.zeros(t.size)
    slip[k] = value
    return _traj(t, diagnostics=_diag(t.size, slip_rear=slip))


REF1 = _traj(T1)


def test_the_window_reaches_a_billionth_of_a_step_past_the_horizon_on_a_grid_from_1_s():
    """A slip spike at t_k = 1.3125 s (sample 20 of a 1/64 s grid from 1 s): a horizon
    0.5e-9 steps before t_k still includes it (round-off), 1.5e-9 steps before does not; at
    exactly one billionth (horizon + 1e-9 dt == t_k in binary) it is included.
    Planted: the step read as t1 + t0 or t2 - t0 or t1 - t1 (0) or always 1 s, the slack
    1e-9 / dt, '<' for '<='."""
    k = 20
    tk = T1[k]
    run = _spike(T1, k)
    assert contact_fidelity(REF1, run, horizon=tk - 0.5e-9 * DT).slip_max == 5.0
    assert contact_fidelity(REF1, run, horizon=tk - 1.5e-9 * DT).slip_max == 0.0
    exact = tk - 1e-9 * DT
    assert exact + 1e-9 * DT == tk                 # the boundary is hit exactly
    assert contact_fidelity(REF1, run, horizon=exact).slip_max == 5.0


def test_a_two_sample_run_takes_its_step_from_its_two_samples():
    """A run of two samples (1 s and 1 + 1/64 s), the spike on the second: a horizon 1.5e-9
    of its step before it leaves it out. Planted: a run needing more than 2 samples for its
    step (1 s taken: the spike included)."""
    run = _spike(T1[:2], 1)
    assert contact_fidelity(REF1, run, horizon=T1[1] - 1.5e-9 * DT).slip_max == 0.0
    assert contact_fidelity(REF1, run, horizon=T1[1]).slip_max == 5.0


def test_a_one_sample_runs_window_allows_a_billionth_of_a_second():
    """A run of one sample has no step: its round-off allowance is 1e-9 of 1 s, so a horizon
    1.5 ns before its sample leaves it with nothing. Planted: 2 s taken for the step (the
    sample included, the error check failing later with another message)."""
    one = _spike(T1[:1], 0, value=2e-3)
    with pytest.raises(ValueError, match=r"^the run has no sample up to the horizon "):
        contact_fidelity(REF1, one, horizon=1.0 - 1.5e-9)


def test_error_at_accepts_a_grid_time_to_a_billionth_of_a_step_on_a_grid_from_1_s():
    """error_at at t_k + 0.5e-9 dt is the error at t_k (round-off); at t_k + 1.5e-9 dt it is
    no grid time. On test_contact's grid from 0, a time of exactly 1e-9 dt is the sample at 0
    (the boundary included). Planted: dt read as t1 + t0, t2 - t0, t1 - t1 (0); the allowance
    1e-9 / dt; '>=' for '>'."""
    q = np.zeros((T1.size, 8))
    q[:, 1] = 0.25
    run = _traj(T1, q)
    tk = T1[20]
    assert error_at(REF1, run, tk + 0.5e-9 * DT) == 0.25
    with pytest.raises(ValueError, match=r"^the runs share no output-grid sample at t = "):
        error_at(REF1, run, tk + 1.5e-9 * DT)
    ref0 = _traj(T0)
    q0 = np.zeros((T0.size, 8))
    q0[:, 1] = 0.5
    dt0 = float(T0[1] - T0[0])
    assert error_at(ref0, _traj(T0, q0), 1e-9 * dt0) == 0.5


def _constant(error, t=T0):
    """A run whose yc is off by ``error`` at every sample: its error at any time is it."""
    q = np.zeros((t.size, 8))
    q[:, 1] = error
    return _traj(t, q)


REF0 = _traj(T0)


def test_three_values_over_4x_and_two_over_16x_are_too_narrow_or_too_few():
    """Both conditions of the judged study are needed: >= 3 values AND a span >= 8x.
    Planted: 'and' for 'or' (3 values over 4x judged), the span test made void
    (MIN_SPAN (1 - 1.000000001) < 0)."""
    s = refinement_study(REF0, [(v, _constant(v)) for v in (4.0, 2.0, 1.0)], "h", 0.3)
    assert (s.verdict, s.verdict_reason) == ("inconclusive",
                                             "3 values spanning 4x; need >= 3 spanning >= 8x")
    s = refinement_study(REF0, [(v, _constant(v)) for v in (16.0, 1.0)], "h", 0.3)
    assert (s.verdict, s.verdict_reason) == ("inconclusive",
                                             "2 values spanning 16x; need >= 3 spanning >= 8x")


def test_a_span_a_billionth_short_of_8x_is_8x():
    """The span is compared with 8x less a billionth (round-off of the values' ratio): a
    span of exactly 8 (1 - 1e-9) is judged. Planted: '<=' for '<' (inconclusive)."""
    top = 8 * (1 - 1e-9)
    s = refinement_study(REF0, [(v, _constant(v)) for v in (top, 2.0, 1.0)], "h", 0.3)
    assert s.span == top
    assert s.verdict == "approaches ideal rolling"


def test_a_finest_error_of_exactly_the_floor_is_judged():
    """Errors 8e-8 .. 1e-8 at values 8 .. 1 (order 1): the finest error equals the
    reference's floor 1e-8, which is not below it, so the study is judged.
    Planted: '<=' for '<' against REFERENCE_FLOOR (inconclusive)."""
    runs = [(v, _constant(v * 1e-8)) for v in (8.0, 4.0, 2.0, 1.0)]
    s = refinement_study(REF0, runs, "h", 0.3)
    assert s.errors[-1] == 1e-8
    assert (s.verdict, s.verdict_reason) == (
        "approaches ideal rolling", "the error shrinks at order 1.00 over 8x (to 1.0e-08 at 1)")


def test_an_order_of_exactly_one_half_approaches():
    """Errors 2^1.5, 2, 2^0.5, 1 at values 8, 4, 2, 1: error = sqrt(value), a fitted order of
    0.5 exactly (the least-squares slope of log e on log v, exact in binary here), which is
    not below NO_SHRINK_ORDER = 0.5. Planted: '<=' for '<' (does not approach)."""
    runs = [(v, _constant(math.sqrt(v))) for v in (8.0, 4.0, 2.0, 1.0)]
    s = refinement_study(REF0, runs, "h", 0.3)
    assert s.order == 0.5
    assert s.verdict == "approaches ideal rolling"


def test_float32_diagnostics_give_double_precision_statistics():
    """An engine recording its slip and penetration in float32 ((N,) arrays, as
    docs/engines.md asks): the RMS is that of the recorded values taken in double, worked
    here with math.fsum. Planted: the diagnostics kept in their own dtype (float32 squares
    and mean: ~1e-8 relative off)."""
    n = T0.size
    slip = (1e-4 * (1.0 + np.sin(7.3 * T0))).astype(np.float32)
    pen = (3e-6 * (1.0 + np.cos(5.1 * T0))).astype(np.float32)
    run = _traj(T0, diagnostics=_diag(n, slip_rear=slip, pen_front=pen, dtype=np.float32))
    fid = contact_fidelity(REF0, run)
    for got, rec in ((fid.slip_rms, slip), (fid.penetration_rms, pen)):
        want = math.sqrt(math.fsum(float(x) ** 2 for x in rec) / (2 * n))   # the other wheel 0
        assert got == pytest.approx(want, rel=1e-13)
    assert fid.slip_max == float(slip.max())


def _old(t, q=None):
    """A trajectory object without a ``diagnostics`` attribute at all (Run.trajectory is any
    object; a Trajectory pickled before the field existed unpickles without it)."""
    tr = _traj(t, q)
    return SimpleNamespace(**{k: v for k, v in vars(tr).items() if k != "diagnostics"})


def test_a_trajectory_without_the_diagnostics_attribute_is_one_without_diagnostics():
    """contact_fidelity refuses it with its ValueError, lift_off_time has no lift-off,
    refinement_study gives NaN slip and penetration, declared_difference_rows gives no
    fidelity row. Planted: getattr(run, 'diagnostics') without its default, in each
    (AttributeError)."""
    with pytest.raises(ValueError, match=r"has no 'slip_speed_rear' \(it has nothing\)"):
        contact_fidelity(REF0, _old(T0))
    assert lift_off_time(_old(T0)) is None
    q = np.zeros((T0.size, 8))
    runs = []
    for v in (8.0, 4.0, 2.0, 1.0):
        q = q.copy()
        q[:, 1] = v
        runs.append((v, _old(T0, q)))
    s = refinement_study(REF0, runs, "h", 0.3)
    assert all(math.isnan(x) for x in s.slip_rms + s.penetration_max)
    ref = Run("reference", "s", "m", "forward", "completed", "", 0.0, T0, REF0.q, REF0.dq,
              trajectory=REF0)
    old = runs[0][1]
    run = Run("e", "s", "m", "forward", "completed", "", 0.0, T0, old.q, old.dq, trajectory=old)
    hz = Horizon(0.5, "separation", 1e-6, 0.0, (1.0, 1.0), "r")
    rows = declared_difference_rows(ref, run, hz, "soft contact", 1e-4, "-")
    assert [r["quantity"] for r in rows] == ["constraint_residual", "trajectory"]


def test_a_missing_diagnostic_names_what_the_run_has_and_what_it_must_record():
    """The ValueError's whole message: the missing key, the keys the run has (sorted, comma
    separated) and what a soft-contact engine must record. Planted: the keys joined by
    'XX, XX', the last sentence changed (XX..XX, upper case)."""
    run = _traj(T0, diagnostics={"slip_speed_front": np.zeros(T0.size),
                                 "normal_force_rear": np.zeros(T0.size)})
    with pytest.raises(ValueError) as e:
        contact_fidelity(REF0, run)
    assert str(e.value) == ("the run's Trajectory.diagnostics has no 'slip_speed_rear' (it has "
                            "normal_force_rear, slip_speed_front); a soft-contact engine must "
                            "record slip_speed_rear/front and penetration_rear/front per sample")


def test_a_refinement_without_diagnostics_or_held_has_nan_and_empty_fields_and_uses_coords():
    """A run without diagnostics: slip RMS and penetration max are NaN (floats, not None);
    held defaults to ''; the errors are over the given coordinates only (theta off by v, yc
    by 100 v: with coords=('theta',) the errors are v). Planted: None appended for the
    penetration, the default held 'XXXX', error_at called without the coordinates."""
    runs = []
    for v in (8.0, 4.0, 2.0, 1.0):
        q = np.zeros((T0.size, 8))
        q[:, 3], q[:, 1] = v * 1e-3, v * 1e-1
        runs.append((v, _traj(T0, q)))
    s = refinement_study(REF0, runs, "h", 0.3, coords=("theta",))
    assert s.held == ""
    assert s.errors == (8e-3, 4e-3, 2e-3, 1e-3)
    assert all(isinstance(x, float) and math.isnan(x) for x in s.penetration_max + s.slip_rms)
    assert s.describe().startswith("error at 0.3 s by h () {8: 8.00e-03, ")


def test_declared_rows_carry_exactly_their_fields_and_stop_at_the_reference_end():
    """The rows' fields (summary.json's): the common ones, 'tolerance' and 'passed' None
    among them, and each kind's extras, nothing else; the fidelity row names both engines.
    The reference ended at 0.30 s (before the 0.5 s horizon and the run's end): a slip spike
    of the run at 0.40 s is past what is compared and not in the fidelity row.
    Planted: 'tolerance' / 'passed' misspelled (XX..XX, upper case: an extra field), the
    fidelity row without engines, the reference's end left out of the cut (the spike in)."""
    n = T0.size
    slip = np.full(n, 1e-4)
    slip[40] = 5e-2                                    # at 0.40 s
    diag = _diag(n, slip_rear=slip)
    q = np.zeros((n, 8))
    q[:, 1] = 2e-3 * T0
    traj = _traj(T0, q, diag)
    ref_traj = _traj(T0[:31])
    ref = Run("reference", "sc", "md", "forward", "fell", "", 0.0, ref_traj.t, ref_traj.q,
              ref_traj.dq, trajectory=ref_traj)
    run = Run("mujoco", "sc", "md", "forward", "completed", "", 0.0, T0, q, traj.dq,
              trajectory=traj)
    hz = Horizon(0.5, "separation", 1e-6, 0.0, (1.0, 1.0), "r")
    rows = [r.as_dict() for r in declared_difference_rows(ref, run, hz, "soft contact", 3e-4,
                                                          "C at 0.1 s")]
    common = ["quantity", "scenario", "model", "engines", "max_error", "tolerance", "passed",
              "localized_to", "note"]
    extras = {"constraint_residual": [],
              "trajectory": ["horizon", "horizon_reason", "lift_off_s"],
              "contact fidelity (slip, penetration, trajectory)": [
                  "horizon", "slip_max", "slip_rms", "penetration_max", "penetration_rms",
                  "lift_off_s"]}
    assert [r["quantity"] for r in rows] == list(extras)
    for r in rows:
        assert sorted(r) == sorted(common + ["declared_difference", "why"]
                                   + extras[r["quantity"]])
        assert (r["tolerance"], r["passed"]) == (None, None)
    fid = rows[2]
    assert fid["engines"] == ["reference", "mujoco"]
    assert fid["horizon"] == 0.3
    assert fid["slip_max"] == 1e-4                       # the spike at 0.40 s is not compared
    assert fid["max_error"] == pytest.approx(2e-3 * 0.3, rel=1e-12)


def test_local_orders_in_float32_and_without_warnings():
    """Orders log(e_i / e_i+1) / log(v_i / v_i+1) of values and errors given in float32 are
    those of the same numbers in double (math.log here); an error of zero or a repeated value
    gives inf or nan without a warning. Planted: values or errors kept in float32 (dtype
    dropped: ~1e-8 relative off), the errstate's divide or invalid left at numpy's default
    (RuntimeWarning)."""
    v32 = np.array([0.004, 0.002, 0.0005], dtype=np.float32)
    e32 = np.array([3e-3, 1.1e-3, 2e-4], dtype=np.float32)
    v, e = [float(x) for x in v32], [float(x) for x in e32]
    want = [math.log(e[i] / e[i + 1]) / math.log(v[i] / v[i + 1]) for i in range(2)]
    for values, errors in ((v32, e), (v, e32)):
        got = local_orders(values, errors)
        assert got == pytest.approx(want, rel=1e-14)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        zero = local_orders([4.0, 2.0, 1.0], [8.0, 0.0, 0.0])     # 8/0: inf; 0/0: nan
        same = local_orders([2.0, 2.0], [1.0, 3.0])               # log(1) = 0 below
    assert zero[0] == math.inf and math.isnan(zero[1])
    assert same[0] == -math.inf
