"""MuJoCo's forward runs (engines/mujoco/run.py) held to the "forward runs" contract of
docs/engines.md (what status, message, t_end and the last row hold for a completed run, a fall
and a failed run), to the module's docstring (the fall interpolated within the step that passes
the limit, the loads as body wrenches, the diagnostics' definitions) and to MuJoCo's own API.

Expected values come from: the reference engine's run of the same scenario; the fall located in
the test by linear interpolation between two steps read from a run that samples every step
(MuJoCo is deterministic, and sampling does not touch the state: such a run passes through
exactly the same states); the scenario's torque function evaluated in the test; MuJoCo's own
stepping (``mj_step`` on a fresh ``MjData``), its velocities (``mj_objectVelocity``) and its
warning texts (``mju_warningText``, ``mj_warning``'s " Time = %.4f." suffix); the reference
model's constraint residuals on MuJoCo's states, which hold the contact points' velocities and
the front contact's height; and the straight-roll law m_eff dv/dt = Mped / R_rear - cv v^2.
Each test names the planted bugs (mutmut's survivors of the module's first measurement) it
fails on.

Cost: every run here is 0.01-0.1 simulated s at the default 1e-4 s step, 10-40 ms each; the
runs several tests read are module fixtures.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import pytest

from reference_model import COORDINATES, load_model
from reference_model.scenarios import Scenario, get_scenario, initial_state

mujoco = pytest.importorskip("mujoco")

from engines import load_engine  # noqa: E402
from engines.base import EngineUsageError  # noqa: E402
from engines.mujoco import MujocoEngine  # noqa: E402
from engines.mujoco.run import _Bicycle  # noqa: E402

#: MuJoCo's default step (docs/engines.md, the MuJoCo options table)
H = 1e-4
#: a fall limit the stability-psid0 bicycle (lean pi/16 = 0.19635 rad, falling) passes between
#: 0.01 and 0.02 s
FALL = 0.1965


def _ramp(t):
    """Rider torques linear in t (steer 0.5 t, pedal 1, anti-roll -2 t N m): a linear function
    is its own linear interpolation, so the torque at an interpolated event is exact."""
    t = np.asarray(t, dtype=float)
    return np.stack([0.5 * t, 1.0 + 0.0 * t, -2.0 * t], axis=-1)


def _nan_from(t_nan: float):
    """Pedal torque 1 N m, non-finite from ``t_nan`` on (a torque table with a gap)."""
    def torque(t):
        t = np.asarray(t, dtype=float)
        T = np.stack([0.0 * t, 1.0 + 0.0 * t, 0.0 * t], axis=-1)
        return np.where((t >= t_nan - 1e-12)[..., None], np.nan, T)
    return torque


#: stability-psid0 (falls at once) with time-varying torques
FALLING = dataclasses.replace(get_scenario("stability-psid0"), torques=_ramp)
#: stability-psid5 (leaned and steered, rolling at 5 rad/s) over 0.1 s
LEANED = dataclasses.replace(get_scenario("stability-psid5"), grid=(0.0, 0.01, 11))


@pytest.fixture(scope="module")
def eng(disc):
    """MuJoCo with its defaults on thesis-disc; its run model is compiled once, on first use."""
    return MujocoEngine(disc)


@pytest.fixture(scope="module")
def reference(disc):
    return load_engine("reference", disc)


@pytest.fixture(scope="module")
def every_step(eng):
    """FALLING sampled at every step (grid step = timestep) to 0.02 s, no fall: the states a
    coarser run of the same scenario passes through, step by step."""
    return eng.simulate(dataclasses.replace(FALLING, grid=(0.0, H, 201)), fall_limit=1.4)


@pytest.fixture(scope="module")
def leaned(eng):
    """(LEANED's run, the wall time of the call, the times `progress` was called with)."""
    calls: list[float] = []
    t0 = time.perf_counter()
    traj = eng.simulate(LEANED, progress=calls.append)
    return traj, time.perf_counter() - t0, calls


# -- the fall ---------------------------------------------------------------------------------

def test_the_fall_is_the_linear_crossing_within_the_step_that_passes_the_limit(eng, every_step):
    """docs/engines.md: a fall ends the run 'fell', the grid stops at the last sample before and
    the final row is the fall itself; the module: the event is interpolated linearly between
    the two steps around it. Expected: the first step k with |theta| >= 0.1965 read from the
    every-step run, s = (limit - |theta_k-1|) / (|theta_k| - |theta_k-1|), and t, q, dq at
    t_k-1 + s h, q_k-1 + s (q_k - q_k-1), ...; the torques are the scenario's function at each
    row's time. Both sides do the same few float operations on the same states, so 1e-12 (s,
    rad, rad/s) is round-off with a wide margin; a misplaced event moves them by up to a
    step (1e-4 s, ~1e-6 rad). Fails when the fraction s is mis-formed (a product, a sign, 1
    always), when the event time or state is taken from the wrong step or interpolated with a
    sign error, when the event's torques are interpolated wrongly or the first row's torques
    are the second step's, when the message is lost."""
    traj = eng.simulate(dataclasses.replace(FALLING, grid=(0.0, 0.01, 3)), fall_limit=FALL)
    th = np.abs(every_step.q[:, 3])
    k = int(np.argmax(th >= FALL))
    assert 100 < k < 200                         # between the samples at 0.01 and 0.02 s
    s = (FALL - th[k - 1]) / (th[k] - th[k - 1])
    t_event = every_step.t[k - 1] + s * H
    assert traj.status == "fell"
    assert traj.message == f"|theta| reached the fall limit 0.1965 rad at t = {t_event:.6f} s"
    np.testing.assert_allclose(traj.t, [0.0, 0.01, t_event], rtol=0, atol=1e-12)
    assert traj.t_end == traj.t[-1]
    a, b = every_step.q[k - 1], every_step.q[k]
    np.testing.assert_allclose(traj.q[-1], a + s * (b - a), rtol=0, atol=1e-12)
    a, b = every_step.dq[k - 1], every_step.dq[k]
    np.testing.assert_allclose(traj.dq[-1], a + s * (b - a), rtol=0, atol=1e-12)
    assert abs(abs(traj.q[-1, 3]) - FALL) <= 1e-12
    np.testing.assert_array_equal(traj.q[:2], every_step.q[[0, 100]])
    np.testing.assert_allclose(traj.T, _ramp(traj.t), rtol=0, atol=1e-12)
    assert traj.timing["steps"] == k
    assert traj.settings["fall_limit"] == FALL
    assert np.all(np.isfinite(traj.ddq)) and np.all(np.isfinite(traj.C))


def test_a_fall_limit_equal_to_the_largest_lean_reached_is_a_fall(eng):
    """|theta| >= fall_limit ends the run (the module's docstring, docs/engines.md: 'reached'):
    a limit equal to the largest |theta| of a lean excursion, read at its step j from a run that
    samples every step, is reached at that step, exactly (s = 1): 'fell' at t_j with q_j on the
    last row. The bicycle starts upright leaning left at 0.02 rad/s and a 1000 N m anti-roll
    torque turns it back: |theta| peaks at ~2.3e-5 rad at 2.4 ms and is passed again only at
    ~5.8 ms. Fails when the fall test is strict (|theta| > limit): the run then goes on to the
    later crossing."""
    sc = dataclasses.replace(get_scenario("check-forward"), dq_ind0=(-0.02, 5.0, 0.0),
                             torques=(0.0, 0.0, 1000.0))
    fine = eng.simulate(dataclasses.replace(sc, grid=(0.0, H, 41)))
    th = np.abs(fine.q[:, 3])
    j = int(np.argmax(th))
    assert 0 < j < 40 and th[j - 1] < th[j] > th[j + 1]        # an interior peak
    traj = eng.simulate(dataclasses.replace(sc, grid=(0.0, 1e-3, 7)), fall_limit=float(th[j]))
    assert traj.status == "fell", traj.message
    assert traj.t_end == pytest.approx(fine.t[j], abs=1e-15)   # t_j-1 + 1.0 h: round-off only
    np.testing.assert_allclose(traj.q[-1], fine.q[j], rtol=0, atol=1e-15)
    assert traj.timing["steps"] == j


def test_a_fall_within_round_off_of_the_last_sample_adds_no_second_row_at_that_time(eng):
    """t is strictly increasing (a grid; docs/engines.md: 'the grid stops at the last sample
    before, and the final row is the fall itself'). With the clock at 100 s (a recording's) and
    the limit one ulp above |theta| at the sample before the fall's step, the event lies
    ~4e-16 s after that sample, below the clock's resolution (1.4e-14 s at 100 s): the event
    time equals the last sample's, and that sample is the last row. Expected rows: the
    every-step run's own. Fails when an event at the last sample's time is sampled again (a
    duplicate time), or compared with another row than the last."""
    sc = dataclasses.replace(get_scenario("stability-psid0"), grid=(100.0, H, 151))
    fine = eng.simulate(sc, fall_limit=1.4)
    th = np.abs(fine.q[:, 3])
    assert th[150] > th[149]                                  # falling: the lean still grows
    limit = float(np.nextafter(th[149], np.inf))
    traj = eng.simulate(sc, fall_limit=limit)
    assert traj.status == "fell"
    assert traj.message == f"|theta| reached the fall limit {limit:.4f} rad at t = 100.014900 s"
    assert np.all(np.diff(traj.t) > 0)
    np.testing.assert_array_equal(traj.t, fine.t[:150])
    assert traj.t_end == fine.t[149]
    np.testing.assert_array_equal(traj.q, fine.q[:150])


def test_a_start_at_the_fall_limit_is_the_references_fall_at_the_start(eng, reference, disc):
    """A lean already at the limit: the reference's run (its own start test) says 'fell' with
    '|theta| = 0.196 rad >= fall limit at the start' and one row, the start; MuJoCo must say
    the same and take no step. The limit is the projected start's |theta| itself (pi/16), so a
    strict test would let the run start. Fails when the start test is strict, the status or the
    message is lost, or the run still takes a step."""
    sc = dataclasses.replace(get_scenario("stability-psid0"), grid=(0.0, 0.01, 3))
    limit = abs(float(initial_state(disc, sc).q[3]))
    ref = reference.simulate(sc, fall_limit=limit)
    traj = eng.simulate(sc, fall_limit=limit)
    assert ref.status == "fell" and ref.message == "|theta| = 0.196 rad >= fall limit at the start"
    assert (traj.status, traj.message) == (ref.status, ref.message)
    np.testing.assert_array_equal(traj.t, ref.t)
    np.testing.assert_allclose(traj.q, ref.q, rtol=0, atol=1e-15)
    assert traj.t_end == ref.t_end == 0.0
    assert traj.timing["steps"] == 0


# -- failed runs ------------------------------------------------------------------------------

def test_a_reset_names_the_warning_its_interval_and_mujocos_own_text(eng):
    """A 1e300 N m pedal torque: MuJoCo's qacc is non-finite at the first step, it resets the
    state and warns. The run ends 'failed' at the last sample before (the start) with one line
    naming the warning, the output interval it happened in and MuJoCo's own text: its
    mju_warningText for the first bad entry of qacc (psi's, the wheel the torque spins; the dof
    index read from the compiled model) followed by mj_warning's ' Time = %.4f.' of MuJoCo's
    clock (MuJoCo's engine_support.c), which must be the run's: the grid starts at 5 s. Fails
    when MuJoCo's clock does not start at the grid's first time, when MuJoCo's text is left
    out of the message."""
    sc = dataclasses.replace(get_scenario("check-forward"), torques=(0.0, 1e300, 0.0),
                             grid=(5.0, 0.01, 3))
    traj = eng.simulate(sc)
    _, m = eng.run_model()
    dof = int(m.joint("psi").dofadr[0])
    text = mujoco.mju_warningText(int(mujoco.mjtWarning.mjWARN_BADQACC), dof)
    assert traj.status == "failed"
    assert traj.message == ("MuJoCo reset the simulation (mjWARN_BADQACC) between t = 5.000000 "
                            "and 5.010000 s; the run ends at the last sample before (MuJoCo: "
                            f"{text} Time = 5.0000.)")
    assert traj.t.tolist() == [5.0] and traj.t_end == 5.0


@pytest.mark.parametrize("t_nan", [0.01, 0.02])
def test_a_non_finite_sample_cuts_the_run_before_it(eng, t_nan):
    """A torque that turns non-finite at a sample's time makes that sample's ddq (MuJoCo's qacc
    with those loads) non-finite. docs/engines.md: never NaN in the arrays, the partial
    trajectory up to the last good step, 'failed', one line: the run ends at the sample before,
    and the message names its time. Two cases: one good sample (the cut keeps exactly one row)
    and two. Fails when the finiteness of ddq is not tested per row (one bad entry cutting
    everything, or q's or dq's rows sufficing), when the cut is not made, when the status or
    message is lost or names another sample, when the cut keeps a row too many."""
    sc = dataclasses.replace(get_scenario("stability-psid5"), torques=_nan_from(t_nan),
                             grid=(0.0, 0.01, 4))
    traj = eng.simulate(sc)
    n = int(round(t_nan / 0.01))
    assert traj.status == "failed"
    assert traj.message == f"MuJoCo's state became non-finite after t = {t_nan - 0.01:.6f} s"
    np.testing.assert_array_equal(traj.t, sc.t[:n])
    assert traj.t_end == sc.t[n - 1]
    for name in ("q", "dq", "ddq", "C", "T"):
        a = getattr(traj, name)
        assert a.shape[0] == n and np.all(np.isfinite(a)), name
    assert all(np.all(np.isfinite(v)) and v.shape == (n,) for v in traj.diagnostics.values())


def test_a_torque_non_finite_from_the_start_ends_failed_at_the_start(eng, reference):
    """The torque is non-finite at the first sample already: the run must end 'failed' at the
    start time, as the reference's does, and not raise. Fails when the cut keeps no row at all
    (the run then raises on its empty time axis)."""
    sc = dataclasses.replace(get_scenario("stability-psid5"), torques=_nan_from(0.0),
                             grid=(0.0, 0.01, 3))
    ref = reference.simulate(sc)
    traj = eng.simulate(sc)
    assert traj.status == ref.status == "failed"
    assert traj.t_end == ref.t_end == 0.0


# -- a completed run --------------------------------------------------------------------------

def test_a_completed_run_says_what_the_reference_says_and_reports_progress(leaned, reference):
    """A run that reaches the end: 'completed' with the reference's message; the initial state's
    correction is the reference's (the same projected start, docs/engines.md); `progress` is
    called with each output sample's time after the first (the module: 'called with the time
    reached at every output sample'). Fails when the completed message is changed, when the
    correction is lost or renamed, when `progress` is dropped, not called or called with
    another time."""
    traj, _, calls = leaned
    ref = reference.simulate(LEANED)
    assert traj.status == ref.status == "completed"
    assert traj.message == ref.message == "reached the end of the grid"
    assert traj.settings["initial_correction"] == ref.settings["initial_correction"]
    assert traj.settings["beta_correction"] == ref.settings["beta_correction"]
    assert calls == LEANED.t[1:].tolist()
    np.testing.assert_array_equal(traj.t, LEANED.t)
    assert traj.t_end == LEANED.t[-1]


def test_the_run_is_labelled_as_mujoco_with_its_contact(leaned):
    """The convergence judgment labels an engine's run from its settings' 'engine' and
    'contact' (comparisons/judgments/convergence.py `_engine_label`): MuJoCo on the disc
    contact. The fall limit the run used is recorded (settings: what determines the result).
    Fails when the keys or the engine's name are changed."""
    from comparisons.judgments.convergence import _engine_label
    traj, _, _ = leaned
    assert _engine_label(traj) == "mujoco (disc contact)"
    assert traj.settings["fall_limit"] == 1.4


def test_timing_counts_the_steps_and_bounds_its_seconds(leaned):
    """timing: the wall time of the call and the stepping's share of it, both within the
    call's own duration measured here, and MuJoCo's step count: 0.1 s at 1e-4 s is 1000 steps.
    Fails when a time is a sum instead of a difference, missing, or the dict is lost; when a
    step is taken after the grid's end."""
    traj, took, _ = leaned
    tm = traj.timing
    assert set(tm) == {"wall_seconds", "solve_seconds", "steps"}
    assert 0 < tm["solve_seconds"] <= tm["wall_seconds"] <= took
    assert tm["steps"] == 1000


def test_residuals_and_contact_diagnostics_agree_with_the_reference_model(leaned, disc):
    """C is the reference model's residuals on MuJoCo's states (the module), and they hold what
    the diagnostics measure a second way: [rD_z, vC_x, vC_y, vD_x, vD_y] are the front
    contact's height and the horizontal velocities of both wheels' material points at their
    contact points (the knife-edge discs' lowest points), with zc = 0. MuJoCo's zc slides the
    whole bicycle vertically, which changes neither horizontal velocity, so slip_speed_rear =
    |(vC_x, vC_y)| and slip_speed_front = |(vD_x, vD_y)|, and it lowers both lowest points
    alike, so penetration_front - penetration_rear = -rD_z. On this leaned, steered run both
    components of both slips are non-zero. 1e-12 (m/s, m): each side is round-off of O(1) m/s
    and O(1) m numbers (measured 7e-16); dropping a slip component changes it by >= 2e-11,
    swapping a column by ~5e-5. Fails when the slip uses the wrong components, when a
    diagnostic reads another column, when C is lost."""
    traj, _, _ = leaned
    np.testing.assert_array_equal(traj.C, disc.constraint_residual(traj.q, traj.dq))
    C, D = traj.C, traj.diagnostics
    assert np.abs(C[1:, 1:]).min() > 4e-8                     # every component non-zero
    np.testing.assert_allclose(D["slip_speed_rear"], np.hypot(C[:, 1], C[:, 2]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(D["slip_speed_front"], np.hypot(C[:, 3], C[:, 4]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(D["penetration_front"] - D["penetration_rear"], -C[:, 0],
                               rtol=0, atol=1e-12)
    assert np.abs(D["penetration_rear"][1:]).min() > 1e-8       # not a zero that any swap keeps
    assert D["normal_force_rear"][-1] > 100 and D["normal_force_front"][-1] > 100


def test_ddq_is_the_straight_rolls_acceleration(eng, disc):
    """ddq is MuJoCo's qacc at each sample's state with that sample's loads. Upright and
    straight the bicycle has one degree of freedom: m_eff dv/dt = Mped / R_rear - cv v^2 with
    m_eff = sum m_i + I2yy / R_rear^2 + I5yy / R_front^2 (the pedal's power Mped v / R_rear, the
    drag's -cv v^3). From the first step on (at the start the contact carries no load yet:
    zero penetration) ddq_xc follows it within 1e-8 m/s^2 (measured 3e-9: the soft contact's
    slip; the law itself is 0.15 m/s^2). Fails when ddq is lost."""
    p = disc.params
    Mped = 5.0
    sc = dataclasses.replace(get_scenario("check-forward"), torques=(0.0, Mped, 0.0),
                             grid=(0.0, 0.01, 6))
    traj = eng.simulate(sc)
    m_eff = p.m2 + p.m3 + p.m4 + p.m5 + p.I2yy / p.R_rear**2 + p.I5yy / p.R_front**2
    v = traj.dq[1:, 0]
    np.testing.assert_allclose(traj.ddq[1:, 0], (Mped / p.R_rear - p.cv * v**2) / m_eff,
                               rtol=0, atol=1e-8)


# -- options and their refusals ---------------------------------------------------------------

def test_t_end_cuts_the_grid(eng):
    """t_end stops the run early on the grid (docs/engines.md). Fails when t_end is ignored."""
    traj = eng.simulate(LEANED, t_end=0.02)
    assert traj.status == "completed"
    np.testing.assert_array_equal(traj.t, LEANED.t[:3])


def test_reference_only_options_are_ignored_and_listed(eng, leaned):
    """rtol, atol, constraints, baumgarte are accepted, change nothing and are listed in
    settings['ignored_options'] (the module's docstring). Fails when one of them is popped
    under another name."""
    traj = eng.simulate(LEANED, rtol=1e-6, constraints="projection", baumgarte=(1.0, 1.0))
    assert traj.settings["ignored_options"] == ["baumgarte", "constraints", "rtol"]
    np.testing.assert_array_equal(traj.q, leaned[0].q)
    assert leaned[0].settings["ignored_options"] == []


def test_settings_given_to_simulate_run_as_an_engine_built_with_them(disc):
    """Any MjcfSettings field given to simulate overrides the engine's for that run: the run
    equals the one of an engine built with those settings, bit for bit (the same compiled
    settings, MuJoCo is deterministic); solref and solimp may be text, as --engine-option gives
    them (docs/engines.md). Fails when the run's model is built with the engine's own settings,
    when solref's or solimp's text is not converted."""
    sc = dataclasses.replace(LEANED, grid=(0.0, 0.01, 4))
    solimp = (0.95, 0.999, 0.002, 0.5, 2.0)
    traj = MujocoEngine(disc).simulate(sc, solref="1e-3, 1", solimp="0.95 0.999 0.002 0.5 2",
                                       timestep=2e-4)
    built = MujocoEngine(disc, solref=(1e-3, 1.0), solimp=solimp, timestep=2e-4).simulate(sc)
    assert traj.status == built.status == "completed"
    for name in ("q", "dq", "ddq"):
        np.testing.assert_array_equal(getattr(traj, name), getattr(built, name))
    for name, values in built.diagnostics.items():
        np.testing.assert_array_equal(traj.diagnostics[name], values)
    assert traj.settings["solref"] == [1e-3, 1.0] and traj.settings["solimp"] == list(solimp)
    assert traj.timing["steps"] == 150                        # 0.03 s at 2e-4 s


def test_a_grid_that_starts_off_zero(eng):
    """A grid starting at 1.23456 s (a recording's clock) runs as one starting at 0: MuJoCo's
    dynamics do not read its clock and the torques are constant, so the states are the same
    bit for bit, and the times are the scenario's own. Fails when the output interval or the
    run's span is computed with the start time added (the step then no longer divides them:
    a refusal)."""
    sc = dataclasses.replace(LEANED, grid=(1.23456, 0.01, 4))
    traj = eng.simulate(sc)
    zero = eng.simulate(dataclasses.replace(LEANED, grid=(0.0, 0.01, 4)))
    np.testing.assert_array_equal(traj.t, sc.t)
    np.testing.assert_array_equal(traj.q, zero.q)


#: MjcfSettings' fields as docs/engines.md's options table lists them (engine.py's docstring)
FIELDS = ("timestep, integrator, solref, solimp, friction, cone, condim, noslip_iterations, "
          "solver, iterations, tolerance, wheel_half_width")


@pytest.mark.parametrize("options, message", [
    (dict(stiffness=1e6, damping=2.0),
     "MuJoCo simulate got unknown option(s) stiffness, damping; it takes fall_limit, t_end, "
     f"progress and {FIELDS}"),
    (dict(friction=0.0),
     "MuJoCo option: MJCF setting friction = 0.0: must be a positive finite number; fix: a "
     "sliding friction coefficient, e.g. 2"),
    (dict(timestep=3e-4),       # 33 or 34 steps of the 0.01 s interval land on the samples
     "MuJoCo timestep = 0.0003 s must divide the output interval 0.01 s and the run's duration "
     f"0.1 s (the steps must land on the output samples); fix: timestep={0.01 / 33:.10g} or "
     f"{0.01 / 34:.10g}"),
], ids=["unknown", "bad-value", "timestep"])
def test_a_bad_option_is_refused_in_one_line_naming_it(eng, options, message):
    """Refused before anything runs, one `EngineUsageError` line that names the option and the
    fix (docs/engines.md). Fails when the unknown options are joined otherwise, when the
    settings' own refusal is lost, when the step's refusal names another engine or option."""
    with pytest.raises(EngineUsageError) as err:
        eng.simulate(LEANED, **options)
    assert str(err.value) == message


def test_a_solimp_text_that_is_not_numbers_is_refused_naming_solimp(eng):
    """Fails when the text's conversion is not told which option it converts."""
    with pytest.raises(EngineUsageError, match=r"^MuJoCo option solimp = '0\.9 nope': not a list "
                       r"of numbers; fix: e\.g\. solimp=0\.99,0\.999,0\.001,0\.5,2"):
        eng.simulate(LEANED, solimp="0.9 nope")


def test_an_inverse_scenario_is_refused_naming_mujoco(eng):
    """Fails when the refusal names another engine or none."""
    with pytest.raises(EngineUsageError) as err:
        eng.simulate(Scenario("steer", "", "inverse"))
    assert str(err.value) == ("scenario 'steer' is an inverse scenario; MuJoCo runs only forward "
                              "scenarios")


# -- the torques --------------------------------------------------------------------------------

class _Recorder:
    """A torque function that takes arrays (`_ramp`) and records what it was called with."""

    def __init__(self):
        self.calls: list[np.ndarray] = []

    def __call__(self, t):
        self.calls.append(np.array(t, dtype=float))
        return _ramp(t)


def test_a_torque_function_that_takes_arrays_is_called_once_on_every_steps_time(eng):
    """'torque(t) at every step: one vectorised call where the function takes arrays' (the
    module): one call, with the times of the steps' starts and the run's end, t0 + i h for
    i = 0 .. 200 over 0.02 s (1e-15 s: i h against the module's t0 + h i, round-off), and the
    rows' torques are the function's at their times. 10 000 calls per simulated second
    otherwise. Fails when the vectorised call is skipped or its result refused, when it is
    asked for one time past the run's end."""
    rec = _Recorder()
    traj = eng.simulate(dataclasses.replace(LEANED, torques=rec, grid=(0.0, 0.01, 3)))
    assert traj.status == "completed"
    assert len(rec.calls) == 1
    np.testing.assert_allclose(rec.calls[0], H * np.arange(201), rtol=0, atol=1e-15)
    np.testing.assert_allclose(traj.T, _ramp(traj.t), rtol=0, atol=1e-15)


def test_a_torque_function_of_one_time_only_is_called_step_by_step(eng):
    """A rider torque written with a Python `if` on t cannot take an array (numpy refuses the
    truth value of one): it is evaluated at each step, and the run equals the one with the same
    torques written for arrays, bit for bit. Fails when the per-step call is lost, called with
    something else than the step's time, or its result shaped wrongly."""
    def pulse(t):
        return (0.0, 1.0 if t < 0.015 else 2.0, 0.0)

    def pulse_array(t):
        t = np.asarray(t, dtype=float)
        return np.stack([0.0 * t, np.where(t < 0.015, 1.0, 2.0), 0.0 * t], axis=-1)

    sc = dataclasses.replace(LEANED, grid=(0.0, 0.01, 3))
    traj = eng.simulate(dataclasses.replace(sc, torques=pulse))
    vec = eng.simulate(dataclasses.replace(sc, torques=pulse_array))
    np.testing.assert_array_equal(traj.T, [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.0]])
    np.testing.assert_array_equal(traj.q, vec.q)
    np.testing.assert_array_equal(traj.dq, vec.dq)


def test_a_torque_function_that_returns_one_row_for_any_input(eng):
    """A function returning the same [Mdir, Mped, Mvue] whatever it is given (an array of times
    too) runs as those constant torques: its result for the array is not the (n, 3) of the
    steps, so it is called per step. Fails when a wrongly shaped vectorised result is taken."""
    sc = dataclasses.replace(LEANED, grid=(0.0, 0.01, 3))
    traj = eng.simulate(dataclasses.replace(sc, torques=lambda t: [0.0, 1.0, 0.0]))
    const = eng.simulate(dataclasses.replace(sc, torques=(0.0, 1.0, 0.0)))
    np.testing.assert_array_equal(traj.q, const.q)
    np.testing.assert_array_equal(traj.T, const.T)


# -- the stepping and the loads ---------------------------------------------------------------

@pytest.mark.parametrize("integrator", ["RK4", "implicit"])
def test_without_loads_a_run_is_mujocos_own_stepping(disc, integrator):
    """With no torques and no drag (cv = 0) nothing of ours enters a step: the run's states
    must be MuJoCo's own mj_step from the same start on the same compiled model, bit for bit
    (1e-12: MuJoCo is deterministic; measured 0). An RK4 run must be stepped by mj_step (its
    mj_step2 integrates with Euler: 8e-8 rad, 5e-7 rad/s away after these 10 steps). The
    settings' 'loads' line, the contact study's row (engines/mujoco/contact_study.py), says
    how the loads are applied, the RK4 stages only for RK4 (docs/engines.md: xfrc_applied set
    from mj_step1's kinematics); its 'rear_height_joint' row describes the zc joint, read back
    here from MuJoCo's model. Fails when RK4 is not recognised (or every integrator is taken
    for it), when mj_step is called wrongly, when a step is taken after the grid's end."""
    model = disc.with_params(disc.params.replace(cv=0.0))
    sc = dataclasses.replace(get_scenario("stability-psid5"), torques=(0.0, 0.0, 0.0),
                             grid=(0.0, 1e-3, 2))
    eng = MujocoEngine(model, integrator=integrator)
    traj = eng.simulate(sc)
    _, m = eng.run_model()
    adr = [int(m.joint(name).qposadr[0]) for name in COORDINATES]
    init = initial_state(model, sc)
    d = mujoco.MjData(m)
    d.qpos[adr], d.qvel[adr] = init.q, init.dq
    for _ in range(10):
        mujoco.mj_step(m, d)
    np.testing.assert_allclose(traj.q[-1], d.qpos[adr], rtol=0, atol=1e-12)
    np.testing.assert_allclose(traj.dq[-1], d.qvel[adr], rtol=0, atol=1e-12)
    assert traj.timing["steps"] == 10
    loads = "rider torques and drag as xfrc_applied, set each step from mj_step1's kinematics"
    assert traj.settings["loads"] == loads + (" and held over the RK4 stages"
                                              if integrator == "RK4" else "")
    zc = m.joint(2)
    assert (zc.name, m.joint(1).name) == ("zc", "yc")
    assert zc.type[0] == mujoco.mjtJoint.mjJNT_SLIDE and list(zc.axis) == [0.0, 0.0, 1.0]
    assert traj.settings["rear_height_joint"] == ("zc, a slide along z after yc (free: the rear "
                                                  "wheel rests on its contact)")


@pytest.mark.parametrize("cv", [0.0, 0.7])
def test_the_loads_are_the_documented_body_wrenches(eng, disc, cv):
    """_Bicycle.loads on a general state of the run's model (yawed, leaned, steered, pitched,
    every rate non-zero): the steer torque about the fork's z axis, the pedal torque about the
    rear wheel's y axis, the anti-roll torque about the frame's x axis (each axis a column of
    MuJoCo's xmat), and the drag -cv |v| v at the frame's CoM with v that point's velocity from
    MuJoCo's mj_objectVelocity (its own spatial arithmetic); nothing on any other body. Without
    drag (cv = 0) the module takes a shorter path, checked too. 1e-12 (N, N m): round-off of
    O(1-10) products. Fails when a torque reads another axis entry or divides by it, when the
    CoM's velocity is transported with a sign error, when |v| has a sign error."""
    _, m = eng.run_model()
    params = disc.params.replace(cv=cv)
    bike = _Bicycle(m, params)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(7)
    d.qpos[:] = rng.uniform(-0.6, 0.6, m.nq)
    d.qvel[:] = rng.uniform(-3.0, 3.0, m.nv)
    mujoco.mj_forward(m, d)
    T = (1.3, -2.1, 0.7)
    bike.loads(d, T)
    body = {name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
            for name in ("fork", "rear_wheel", "frame")}
    axis = lambda name, i: d.xmat[body[name]].reshape(3, 3)[:, i]
    vel = np.zeros(6)
    mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, body["frame"], vel, 0)
    v = vel[3:]
    expected = np.zeros((m.nbody, 6))
    expected[body["fork"], 3:] = T[0] * axis("fork", 2)
    expected[body["rear_wheel"], 3:] = T[1] * axis("rear_wheel", 1)
    expected[body["frame"], 3:] = T[2] * axis("frame", 0)
    expected[body["frame"], :3] = -cv * np.linalg.norm(v) * v
    assert np.abs(axis("frame", 0)[:2]).min() > 0.1 and np.abs(v).min() > 0.1   # general
    np.testing.assert_allclose(d.xfrc_applied, expected, rtol=0, atol=1e-12)
