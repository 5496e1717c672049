"""DART's forward run (engines/dart/run.py) held to the forward-run contract of docs/engines.md
("### `simulate`": status, message, t_end, the final row of a fall, the partial trajectory of a
failed run) and to the module's docstring: the samples on the scenario's grid are DART's states
at every `per`-th step (the same run sampled at every step, read in the test), ddq is the
velocity change of the step ending at each sample over the step (finite differences of that
per-step run), the torques are the scenario's torque function evaluated in the test, C is the
reference model's residual on the run's states, the first row is the projected initial state,
the fall ends the run at the first step whose |theta| reaches the limit (located in the test
from the per-step run), a non-finite state (planted in DART's world by a wrapper around its
step) ends the run at the last good sample with its one-line message; the options
(engines/dart/options.py, docs/engines.md's table) reach the run, each bad one refused in one
line; the run's settings and timing. Each test names the planted bugs (mutmut's survivors of
the module's first measurement) it fails on.

Scenarios are cut to 20 ms (40 DART steps of 5e-4 s, a few ms each run); the grid starts at
t0 = 0.1 ms, off the step lattice, so that a grid read from its second sample or an interval
summed instead of differenced shows.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import pytest

from engines import EngineUsageError
from reference_model import load_model
from reference_model.scenarios import get_scenario, initial_state, torque_input

dart = pytest.importorskip("dartpy")

import engines.dart.run as dart_run  # noqa: E402
from engines.dart import DartEngine  # noqa: E402
from engines.dart.options import RunSettings  # noqa: E402

#: the grid's start (s), not a multiple of the default step 5e-4 s
T0 = 1e-4
#: the output interval (s): 4 DART steps at the default 5e-4 s
DT = 2e-3
#: DART's default step (options.py, docs/engines.md's table)
H = 5e-4
N = 11
PER = round(DT / H)
DIAGNOSTICS = ("slip_speed_rear", "penetration_rear", "slip_speed_front", "penetration_front",
               "normal_force_rear", "normal_force_front")
THETA = 3


def _short(name, dt=DT, n=N):
    return dataclasses.replace(get_scenario(name), grid=(T0, dt, n))


@pytest.fixture(scope="module")
def model():
    return load_model("thesis-disc")


@pytest.fixture(scope="module")
def engine(model):
    return DartEngine(model)


@pytest.fixture(scope="module")
def rolling(engine):
    """stability-psid10 (rolling at 10 rad/s, leaned 0.196 rad) on the 2 ms grid, with the
    times the progress callback was given and the wall time around the call."""
    calls = []
    w0 = time.perf_counter()
    run = engine.simulate(_short("stability-psid10"), progress=calls.append)
    return run, calls, time.perf_counter() - w0


@pytest.fixture(scope="module")
def per_step(engine):
    """The same run sampled at every DART step (grid interval = the step, so per = 1)."""
    return engine.simulate(_short("stability-psid10", dt=H, n=(N - 1) * PER + 1))


@pytest.fixture(scope="module")
def falling(engine):
    """stability-psid0 (standing still, leaned 0.196 rad: it falls) sampled at every step, with
    no fall limit in reach: the lean at every step, to locate a fall in."""
    return engine.simulate(_short("stability-psid0", dt=H, n=(N - 1) * PER + 1), fall_limit=10.0)


def test_a_completed_run_is_darts_states_on_the_scenarios_grid(rolling, per_step, model):
    """Contract: status 'completed', message "reached the end of the grid" (the module's
    status message, whole), t the scenario's grid and t_end its last sample. The samples are
    DART's states after every 4th step: the per-step run's rows 0, 4, ..., 40, bit for bit
    (the same world, loads and steps). The first row is the projected initial state
    (initial_state, the same for every engine) with ddq = 0; C is the reference model's
    constraint_residual on the run's states (an independent evaluation here, round-off).
    Fails when zc is inserted at the wrong place in the initial state or deleted from the
    wrong place in dq or ddq, when the grid is stepped one step too far or too short, when the
    first sample is stamped grid[1], when t_end is not the last sample, when C, dq or ddq is
    dropped or C is flattened."""
    run, _, _ = rolling
    sc = _short("stability-psid10")
    assert run.status == "completed"
    assert run.message == "reached the end of the grid"
    assert np.array_equal(run.t, sc.t)
    assert run.t_end == sc.t[-1]
    init = initial_state(model, sc)
    assert np.array_equal(run.q[0], init.q) and np.array_equal(run.dq[0], init.dq)
    assert np.array_equal(run.ddq[0], np.zeros(8))
    for name in ("q", "dq", "ddq"):
        got = getattr(run, name)
        assert got.shape == (N, 8)
        assert np.array_equal(got, getattr(per_step, name)[::PER])
    C = np.asarray(model.constraint_residual(run.q, run.dq), dtype=float).reshape(N, 5)
    assert run.C.shape == (N, 5)
    assert np.allclose(run.C, C, rtol=0, atol=1e-15)
    assert run.timing["steps"] == (N - 1) * PER


def test_ddq_is_the_velocity_change_of_the_step_ending_at_each_sample(per_step):
    """The module's docstring: ddq at a sample is the velocity change of the step that ends
    there over the step; sampled at every step that is the finite difference of consecutive
    dq rows over h = 5e-4 s, formed here from the rows (round-off: velocities of ~10 rad/s,
    differences of ~1e-3 over 5e-4: 1e-9 relative to the largest is far above it and far below
    a factor h^2 or a sum of velocities). Fails when the change is multiplied by h or the
    velocities are added."""
    expected = np.diff(per_step.dq, axis=0) / H
    got = per_step.ddq[1:]
    assert np.allclose(got, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    assert np.abs(expected).max() > 1.0


def test_early_on_the_run_follows_the_reference(rolling, model):
    """Over the first 20 ms DART's contact agrees with the reference's run of the same
    scenario (docs/engines.md: the run leaves the reference at first order in the step,
    5.4e-5 at 0.1 s; the bound 2e-5 rad or m here is that rate over 20 ms with a factor 2);
    the normal forces are zero at t0 (docs: "zero at t = 0, before any step") and carry the
    bicycle's 827 N within 10 % afterwards (measured 769 N: the CoMs accelerate downward as it
    leans, tests/test_dart.py's Newton balance; a dropped or swapped column reads a slip or a
    depth, < 1e-2). Measured q error 1.1e-5. Fails when a
    diagnostics column is dropped or the coordinates read from the wrong DART dofs."""
    from engines.reference import ReferenceEngine
    run, _, _ = rolling
    ref = ReferenceEngine(model).simulate(_short("stability-psid10"))
    assert np.abs(run.q - ref.q).max() < 2e-5
    assert set(run.diagnostics) == set(DIAGNOSTICS)
    d = run.diagnostics
    for key in DIAGNOSTICS:
        assert d[key].shape == (N,) and d[key].dtype == float
    p = model.params
    weight = (p.m2 + p.m3 + p.m4 + p.m5) * p.g
    assert d["normal_force_rear"][0] == 0.0 and d["normal_force_front"][0] == 0.0
    assert np.allclose(d["normal_force_rear"][1:] + d["normal_force_front"][1:], weight,
                       rtol=0.1)


def test_the_torques_are_the_scenarios_torque_function_at_each_sample(engine, model):
    """replay's torques are the zigzag spline (torque_input, a function of t, evaluated here
    at the grid's times and at the fall step's time); T holds them at each sample, exactly
    (the same float evaluation). Fails when the torque is evaluated at other times (a grid
    shifted by one sample, the step times built from the second sample or with h divided),
    when the first row takes the next step's torque, when the function is treated as a
    constant, when the torques are not evaluated on the model, or when T is dropped."""
    sc = _short("replay")
    f = torque_input(model, sc)
    run = engine.simulate(sc)
    assert run.status == "completed"
    expected = np.array([np.asarray(f(t), dtype=float).reshape(3) for t in sc.t])
    assert run.T.shape == (N, 3) and run.T.dtype == float
    assert np.array_equal(run.T, expected)


def test_constant_torques_fill_every_row(engine):
    """A constant [Mdir, Mped, Mvue] (docs: "a constant ... or a function of t") is the T of
    every row."""
    run = engine.simulate(dataclasses.replace(_short("stability-psid10"),
                                              torques=(0.5, -1.0, 2.0)))
    assert np.array_equal(run.T, np.tile([0.5, -1.0, 2.0], (N, 1)))


def test_progress_is_called_with_the_time_of_every_sample_reached(rolling):
    """The simulate docstring: progress is "called with the time reached at every output
    sample": the grid's times after the start, each a float. Fails when the option is dropped
    or the callback gets None or a wrong index."""
    run, calls, _ = rolling
    assert calls == [float(t) for t in run.t[1:]]
    assert all(type(c) is float for c in calls)


def test_timing_is_the_runs_wall_time_and_steps(rolling):
    """timing: wall and solve seconds, each between 0 and the wall time the test measured
    around the call (solve inside wall), and the number of DART steps taken. Fails when a
    start time is added instead of subtracted or a timing is dropped."""
    run, _, outside = rolling
    tm = run.timing
    assert 0.0 < tm["solve_seconds"] <= tm["wall_seconds"] <= outside
    assert tm["steps"] == (N - 1) * PER


def _fall_step(falling, limit):
    """The first step index at which the per-step run's |theta| reaches ``limit``."""
    return int(np.flatnonzero(np.abs(falling.q[:, THETA]) >= limit)[0])


def test_a_fall_ends_at_the_first_step_reaching_the_limit(engine, falling, model):
    """Contract: status 'fell', "the final row is the fall itself". The fall limit is set to
    DART's own |theta| at step 23 of the per-step run (read back), so the first step reaching
    it is step 23 (t = t0 + 23 h), between the grid's samples 5 and 6: the run holds samples
    0..5, then step 23's state, velocity change over h and torques; t_end is its time; the
    message, whole: "|theta| reached the fall limit {limit:.4f} rad at t = {t:.6f} s"; the
    settings record the fall limit; progress saw samples 1..5. Fails when the fall is taken at
    |theta| > limit (one step later), when the lean is read from another dof, when the fall
    row's time, torques or ddq is dropped or ddq is scaled by h^2 or adds the velocities,
    when the loop returns instead of ending the run, or when fall_limit is not read."""
    m = 23
    limit = abs(float(falling.q[m, THETA]))
    assert _fall_step(falling, limit) == m
    calls = []
    sc = _short("stability-psid0")
    run = engine.simulate(sc, fall_limit=limit, progress=calls.append)
    t_fall = T0 + m * H
    assert run.status == "fell"
    assert run.message == f"|theta| reached the fall limit {limit:.4f} rad at t = {t_fall:.6f} s"
    assert np.array_equal(run.t[:-1], sc.t[:6])
    assert run.t[-1] == pytest.approx(t_fall, rel=0, abs=1e-15) and run.t_end == run.t[-1]
    assert np.array_equal(run.q[-1], falling.q[m]) and np.array_equal(run.dq[-1], falling.dq[m])
    assert np.allclose(run.ddq[-1], (falling.dq[m] - falling.dq[m - 1]) / H, rtol=0,
                       atol=1e-9 * np.abs(falling.ddq).max())
    assert np.array_equal(run.T[-1], [0.0, 1.0, 0.0])       # stability-psid0's constant torques
    assert run.C.shape == (7, 5)
    assert run.settings["fall_limit"] == limit
    assert calls == [float(t) for t in sc.t[1:6]]
    assert run.timing["steps"] == m


def test_a_start_at_the_fall_limit_is_a_fall_at_the_start(engine, model):
    """|theta| at the start equal to the fall limit (0.196 rad, the projected initial lean,
    read from initial_state) is a fall there: one row (the initial state), no step, t_end the
    start, and the message, whole: "|theta| = 0.196 rad >= fall limit at the start". Fails
    when the start's test is strict, when the run still takes a step, or when the status or
    message is dropped."""
    sc = _short("stability-psid0")
    theta0 = abs(float(initial_state(model, sc).q[THETA]))
    run = engine.simulate(sc, fall_limit=theta0)
    assert run.status == "fell"
    assert run.message == f"|theta| = {theta0:.3f} rad >= fall limit at the start"
    assert run.message == "|theta| = 0.196 rad >= fall limit at the start"
    assert run.t.tolist() == [T0] and run.t_end == T0 and run.q.shape == (1, 8)
    assert run.timing["steps"] == 0


class _PoisonedWorld:
    """DART's world with its step wrapped: after step ``at`` (1-based) DART's position or
    velocity of the dof named ``dof`` is set to NaN, as a diverging solver would leave it."""

    def __init__(self, world, bike, at, dof, what):
        self._world, self._bike, self._at, self._n = world, bike, at, 0
        self._i, self._what = bike.getDof(dof).getIndexInSkeleton(), what

    def __getattr__(self, name):
        return getattr(self._world, name)

    def step(self):
        self._world.step()
        self._n += 1
        if self._n == self._at:
            if self._what == "position":
                self._bike.setPosition(self._i, math.nan)
            else:
                self._bike.setVelocity(self._i, math.nan)


@pytest.fixture
def poison(monkeypatch):
    """Plants a NaN in the next run's world after step ``at``."""
    def plant(at, dof, what):
        real = dart_run.build_world

        def build(params, s):
            rw = real(params, s)
            rw.world = _PoisonedWorld(rw.world, rw.bike, at, dof, what)
            return rw
        monkeypatch.setattr(dart_run, "build_world", build)
    return plant


def _failed_message(k):
    return (f"DART's state became non-finite between t = {T0 + (k - 1) * H:.6f} and "
            f"{T0 + k * H:.6f} s; the run ends at the last sample before")


def test_a_non_finite_lean_between_samples_fails_the_run_at_once(engine, rolling, poison):
    """Contract: 'failed', the partial trajectory up to the last good sample, the reason in
    one line, never NaN in the arrays. A NaN lean after step 10 (between samples 2 and 3):
    the run holds samples 0..2 (the clean run's), and the message names the step, whole.
    Fails when a non-finite lean is only noticed together with non-finite velocities at a
    sample, or when the loop returns instead of ending the run."""
    poison(10, "theta", "position")
    run = engine.simulate(_short("stability-psid10"))
    clean, _, _ = rolling
    assert run.status == "failed"
    assert run.message == _failed_message(10)
    assert np.array_equal(run.q, clean.q[:3]) and run.t_end == clean.t[2]
    assert np.isfinite(run.q).all() and np.isfinite(run.dq).all()


def test_a_non_finite_velocity_at_a_sample_fails_the_run(engine, rolling, poison):
    """A NaN steer rate (the lean finite) after step 12, which ends sample 3: the velocities
    are checked at every sample, so the run fails there with samples 0..2. Fails when they are
    checked only at a sample that is also a fall."""
    poison(12, "gamma", "velocity")
    run = engine.simulate(_short("stability-psid10"))
    clean, _, _ = rolling
    assert run.status == "failed"
    assert run.message == _failed_message(12)
    assert np.array_equal(run.q, clean.q[:3])
    assert np.isfinite(run.dq).all()


def test_a_non_finite_velocity_at_the_fall_fails_the_run(engine, falling, poison):
    """A NaN steer rate after step 23 (between samples), where |theta| is exactly the fall
    limit (DART's own lean at that step, read from the per-step run): a fall row would carry
    NaN, so the run is 'failed' with samples 0..5. Fails when the fall's velocity check is
    strict (|theta| > limit)."""
    m = 23
    limit = abs(float(falling.q[m, THETA]))
    poison(m, "gamma", "velocity")
    run = engine.simulate(_short("stability-psid0"), fall_limit=limit)
    assert run.status == "failed"
    assert run.message == _failed_message(m)
    assert run.t.size == 6 and np.isfinite(run.dq).all()


def test_t_end_cuts_the_grid(engine):
    """t_end (s, stop early: the simulate docstring, docs/engines.md) stops the run at the last
    grid sample at or before it: 10.5 ms keeps samples 0..5 (t0 + 5 x 2 ms = 10.1 ms), status
    'completed'. Fails when t_end is not read or not passed on."""
    sc = _short("stability-psid10")
    run = engine.simulate(sc, t_end=0.0105)
    assert run.status == "completed"
    assert np.array_equal(run.t, sc.t[:6]) and run.t_end == sc.t[5]


def test_an_inverse_scenario_is_refused_in_one_line_naming_dart(engine):
    """docs/engines.md: simulate runs forward scenarios; the refusal names the engine."""
    with pytest.raises(EngineUsageError) as err:
        engine.simulate(get_scenario("check"))
    assert str(err.value) == "scenario 'check' is an inverse scenario; DART runs only forward scenarios"


def test_a_timestep_that_does_not_divide_the_interval_is_refused_in_one_line(engine):
    """The step must divide the sampling interval (docs/engines.md's table); 3e-4 s does not
    divide 2 ms: the message names DART's option, the interval and the run's duration
    (10 x 2 ms = 20 ms) and the two nearest steps that do (2/6 and 2/7 ms). Fails when the
    engine or option name is dropped or the interval or duration is misformed."""
    with pytest.raises(EngineUsageError) as err:
        engine.simulate(_short("stability-psid10"), timestep=3e-4)
    assert str(err.value) == (
        "DART timestep = 0.0003 s must divide the output interval 0.002 s and the run's "
        "duration 0.02 s (the steps must land on the output samples); fix: "
        f"timestep={DT / 6:.10g} or {DT / 7:.10g}")


def test_an_unknown_option_is_refused_in_one_line_listing_the_options(engine):
    """An unknown option is refused before anything runs, naming it and listing what
    simulate takes (the documented option names: options.py's fields, docs/engines.md)."""
    with pytest.raises(EngineUsageError) as err:
        engine.simulate(_short("stability-psid10"), step=1e-3, method="rk4")
    assert str(err.value) == (
        "DART simulate got unknown option(s) step, method; it takes fall_limit, t_end, progress "
        "and timestep, collision_detector, friction, solver, wheel_half_width, split_impulse")


def test_a_bad_option_value_is_refused_in_one_line(engine):
    """options.py's rule, applied to a run's option: a friction of -1 is refused naming the
    option and the default as the fix."""
    with pytest.raises(EngineUsageError) as err:
        engine.simulate(_short("stability-psid10"), friction=-1.0)
    assert str(err.value) == ("DART option friction = -1.0: must be a positive number; fix: "
                              "e.g. friction=2.0")


def test_a_runs_options_override_the_engines_settings(model):
    """An option given to simulate replaces that one setting for the run; the engine's other
    settings stay (here an engine at friction 0.8 and PGS run with timestep 2.5e-4 s: 8 steps
    per 2 ms sample, 80 in all). Reference-only options (rtol, atol, constraints, baumgarte)
    are accepted and listed in the settings as ignored. Fails when the options are ignored,
    the engine's settings dropped, a valid option taken for unknown, or a reference-only
    option popped under the wrong name."""
    eng = DartEngine(model, friction=0.8, solver="pgs")
    run = eng.simulate(_short("stability-psid10"), timestep=2.5e-4, rtol=1e-9, baumgarte=(1, 1))
    assert run.status == "completed"
    s = run.settings
    assert (s["timestep"], s["friction"], s["solver"]) == (2.5e-4, 0.8, "pgs")
    assert (s["collision_detector"], s["wheel_half_width"], s["split_impulse"]) == ("ode", 1e-6,
                                                                                   False)
    assert s["ignored_options"] == ["baumgarte", "rtol"]
    assert run.timing["steps"] == 80
    assert s["grid"] == "scenario grid (every 8 steps)"


def test_the_runs_settings_record_what_determines_it(rolling, model):
    """docs/engines.md: "settings is a dict of what determines the result"; every option of
    the table at its default, the engine and DART's version (dartpy's own), the contact, the
    fall limit (the scenario's 1.4 rad), the initial state's correction (initial_state's
    own), no ignored options, and the descriptions the report prints, each whole, with the
    thesis-disc radii (0.35 m), the half-width and friction of the options. Fails when any
    entry is dropped, renamed or reworded."""
    run, _, _ = rolling
    s = run.settings
    init = initial_state(model, _short("stability-psid10"))
    p = model.params
    expected = {
        "engine": "dart", "dart_version": dart.__version__, "contact": model.contact,
        **dataclasses.asdict(RunSettings()),
        "wheels": (f"cylinders of the wheel radii ({p.R_rear:g} m rear, {p.R_front:g} m front), "
                   "half-width 1e-06 m, axis = the axle; ground: a welded box, top face z = 0"),
        "friction_coefficients": "Coulomb 2 (wheels and ground), DART's friction pyramid",
        "integrator": "DART's World.step: semi-implicit Euler, impulses from a boxed LCP",
        "rear_height_joint": ("zc, a prismatic z joint after yc (free: the rear wheel rests on "
                              "its contact)"),
        "loads": "rider torques and drag as external forces, set before each step",
        "fall_limit": 1.4,
        "grid": "scenario grid (every 4 steps)",
        "ddq": "the velocity change of the step ending at each sample, over the step",
        "C": "reference model's constraint_residual on the DART states",
        "diagnostics": ("slip speed and penetration of each wheel's knife-edge disc at its "
                        "lowest point; the ground's vertical force per wheel"),
        "initial_correction": init.describe(), "beta_correction": init.beta_correction,
        "ignored_options": [],
    }
    assert s == expected
    assert set(run.timing) == {"wall_seconds", "solve_seconds", "steps"}


def test_a_start_turned_and_moved_on_the_ground_is_the_same_ride_turned(engine, rolling, model):
    """The ground is level and uniform, gravity vertical: a start moved to (0.3, -0.2) m and
    turned by phi = 0.7 rad is the same ride, its lean, steer and wheel angles equal to the
    unturned run's and its heading 0.7 rad more (1.2e-9 rad measured, the rotated contact
    geometry's round-off; tolerance 1e-7), and its first row is the projected initial state
    exactly. Fails when zc is inserted after phi instead of after yc in DART's start (phi read
    as zc: the bicycle starts 0.7 m up and turned 0)."""
    run = rolling[0]
    q0 = list(_short("stability-psid10").q0)
    q0[0], q0[1], q0[2] = 0.3, -0.2, 0.7
    turned = dataclasses.replace(_short("stability-psid10"), q0=tuple(q0))
    got = engine.simulate(turned)
    assert np.array_equal(got.q[0], initial_state(model, turned).q)
    assert got.status == "completed"
    assert np.abs(got.q[:, 3:] - run.q[:, 3:]).max() < 1e-7
    assert np.abs(got.q[:, 2] - (run.q[:, 2] + 0.7)).max() < 1e-7
