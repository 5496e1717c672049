"""The contact-fidelity judgments (comparisons/judgments/contact.py) on synthetic trajectories
whose answers are known in closed form: slip and penetration statistics of given signals, and
refinement studies whose errors are exactly C v^p (order p)."""

import math

import numpy as np
import pytest

from comparisons.judgments.contact import (contact_fidelity, error_at, lift_off_time,
                                           local_orders, refinement_study)
from reference_model.solvers import Trajectory

DT = 0.01
T = np.round(np.arange(0, 101) * DT, 12)      # 0 .. 1 s on the 0.01 s grid


def _traj(t, q, diagnostics=None):
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    z = np.zeros_like(q)
    return Trajectory(t=t, q=q, dq=z, ddq=z, C=np.zeros((t.size, 5)), T=np.zeros((t.size, 3)),
                      status="completed", message="", t_end=float(t[-1]),
                      diagnostics=diagnostics or {})


def _diag(n, slip_rear=None, slip_front=None, pen_rear=None, pen_front=None):
    zero = np.zeros(n)
    return {"slip_speed_rear": zero if slip_rear is None else slip_rear,
            "slip_speed_front": zero if slip_front is None else slip_front,
            "penetration_rear": zero if pen_rear is None else pen_rear,
            "penetration_front": zero if pen_front is None else pen_front}


REF = _traj(T, np.zeros((T.size, 8)))


def _drift_run(c, t=T, diagnostics=None):
    """A run whose yc drifts as c t (a constant lateral slip of c m/s)."""
    q = np.zeros((t.size, 8))
    q[:, 1] = c * t
    return _traj(t, q, diagnostics)


# -- slip, penetration, error against time ------------------------------------------------------

def test_fidelity_statistics_of_known_signals():
    # rear slip A |sin(2 pi t)| over 100 samples of one period (t = 0 .. 0.99; the sample at
    # 1.0 is past the horizon): the mean of sin^2 over a whole number of periods sampled
    # uniformly (N > 2) is exactly 1/2, so the RMS over both wheels (front zero) is
    # sqrt((A^2 / 2 + 0) / 2) = A / 2; the max A is at t = 0.25.
    A = 3e-4
    slip = A * np.abs(np.sin(2 * np.pi * T))
    pen_r = np.full(T.size, 1e-6)
    pen_f = np.zeros(T.size)
    pen_f[40] = 3e-6                                   # one sample at t = 0.40 s
    run = _drift_run(2e-3, diagnostics=_diag(T.size, slip_rear=slip, pen_rear=pen_r,
                                             pen_front=pen_f))
    fid = contact_fidelity(REF, run, horizon=0.99)
    assert fid.horizon == pytest.approx(0.99)
    assert fid.slip_max == pytest.approx(A, rel=1e-12)
    assert fid.slip_worst == "rear at 0.25 s"
    assert fid.slip_rms == pytest.approx(A / 2, rel=1e-12)
    assert fid.penetration_max == pytest.approx(3e-6, rel=1e-12)
    assert fid.penetration_worst == "front at 0.40 s"
    # RMS over 2 x 100 samples: 100 of 1e-6, one of 3e-6, the rest 0
    assert fid.penetration_rms == pytest.approx(math.sqrt((100e-12 + 9e-12) / 200), rel=1e-12)
    # the trajectory error is the drift 2e-3 t, largest at the horizon
    assert fid.error_end == pytest.approx(2e-3 * 0.99, rel=1e-12)
    assert fid.error_max == pytest.approx(2e-3 * 0.99, rel=1e-12)
    np.testing.assert_allclose(fid.error["yc"], 2e-3 * T[:100], rtol=0, atol=1e-18)


def test_fidelity_ignores_what_lies_beyond_the_horizon():
    slip = np.zeros(T.size)
    slip[-1] = 5.0                                     # a spike at 1.0 s, past the horizon
    fid = contact_fidelity(REF, _drift_run(0.0, diagnostics=_diag(T.size, slip_front=slip)),
                           horizon=0.5)
    assert fid.slip_max == 0.0 and fid.horizon == pytest.approx(0.5)
    assert contact_fidelity(REF, _drift_run(0.0, diagnostics=_diag(T.size, slip_front=slip))
                            ).slip_max == 5.0            # no horizon: the whole run


def test_fidelity_needs_the_diagnostics():
    with pytest.raises(ValueError, match="slip_speed_rear"):
        contact_fidelity(REF, _drift_run(1e-3))
    bad = _diag(T.size)
    bad["penetration_front"] = np.zeros(3)
    with pytest.raises(ValueError, match="penetration_front.*one value per sample"):
        contact_fidelity(REF, _drift_run(1e-3, diagnostics=bad))


# -- refinement studies with errors C v^p --------------------------------------------------------

VALUES = (2e-3, 1e-3, 5e-4, 2.5e-4)          # spans 8x, as convergence.MIN_SPAN asks


@pytest.mark.parametrize("p", [1.0, 2.0])
def test_refinement_recovers_the_order_of_errors_c_v_p(p):
    # a run at value v drifts as 40 v^p t, so its error at 0.3 s is 12 v^p exactly: the fitted
    # line through log e = p log v + log 12 has slope p (to round-off of logs, 1e-9)
    runs = [(v, _drift_run(40 * v ** p)) for v in VALUES]
    s = refinement_study(REF, runs, "solref time constant [s]", at_time=0.3)
    assert s.values == tuple(sorted(VALUES, reverse=True))
    np.testing.assert_allclose(s.errors, [12 * v ** p for v in s.values], rtol=1e-12)
    assert s.order == pytest.approx(p, abs=1e-9)
    assert s.intercept == pytest.approx(math.log(12), abs=1e-8)
    np.testing.assert_allclose(s.orders, [p] * 3, atol=1e-9)
    assert s.verdict == "approaches ideal rolling"
    assert math.isnan(s.slip_rms[0])                  # the synthetic runs have no diagnostics


def test_refinement_reports_an_error_that_does_not_shrink():
    # the same error at every value (order 0): whatever limits it is not the refined parameter
    runs = [(v, _drift_run(1e-2 * (1 + 0.01 * k))) for k, v in enumerate(VALUES)]
    s = refinement_study(REF, runs, "timestep [s]", at_time=0.3)
    assert abs(s.order) < 0.05
    assert s.verdict == "does not approach"


def test_refinement_needs_a_span_to_judge():
    runs = [(v, _drift_run(40 * v)) for v in (2e-3, 1e-3)]     # 2x: too narrow
    s = refinement_study(REF, runs, "timestep [s]", at_time=0.3)
    assert s.order == pytest.approx(1.0, abs=1e-9)
    assert s.verdict == "inconclusive"


def test_refinement_refuses_a_run_that_stops_before_the_time():
    short = _drift_run(1e-3, t=T[:21])                         # ends at 0.2 s
    with pytest.raises(ValueError, match=r"= 0.0005: .*t = 0.3 s"):
        refinement_study(REF, [(1e-3, _drift_run(1e-3)), (5e-4, short)], "timestep [s]",
                         at_time=0.3)
    with pytest.raises(ValueError, match="at least 2 runs"):
        refinement_study(REF, [(1e-3, _drift_run(1e-3))], "timestep [s]", at_time=0.3)


def test_error_at_and_local_orders():
    assert error_at(REF, _drift_run(2.0), 0.5) == pytest.approx(1.0, rel=1e-12)
    # errors 8, 2, 1 at values 4, 2, 1: orders log(4)/log(2) = 2 and 1
    np.testing.assert_allclose(local_orders([4, 2, 1], [8, 2, 1]), [2.0, 1.0], rtol=1e-12)


# -- the stage on MuJoCo (quick: four runs of 0.2 s and one of 0.5 s, ~1 s) ---------------------

@pytest.fixture(scope="module")
def quick_study(mujoco_quick_study):
    return mujoco_quick_study.section


def test_stage_states_the_contact_settings(quick_study):
    from reference_model.export_mjcf import MjcfSettings
    d = MjcfSettings()
    table = next(b for b in quick_study.blocks if getattr(b, "header", None) == ("setting", "value"))
    cells = dict(table.rows)
    assert cells["solref (time constant s, damping ratio)"] == f"{d.solref[0]:g}, {d.solref[1]:g}"
    assert cells["noslip iterations"] == str(d.noslip_iterations)
    assert cells["timestep, integrator"] == f"{d.timestep:g} s, {d.integrator}"
    assert f"cone {d.cone}, condim {d.condim}" in cells["friction"]
    assert "cylinders" in cells["geometry"]


def test_slip_and_error_are_first_order_in_the_contact_time_constant(quick_study):
    """MuJoCo solves its friction rows for J qacc = -b J qdot with b = 2 / (dmax tc) and leaves
    out the dJ/dt qdot a rolling point's acceleration needs (its documented constraint model):
    the rows settle at a slip of that term's size times dmax tc / 2, proportional to tc, and a
    small slip moves the trajectory in proportion. So with the step at tc / 2 the slip RMS per
    tc must be one constant (within 10 %: the slip's pattern shifts slightly with the run) and
    the error's fitted order 1 +- 0.2 (over 8x in tc; measured 1.02)."""
    study = next(c for c in quick_study.comparisons
                 if c["quantity"].startswith("contact refinement"))
    per_tc = np.array(study["slip_rms"]) / np.array(study["values"])
    assert per_tc.max() / per_tc.min() < 1.1, per_tc
    assert 0.8 <= study["order"] <= 1.2, study
    assert study["verdict"] == "approaches ideal rolling"


def test_a_wheel_lifts_off_where_ideal_rolling_needs_the_ground_to_pull(quick_study):
    """MuJoCo's contact is unilateral: a wheel leaves the ground where the reference's
    bilateral constraint has to pull it down (a negative normal force, from the reference's own
    multipliers). The two times agree within 0.02 s (two output samples: each is read on the
    0.01 s grid)."""
    fid = next(c for c in quick_study.comparisons if c["quantity"].startswith("contact fidelity"))
    assert fid["lift_off_s"] is not None and fid["ideal_pull_s"] is not None
    assert abs(fid["lift_off_s"] - fid["ideal_pull_s"]) <= 0.02 + 1e-9, fid
    # before it, the soft contact stays close to rolling: slip below 1 cm/s, penetration < 1 um
    assert fid["slip_max"] < 1e-2 and fid["penetration_max"] < 1e-6, fid


def test_disc_claims_replace_only_mujocos_entries():
    from comparisons.stages.soft_contact_claims import DiscClaims, merge_claims, on_disc
    base = [{"claim_id": "stability-psid10", "engine": e, "verdict": v, "evidence": "x"}
            for e, v in (("reference", "partly"), ("mujoco", "not assessed"))]
    base.append({"claim_id": "check-pedal-torque", "engine": "mujoco", "verdict": "not assessed",
                 "evidence": "y"})
    disc = DiscClaims("mujoco", "MuJoCo", ({"claim_id": "stability-psid10", "engine": "mujoco",
                                            "verdict": "partly", "evidence": "fell at 1.692 s"},))
    out = merge_claims(base, disc)
    assert [(c["engine"], c["claim_id"], c["verdict"]) for c in out] == [
        ("reference", "stability-psid10", "partly"), ("mujoco", "stability-psid10", "partly"),
        ("mujoco", "check-pedal-torque", "not assessed")]
    assert out[1]["evidence"] == on_disc("MuJoCo") + "fell at 1.692 s" and out[0]["evidence"] == "x"


# -- lift-off and a declared difference's rows (issue 24's mutation round; no engine runs) ------

def test_lift_off_is_the_first_unloaded_sample_after_the_start():
    n = T.size
    rear, front = np.full(n, 100.0), np.full(n, 50.0)
    rear[0] = front[0] = 0.0                     # the start (not yet loaded) never counts
    front[30] = 0.0                              # front unloaded at 0.30 s (zero counts)
    rear[60] = -1.0
    run = _traj(T, np.zeros((n, 8)), {"normal_force_rear": rear, "normal_force_front": front})
    assert lift_off_time(run) == pytest.approx(0.30, abs=1e-12)
    front[30] = 1e-9                             # loaded, barely: the rear's pull at 0.60 s
    assert lift_off_time(run) == pytest.approx(0.60, abs=1e-12)
    rear[60] = 1.0
    assert lift_off_time(run) is None            # always loaded after the start
    assert lift_off_time(_traj(T, np.zeros((n, 8)), {"normal_force_rear": rear})) is None
    assert lift_off_time(REF) is None            # no normal forces recorded


def _run(engine, traj):
    from engines.runs import Run
    return Run(engine, "stability-psid10", "thesis-disc", "forward", "completed", "", 0.0,
               traj.t, traj.q, traj.dq, trajectory=traj)


def test_a_declared_differences_rows_are_measured_and_reported_never_judged():
    """yc drifts at 2 mm/s (error 2e-3 t); horizon 0.5 s; a rear slip of 1e-4 m/s constant,
    a penetration of 1e-6 m at 0.20 s on the front; the front unloaded at 0.30 s."""
    from comparisons.judgments.contact import declared_difference_rows
    from comparisons.judgments.convergence import Horizon
    n = T.size
    diag = _diag(n, slip_rear=np.full(n, 1e-4), pen_front=np.where(np.isclose(T, 0.2), 1e-6, 0))
    diag.update(normal_force_rear=np.full(n, 10.0),
                normal_force_front=np.where(T >= 0.3 - 1e-12, -1.0, 10.0))
    ref = _run("reference", REF)
    run = _run("mujoco", _drift_run(2e-3, diagnostics=diag))
    hz = Horizon(0.5, "separation", 1e-6, 0.0, (1.0, 1.0), "the twins part at 0.51 s")
    rows = [r.as_dict() for r in declared_difference_rows(ref, run, hz, "soft contact", 3e-4,
                                                          "C[vC_y] at t = 0.40 s")]
    note = "reported, not judged: a declared model difference (soft contact)"
    assert [r["quantity"] for r in rows] == [
        "constraint_residual", "trajectory", "contact fidelity (slip, penetration, trajectory)"]
    for r in rows:
        assert (r["tolerance"], r["passed"], r["note"]) == (None, None, note)
        assert (r["declared_difference"], r["why"]) == ("soft contact", "declared model difference")
        assert (r["scenario"], r["model"]) == ("stability-psid10", "thesis-disc")
    c, tr, fid = rows
    assert (c["engines"], c["max_error"], c["localized_to"]) == (
        ["mujoco"], 3e-4, "C[vC_y] at t = 0.40 s")
    assert tr["engines"] == ["reference", "mujoco"]
    assert tr["max_error"] == pytest.approx(1e-3, rel=1e-9)        # 2e-3 m/s x 0.5 s
    assert (tr["horizon"], tr["horizon_reason"]) == (0.5, "the twins part at 0.51 s")
    assert tr["lift_off_s"] == pytest.approx(0.3, abs=1e-12)
    assert tr["localized_to"] == ("largest: yc, up to the meaningful horizon 0.50 s; a wheel "
                                  "lifts off at 0.30 s")
    assert fid["max_error"] == pytest.approx(1e-3, rel=1e-9) and fid["horizon"] == 0.5
    assert fid["slip_max"] == pytest.approx(1e-4, rel=1e-12)
    # RMS over both wheels' samples: rear 1e-4 everywhere, front 0 -> 1e-4 / sqrt(2)
    assert fid["slip_rms"] == pytest.approx(1e-4 / math.sqrt(2), rel=1e-12)
    assert fid["penetration_max"] == pytest.approx(1e-6, rel=1e-12)
    # one sample of 1e-6 among 2 x 51 (both wheels up to 0.5 s)
    assert fid["penetration_rms"] == pytest.approx(1e-6 / math.sqrt(102), rel=1e-12)
    assert fid["lift_off_s"] == pytest.approx(0.3, abs=1e-12)
    assert fid["localized_to"] == ("slip max 1.0e-04 m/s (rear at 0.00 s), penetration max "
                                   "1.0e-06 m up to 0.50 s; lift-off at 0.30 s")
    # no diagnostics: no fidelity row, and the trajectory row says nothing of a lift-off
    plain = _run("mujoco", _drift_run(2e-3))
    rows = declared_difference_rows(ref, plain, hz, "soft contact", 3e-4, "-")
    assert [r["quantity"] for r in rows] == ["constraint_residual", "trajectory"]
    assert rows[1]["localized_to"] == "largest: yc, up to the meaningful horizon 0.50 s"
    assert rows[1]["lift_off_s"] is None
    # a run that ended shorter than the horizon is compared up to its end
    short = _run("mujoco", _drift_run(2e-3, t=T[:31]))
    assert declared_difference_rows(ref, short, hz, "d", None, "-")[1]["max_error"] == \
        pytest.approx(2e-3 * 0.3, rel=1e-9)
    # without samples, or without the reference's trajectory: the residual row alone
    from engines.runs import Run
    empty = Run("mujoco", "s", "m", "forward", "failed", "boom", 0.0)
    assert len(declared_difference_rows(ref, empty, hz, "d", None, "-")) == 1
    no_ref_traj = Run("reference", "s", "m", "forward", "completed", "", 0.0, T, REF.q, REF.dq)
    assert len(declared_difference_rows(no_ref_traj, run, hz, "d", None, "-")) == 1
    # a fidelity row without a lift-off says so
    no_lift = dict(diag, normal_force_front=np.full(n, 10.0))
    rows = declared_difference_rows(ref, _run("mujoco", _drift_run(2e-3, diagnostics=no_lift)),
                                    hz, "soft contact", 3e-4, "-")
    assert rows[2]["localized_to"].endswith("up to 0.50 s; no lift-off")
    assert rows[2]["lift_off_s"] is None


def test_a_refinement_with_diagnostics_reports_slip_and_penetration_up_to_its_time():
    """Runs at v = 2e-3 .. 2.5e-4 (8x), error 40 v t, rear slip v (constant) and a front
    penetration of 10 v at 0.2 s plus a spike of 1 at 0.5 s, past at_time = 0.3 s (not seen).
    RMS over both wheels' 31 samples up to 0.3 s: v / sqrt(2)."""
    n = T.size
    runs = []
    for v in VALUES:
        pen = np.where(np.isclose(T, 0.2), 10 * v, 0.0)
        pen[50] = 1.0
        runs.append((v, _drift_run(40 * v, diagnostics=_diag(n, slip_rear=np.full(n, v),
                                                              pen_front=pen))))
    s = refinement_study(REF, runs, "timestep [s]", at_time=0.3, held="tc = 2 h")
    assert (s.parameter, s.held, s.at_time) == ("timestep [s]", "tc = 2 h", 0.3)
    np.testing.assert_allclose(s.slip_rms, [v / math.sqrt(2) for v in s.values], rtol=1e-12)
    np.testing.assert_allclose(s.penetration_max, [10 * v for v in s.values], rtol=1e-12)
    assert s.span == pytest.approx(8.0) and s.verdict == "approaches ideal rolling"
    assert s.verdict_reason == "the error shrinks at order 1.00 over 8x (to 3.0e-03 at 0.00025)"
    assert s.describe() == ("error at 0.3 s by timestep [s] (tc = 2 h) {0.002: 2.40e-02, "
                            "0.001: 1.20e-02, 0.0005: 6.00e-03, 0.00025: 3.00e-03}: fitted order "
                            "1.00 -> approaches ideal rolling (" + s.verdict_reason + ")")


def test_the_refinement_verdicts_reasons():
    """Each verdict's reason, written out: too few values or too narrow a span, an error of
    zero (no order), errors below the reference's floor 1e-8, one that does not shrink."""
    s = refinement_study(REF, [(v, _drift_run(40 * v)) for v in (2e-3, 1e-3)], "h", 0.3)
    assert s.verdict_reason == "2 values spanning 2x; need >= 3 spanning >= 8x"
    three = (2e-3, 1e-3, 2.5e-4)                       # three values over exactly 8x: judged
    assert refinement_study(REF, [(v, _drift_run(40 * v)) for v in three], "h", 0.3
                            ).verdict == "approaches ideal rolling"
    zero = [(v, _drift_run(0.0 if k == 3 else 40 * v)) for k, v in enumerate(VALUES)]
    s = refinement_study(REF, zero, "h", 0.3)
    assert (s.verdict, s.verdict_reason) == (
        "inconclusive", "an error is zero or not finite: no order can be fitted")
    tiny = refinement_study(REF, [(v, _drift_run(1e-6 * v)) for v in VALUES], "h", 0.3)
    assert tiny.verdict == "inconclusive" and tiny.verdict_reason == (
        "error at the finest value 7.5e-11 is below 1e-08, the reference's own accuracy")
    flat = [(v, _drift_run(1e-2 * (1 + 0.01 * k))) for k, v in enumerate(VALUES)]
    s = refinement_study(REF, flat, "h", 0.3)
    assert s.verdict_reason.startswith(f"order {s.order:.2f} < 0.5: error(coarsest) / "
                                       "error(finest) = ")
    # the coarsest value's error 3e-3 over the finest's 3.09e-3
    assert s.verdict_reason.endswith(f"= {3e-3 / 3.09e-3:.3g} over 8x")
    with pytest.raises(ValueError, match=r"h = 0: refined values must be positive"):
        refinement_study(REF, [(1e-3, _drift_run(1e-3)), (0, _drift_run(1e-3))], "h", 0.3)


def test_error_at_names_the_last_common_time_and_both_ends():
    short = _drift_run(1e-3, t=T[:21])
    with pytest.raises(ValueError) as e:
        error_at(REF, short, 0.3)
    assert str(e.value) == ("the runs share no output-grid sample at t = 0.3 s (the last common "
                            "one is 0.2 s; ends: reference 1 s, engine 0.2 s)")
    # only the given coordinates: yc drifts, theta does not
    assert error_at(REF, _drift_run(2.0), 0.5, coords=("theta",)) == 0.0
    # a time between grid samples is not a grid time
    with pytest.raises(ValueError, match="no output-grid sample at t = 0.305 s"):
        error_at(REF, _drift_run(2.0), 0.305)


def test_fidelity_windows_and_the_wheels_names():
    """A one-sample run is its own window; the worst sample is named by the wheel (the last
    word of the diagnostic's key) and its time; non-finite diagnostics are refused by name."""
    one = _traj(T[:1], np.zeros((1, 8)), _diag(1, slip_front=np.array([2e-3])))
    fid = contact_fidelity(REF, one, horizon=0.0)
    assert fid.slip_worst == "front at 0.00 s" and fid.slip_max == 2e-3
    with pytest.raises(ValueError, match="no sample up to the horizon -1"):
        contact_fidelity(REF, _drift_run(0.0, diagnostics=_diag(T.size)), horizon=-1.0)
    bad = _diag(T.size, pen_rear=np.full(T.size, np.nan))
    with pytest.raises(ValueError, match="non-finite values in Trajectory.diagnostics "
                                         "penetration_rear, penetration_front"):
        contact_fidelity(REF, _drift_run(0.0, diagnostics=bad))
    with pytest.raises(ValueError, match=r"has no 'slip_speed_rear' \(it has nothing\)"):
        contact_fidelity(REF, _drift_run(0.0))
    # the horizon includes the sample at it, to a billionth of a step (round-off)
    fid = contact_fidelity(REF, _drift_run(0.0, diagnostics=_diag(T.size)), horizon=0.5 - 1e-13)
    assert fid.horizon == pytest.approx(0.5)
