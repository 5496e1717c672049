"""The Exudyn adapter's own pieces (engines/exudyn/engine.py) taken apart: the run monitor that
announces long runs and reports their progress (``_Monitor``, ``_duration``), the step check
(``check_step``), the rider torques as Exudyn loads (``add_torques``, ``_as_spline``,
``_symbolic_spline``), the drag connector (``add_drag``), the fall event between two steps
(``_hermite_event``), the solver's error text, the engine's options and Exudyn settings, its
generalized forces (``TreeForces``), and what ``simulate`` does with its options, a failed or
non-finite run, a fall and its timing.

The engine's runs and terms against the reference are tests/test_exudyn.py's; here each piece
is checked where a run cannot see it, with a planted bug named in each test.

Expected values: the module docstring and the engine's docstrings (the torque targets: steer
[0, 0, Mdir] on the fork, pedal [0, Mped, 0] on the rear wheel, anti-roll [Mvue, 0, 0] on the
frame; "no step-size control"; "no solution or sensor files"; a run estimated longer than
LONG_RUN_SECONDS is announced, re-estimated after MEASURE_AFTER s, reports every PROGRESS_EVERY
s), hand arithmetic on a fake clock (the monitor's lines), scipy's own not-a-knot
``CubicSpline`` and ``CubicHermiteSpline`` (the torque splines, the fall event of a run),
numpy's polynomial roots (the event of a known cubic), the reference model's generalized
forces and constraint residual, and Exudyn's own API read back (its loads, objects and load
values). Runs are 20 steps of 1 ms on a grid that starts at t0 = 0.1 s (so a grid read from
its first sample or an interval summed instead of differenced shows); each takes milliseconds.
"""

from __future__ import annotations

import dataclasses
import types

import numpy as np
import pytest
from numpy.polynomial import Polynomial
from scipy.interpolate import CubicHermiteSpline, CubicSpline

exu = pytest.importorskip("exudyn")

from exudyn.itemInterface import MarkerBodyRigid, ObjectGround  # noqa: E402

from engines import CapabilityError, EngineError, EngineUsageError  # noqa: E402
from engines.exudyn import engine as exudyn_engine  # noqa: E402
from engines.exudyn.engine import (ExudynEngine, TreeForces, _as_spline, _duration,  # noqa: E402
                                   _hermite_event, _Monitor, _solver_error_string, add_drag,
                                   add_torques, check_step)
from engines.exudyn.tree import TreeBuild  # noqa: E402
from exudyn_checks import H, random_states  # noqa: E402
from reference_model.scenarios import SCENARIOS, initial_state  # noqa: E402

T0, DT = 0.1, 0.01
#: stability-psid10 (leaned pi/16, rolling) cut to two output intervals from t0 = 0.1 s: 20 steps
SHORT = dataclasses.replace(SCENARIOS["stability-psid10"], grid=(T0, DT, 3))
WHAT = "exudyn tree on stability-psid10"
#: the module docstring's torque targets: torque k -> (marker, body axis)
TARGETS = {0: ("fork", 2), 1: ("rear", 1), 2: ("frame", 0)}
#: a limit the leaned bicycle's |theta| passes between steps 8 and 9 of SHORT (0.196443 rad at
#: step 8, 0.196467 at step 9: read from the run in ``full`` below)
FALL = 0.19645


@pytest.fixture(scope="module")
def engine(disc):
    return ExudynEngine(disc)


@pytest.fixture(scope="module")
def full(engine):
    """SHORT at every step, no fall (the default limit 1.4 rad): the states a fall is located
    between."""
    return engine.simulate(SHORT, every_step=True)


# -- the run monitor ------------------------------------------------------------------------------

class Clock:
    """perf_counter for the engine module: the time the test sets."""

    def __init__(self, now):
        self.now = now

    def __call__(self):
        return self.now


@pytest.fixture
def clock(monkeypatch):
    c = Clock(1000.0)
    monkeypatch.setattr(exudyn_engine, "time", types.SimpleNamespace(perf_counter=c))
    return c


def _monitor(clock, *args, **kwargs):
    """A monitor started at 1000 s on the fake clock."""
    clock.now = 1000.0
    return _Monitor(*args, **kwargs)


def _steps(monitor, clock, elapsed_and_t):
    for elapsed, t in elapsed_and_t:
        clock.now = 1000.0 + elapsed
        monitor(t)


def test_durations_are_seconds_minutes_or_hours():
    """How long a run takes, in the unit that keeps the number small: whole seconds below 2
    min, whole minutes below 2 h, hours to a tenth beyond. Expected: the arithmetic (7199 s =
    119.98 min, 7200 s = 2 h). Planted: a boundary moved onto its own value (120 s as '120 s',
    7200 s as '120 min'), minutes or hours computed with the wrong divisor."""
    assert _duration(0.4) == "0 s"
    assert _duration(119.4) == "119 s"
    assert _duration(120.0) == "2 min"
    assert _duration(7199.0) == "120 min"
    assert _duration(7200.0) == "2.0 h"
    assert _duration(9000.0) == "2.5 h"


def test_the_measured_cost_is_announced_once_when_the_run_is_long(clock):
    """After MEASURE_AFTER = 2 s of wall time, and not before the second step, the cost per step
    is measured on the run; a run so estimated longer than LONG_RUN_SECONDS = 120 s is announced
    once. On the fake clock: the first step ends 3 s in (no measurement: one step is not a
    cost), the second 14 s in: 7 s per step = 7000.00 ms, 19 steps = 133 s in all ('2 min'),
    133 - 14 = 119 s left; a third step 20 s in says nothing more. Planted: the step counter
    started at 1, set instead of incremented, or stepped by 2; the measurement made at the
    first step or again at the next; the total divided by n_steps; the ms, total or time left
    computed wrongly (left as total + elapsed)."""
    lines = []
    m = _monitor(clock, 19, 0.0, 0.019, "w", lines.append, None, announced=False)
    _steps(m, clock, [(3.0, 0.001)])
    assert lines == []
    _steps(m, clock, [(14.0, 0.002), (20.0, 0.003)])
    assert lines == ["w: measured 7000.00 ms per step: about 2 min in all, 119 s left"]


def test_the_measurement_starts_at_two_seconds_and_a_run_of_120_s_is_not_long(clock):
    """The measurement is made at the first step with at least MEASURE_AFTER = 2 s behind it
    (1.9 s: not yet; 2.0 s exactly: yes), and a run is long only when estimated *longer* than
    120 s: 2.0 s over 2 steps of a 120-step run is 120 s exactly: silent, measured once (a
    later, slower estimate stays silent); 1.9 s after 2 steps of a 200-step run is not yet a
    measurement, 2.0 s after 3 is: 666.67 ms per step, 133 s in all, 131 s left, both '2 min'.
    Planted: '>' for '>=' at 2 s, '>=' for '>' at 120 s."""
    lines = []
    m = _monitor(clock, 120, 0.0, 0.12, "w", lines.append, None, announced=False)
    _steps(m, clock, [(1.0, 0.001), (2.0, 0.002), (50.0, 0.003)])
    assert lines == []
    m = _monitor(clock, 200, 0.0, 0.2, "w", lines.append, None, announced=False)
    _steps(m, clock, [(1.0, 0.001), (1.9, 0.002), (2.0, 0.003)])
    assert lines == ["w: measured 666.67 ms per step: about 2 min in all, 2 min left"]


def test_a_run_announced_long_reports_its_progress_every_30_s(clock):
    """A run announced before it starts (``announced``) reports, from PROGRESS_EVERY = 30 s
    after its start, every 30 s, the time reached, the end time, the fraction done of
    [t0, t1] and the time left (elapsed / done - elapsed). Grid [0.5, 2.5] s, 4 steps of a run
    too short to be re-announced: at 29.5 s nothing; at 30.0 s, t = 2.0: 75 % done, 30/0.75 -
    30 = 10 s left; at 59.9 s nothing (the next report is due 30 s after the last); at 60.0 s,
    t = 2.5: 100 %, 0 s left. Planted: the first report due at once (start - 30) or on any
    step ('or'), a report due strictly after 30 s, the next one due at once, the fraction from
    t + t0 or over t1 + t0 or times the span, 101 % for 100 %, the time left as elapsed x done
    or plus elapsed, the floor 1e-9 on the fraction made 1."""
    lines = []
    m = _monitor(clock, 4, 0.5, 2.5, "w", lines.append, None, announced=True)
    _steps(m, clock, [(29.5, 0.75), (30.0, 2.0), (59.9, 2.25), (60.0, 2.5)])
    assert lines == ["w: t = 2.0000 of 2.5000 s (75%), about 10 s left",
                     "w: t = 2.5000 of 2.5000 s (100%), about 0 s left"]


def test_a_run_found_long_reports_progress_after_its_announcement(clock):
    """A run not announced before it starts but measured long (announced=False, 7 s per step
    over 19 steps: 133 s) reports its progress from then on like an announced one: at 30 s,
    t = 0.25 of [0, 1]: 25 %, 30/0.25 - 30 = 90 s left; a run measured short (3 steps) never
    does. Planted: the run not marked long when measured so."""
    lines = []
    m = _monitor(clock, 19, 0.0, 1.0, "w", lines.append, None, announced=False)
    _steps(m, clock, [(7.0, 0.1), (14.0, 0.2), (30.0, 0.25)])
    assert lines == ["w: measured 7000.00 ms per step: about 2 min in all, 119 s left",
                     "w: t = 0.2500 of 1.0000 s (25%), about 90 s left"]
    lines.clear()
    m = _monitor(clock, 3, 0.0, 1.0, "w", lines.append, None, announced=False)
    _steps(m, clock, [(14.0, 0.1), (28.0, 0.2), (30.0, 0.25)])
    assert lines == []


def test_progress_at_the_start_or_on_an_empty_span(clock):
    """At t = t0 nothing is done yet: the time left is elapsed / 1e-9 (the floor on the
    fraction) - elapsed = 3e10 - 30 s = 8333333.3 h, not a division by zero; on an empty span
    (t1 = t0) the run counts as done: 100 %, 0 s left. Planted: '>=' for '>' on the span
    (a division by zero), 2.0 for the fraction of an empty span."""
    lines = []
    for t1 in (2.5, 0.5):
        m = _monitor(clock, 4, 0.5, t1, "w", lines.append, None, announced=True)
        _steps(m, clock, [(30.0, 0.5)])
    assert lines == ["w: t = 0.5000 of 2.5000 s (0%), about 8333333.3 h left",
                     "w: t = 0.5000 of 0.5000 s (100%), about 0 s left"]


def test_progress_is_called_every_step_with_or_without_messages(clock):
    """``progress`` gets the time reached after every step as a float, whether or not there is
    a ``notify`` (None: no messages at all, even for a run announced long and past its report
    time). Planted: progress called with None, messages sent only when notify is None."""
    times = []
    m = _monitor(clock, 3, 0.0, 0.3, "w", None, times.append, announced=True)
    _steps(m, clock, [(10.0, np.float64(0.1)), (40.0, 0.2), (90.0, 0.3)])
    assert times == [0.1, 0.2, 0.3] and all(type(t) is float for t in times)


# -- the step check -------------------------------------------------------------------------------

@pytest.mark.parametrize("h", [0, 0.0, -1e-3, float("nan"), float("inf"), True, "1e-3", None])
def test_a_step_that_is_no_positive_time_is_refused_with_its_value(h):
    """h must be a positive finite number (not a bool): anything else is an EngineUsageError
    naming it, before any division. Planted: 'or' for 'and' in the test (inf, True, nan or a
    negative step let through to a division or another message), h >= 0 accepted, the
    message lost."""
    with pytest.raises(EngineUsageError) as err:
        check_step(h, 0.01)
    assert str(err.value) == f"the Exudyn step must be a positive time in s; got {h!r}"


@pytest.mark.parametrize("h, options", [(3e-3, "0.003333333333 or 0.0025"),
                                        (0.03, "0.01 or 0.005"),
                                        (1e-3 * (1 + 1e-8), "0.001111111111 or 0.001")])
def test_a_step_not_dividing_the_interval_is_refused_with_two_that_do(h, options):
    """h must divide the output interval to round-off (1e-9 relative): 3 ms does not divide 10
    ms (the nearest k = 3 and 4 give 10/3 and 2.5 ms, larger first), 30 ms is longer than the
    interval (k = 1 and 2: 10 and 5 ms), and 1 ms made 1e-8 relative too long is off by 1e-10
    s over 10 steps (k = 9, 10: it is just under 10 per interval). Expected: the divisions by
    hand. Planted: 'and' for 'or' (a step of 3 ms accepted), the tolerance 1e-9 made 1 or
    divided by the interval, k from interval x h or at least 2, the options as products, from
    k - 1 or k + 2, smallest first, joined by ' OR ' or 'XX or XX'."""
    with pytest.raises(EngineUsageError) as err:
        check_step(h, 0.01)
    assert str(err.value) == (
        f"the Exudyn step h = {h:g} s must divide the output interval 0.01 s (the steps must "
        f"land on the output samples); fix: use 0.01/k s, e.g. {options}")


def test_steps_dividing_the_interval_and_the_span():
    """A dividing step gives the steps per interval: 10 for 1 ms in 10 ms, 3 for 10/3 ms (not
    a float that divides exactly), 2 for an int step 1 in an interval of 2; the span is
    divided to round-off, 1e-9 relative above 1 s and 1e-9 absolute below: 10 s + 5e-9 (5e-10
    relative) passes. Planted: the span's tolerance divided by the span."""
    assert check_step(1e-3, 0.01) == 10
    assert check_step(0.01 / 3, 0.01, 5.0) == 3
    assert check_step(1, 2) == 2
    assert check_step(1e-3, 0.01, 10.0 + 5e-9) == 10
    assert check_step(1e-3, 0.01, 0.5 + 0.5e-9) == 10


@pytest.mark.parametrize("span", [0.0125, 0.5 + 1.5e-9])
def test_a_step_not_dividing_the_span_is_refused(span):
    """The run's duration must be a multiple of h too: 5 ms does not divide 12.5 ms, and 1 ms
    misses 0.5 s + 1.5e-9 by 1.5e-9 s, more than the 1e-9 s round-off allowed below 1 s.
    Planted: the span check skipped ('is None'), its tolerance made 1 s or floored at 2 s
    instead of 1 s, the message lost."""
    h = 5e-3 if span == 0.0125 else 1e-3
    with pytest.raises(EngineUsageError) as err:
        check_step(h, 0.01, span)
    assert str(err.value) == (f"the Exudyn step h = {h:g} s must divide the run's duration "
                              f"{span:g} s; fix: a step dividing both 0.01 s and {span:g} s")


# -- rider torques as loads -----------------------------------------------------------------------

GRID = 1.0 + 0.1 * np.arange(11)         # knots 1.0 .. 2.0 s


def _spline(scale=0.9, seed=3):
    """scipy's not-a-knot spline through random torques on GRID (|values| <= scale)."""
    data = np.random.default_rng(seed).uniform(-scale, scale, (GRID.size, 3))
    return CubicSpline(GRID, data, axis=0, bc_type="not-a-knot"), data


def _bump(t):
    """0 at every knot of GRID, 1 at every mid-point."""
    return np.sin(np.pi * (t - 1.0) / 0.1) ** 2


def test_a_spline_on_the_grid_is_reproduced_everywhere():
    """A torque that is a cubic spline on the scenario grid comes back as scipy's not-a-knot
    spline through its values: equal to the given spline (round-off, 1e-12) at and between
    the knots and beyond both ends (the end pieces extend); a constant torque returned as
    ints is a spline too. Expected: scipy's spline evaluated directly."""
    S, _ = _spline()
    got = _as_spline(S, GRID)
    assert got is not None
    probe = np.linspace(0.8, 2.2, 57)
    np.testing.assert_allclose(got(probe), S(probe), rtol=0, atol=1e-12)
    const = _as_spline(lambda t: [1, -2, 3], GRID)
    np.testing.assert_allclose(const(probe), np.tile([1.0, -2.0, 3.0], (probe.size, 1)),
                               rtol=0, atol=1e-12)


def test_a_spline_is_probed_at_the_knots_and_mid_points_only():
    """``_as_spline`` checks the function at the knots and the mid-points between them
    (its docstring): a torque that is the spline on the grid and held at its end values
    outside it is accepted, one that leaves the spline between the knots of the second half
    only (a bump, zero at the knots, 1e-3 N m at the mid-points from 1.55 s) is refused.
    Planted: the mid-points 0.5 / (sum), 1.5 x (sum), half the difference, or the sums
    taken with the first knot (t_k + t_0) / 2 (all of them in the first half)."""
    S, _ = _spline()
    held = lambda t: S(np.clip(t, 1.0, 2.0))                       # noqa: E731
    assert _as_spline(held, GRID) is not None
    late = lambda t: S(t) + (1e-3 * _bump(t) if t > 1.5 else 0.0)  # noqa: E731
    assert _as_spline(late, GRID) is None


@pytest.mark.parametrize("scale, off, accepted", [(0.9, 0.5e-9, True), (0.9, 1.5e-9, False),
                                                  (1e4, 1e-6, True), (1e4, 1e-4, False)])
def test_the_spline_tolerance_is_1e9_relative_and_at_least_1e9(scale, off, accepted):
    """Reproduced means to 1e-9 relative (the docstring) to the largest torque, counted as at
    least 1 N m (small torques are not held to a smaller absolute tolerance than 1e-9 N m):
    with torques up to 0.9 N m, 0.5e-9 off at the
    mid-points is accepted and 1.5e-9 refused; with torques ~1e4 N m, 1e-6 off (1e-10
    relative) is accepted and 1e-4 (1e-8) refused. Planted: the floor 2 N m instead of 1,
    the tolerance divided by the scale."""
    S, _ = _spline(scale)
    f = lambda t: S(t) + off * _bump(t)                            # noqa: E731
    assert (_as_spline(f, GRID) is not None) is accepted


@pytest.mark.parametrize("torque", [lambda t: [1.0, 2.0], lambda t: None, lambda t: "torque"])
def test_a_torque_that_is_no_three_numbers_is_no_spline(torque):
    """A torque function giving two values, None or text has no spline: None (the engine then
    falls back to calling it), not an exception."""
    assert _as_spline(torque, GRID) is None


def _load_system():
    """An Exudyn system with a ground and the three markers the torques act on."""
    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddObject(ObjectGround())
    markers = {k: mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[i, 0, 0]))
               for i, k in enumerate(("ground", "frame_com", "fork", "rear", "frame"))}
    return mbs, markers


def _load_values(mbs, t):
    """Exudyn's values of every load at time t (its user functions evaluated by Exudyn)."""
    mbs.systemData.SetTime(float(t))
    return [np.asarray(mbs.GetLoadValues(i), dtype=float)
            for i in range(mbs.systemData.NumberOfLoads())]


@pytest.mark.parametrize("given", [(0.5, 0.0, -2.0), [[0.5, 0, -2]]])
def test_constant_torques_are_body_fixed_loads_on_their_bodies(given):
    """Constant torques (three numbers, flat or as one (1, 3) row): one body-fixed LoadTorqueVector
    per non-zero torque, on its body and axis (steer [0, 0, Mdir] on the fork, anti-roll
    [Mvue, 0, 0] on the frame; the zero pedal torque adds no load); settings text 'constant
    body-fixed LoadTorqueVector'. Expected: the module docstring, Exudyn's loads read back.
    Planted: the load vector started as [0, 1, 0], the torques not flattened to three."""
    mbs, markers = _load_system()
    assert add_torques(mbs, markers, given, GRID) == "constant body-fixed LoadTorqueVector"
    loads = [mbs.GetLoad(i) for i in range(mbs.systemData.NumberOfLoads())]
    assert [int(ld["markerNumber"]) for ld in loads] == [int(markers["fork"]),
                                                         int(markers["frame"])]
    np.testing.assert_array_equal(loads[0]["loadVector"], [0.0, 0.0, 0.5])
    np.testing.assert_array_equal(loads[1]["loadVector"], [-2.0, 0.0, 0.0])
    assert all(ld["bodyFixed"] for ld in loads)


def _check_torque_loads(mbs, markers, torque, times, kind):
    loads = [mbs.GetLoad(i) for i in range(mbs.systemData.NumberOfLoads())]
    assert len(loads) == 3
    for k, (where, axis) in TARGETS.items():
        assert int(loads[k]["markerNumber"]) == int(markers[where]) and loads[k]["bodyFixed"]
        assert loads[k]["loadVectorUserFunction"]["type"] == kind
    mbs.Assemble()
    for t in times:
        values = _load_values(mbs, t)
        T = np.asarray(torque(t), dtype=float)
        for k, (where, axis) in TARGETS.items():
            expected = np.zeros(3)
            expected[axis] = T[k]
            np.testing.assert_allclose(values[k], expected, rtol=0, atol=1e-12 * max(1, abs(T[k])))


def test_a_torque_spline_becomes_symbolic_loads_exact_at_the_knots(disc):
    """A torque history that is a spline on the grid: three body-fixed loads (fork z, rear
    wheel y, frame x) with *symbolic* user functions that Exudyn evaluates equal to scipy's
    spline at and between the knots and beyond both ends (1e-12), and at the knots exactly
    the given torque values (the spline interpolates its data: there the piece starting at
    the knot is evaluated at s = 0; the knot itself, not the mid-point, is where the pieces
    meet); the functions are kept alive in ``mbs.variables['_symbolic_keepalive']`` after
    whatever was there (here the drag's); settings text with the number of pieces (10 for
    11 knots). Planted: the branch taken at t <= knot (the left piece at a knot), the first or
    the last piece dropped (not-a-knot's end pieces are the next ones' cubics: only round-off
    shows), a symbolic function not kept, the earlier keep-alive list dropped, 11 or 9
    pieces, the settings text changed."""
    mbs, markers = _load_system()
    add_drag(mbs, markers, 0.3)
    drag_sym = mbs.variables["_symbolic_keepalive"][0]
    S, data = _spline()
    how = add_torques(mbs, markers, S, GRID)
    assert how == ("body-fixed LoadTorqueVector with symbolic user functions (the cubic spline "
                   "of the torque history, 10 pieces, evaluated in C++)")
    keep = mbs.variables["_symbolic_keepalive"]
    assert len(keep) == 4 and keep[0] is drag_sym
    for j, sym in enumerate(keep[1:]):
        got = sym.Evaluate(mbs, 1.23, [0.0, 0.0, 0.0])
        assert got[TARGETS[j][1]] == pytest.approx(float(S(1.23)[j]), abs=1e-12)
    _check_torque_loads(mbs, markers, S, np.linspace(0.8, 2.2, 29), "Symbolic")
    for k, t in enumerate(GRID[:-1]):
        values = _load_values(mbs, t)
        for j, (where, axis) in TARGETS.items():
            assert values[j][axis] == data[k, j], (k, j)


def test_any_other_torque_function_becomes_python_loads():
    """A torque function of time that is no spline on the grid: the same three body-fixed loads
    with *Python* user functions calling it (Exudyn's values equal the function's components
    on their axes, 1e-12), nothing added to the keep-alive list (what was there stays); the
    settings text says so. Planted: the branches swapped, the user function not set or set on
    another load, the component or the axis lost, the earlier keep-alive list dropped, the text
    changed."""
    mbs, markers = _load_system()
    mbs.variables["_symbolic_keepalive"] = ["earlier"]

    def torque(t):
        return np.array([np.sin(40 * t), 2.0 + np.cos(7 * t), -3.0 * t])

    how = add_torques(mbs, markers, torque, GRID)
    assert how == ("body-fixed LoadTorqueVector with Python user functions (torque function of "
                   "time)")
    assert mbs.variables["_symbolic_keepalive"] == ["earlier"]
    _check_torque_loads(mbs, markers, torque, [0.9, 1.0, 1.234, 1.75, 2.3], "Python")


def test_drag_is_cv_v_abs_v_on_the_frame_com_through_a_symbolic_connector():
    """Qaero = -cv |v| v on the frame's CoM: a CartesianSpringDamper between the ground and the
    frame_com markers, zero stiffness and damping, whose symbolic force function (evaluated by
    Exudyn) is cv |v| v (the connector applies minus that to the frame), kept alive after what
    was there; no connector for cv = 0. Expected: the module docstring, cv |v| v by hand.
    Planted: a marker swapped, a stiffness or damping left in, the force without |v|."""
    mbs, markers = _load_system()
    mbs.variables["_symbolic_keepalive"] = ["earlier"]
    assert add_drag(mbs, markers, 0.0) == "none (cv = 0)"
    assert mbs.systemData.NumberOfObjects() == 1
    how = add_drag(mbs, markers, 0.3)
    assert how == ("CartesianSpringDamper frame CoM - ground, symbolic force cv |v| v "
                   "(evaluated in C++)")
    csd = mbs.GetObject(1)
    assert csd["objectType"] == "ConnectorCartesianSpringDamper"
    assert [int(m) for m in csd["markerNumbers"]] == [int(markers["ground"]),
                                                       int(markers["frame_com"])]
    np.testing.assert_array_equal(csd["stiffness"], np.zeros(3))
    np.testing.assert_array_equal(csd["damping"], np.zeros(3))
    keep = mbs.variables["_symbolic_keepalive"]
    assert len(keep) == 2 and keep[0] == "earlier"
    v = np.array([1.0, 2.0, -2.0])
    got = keep[1].Evaluate(mbs, 0.0, 1, [0.0] * 3, list(v), [0.0] * 3, [0.0] * 3, [0.0] * 3)
    np.testing.assert_allclose(got, 0.3 * 3.0 * v, rtol=1e-15)


# -- the fall event between two steps -------------------------------------------------------------

def _cubics(theta_sign):
    """Eight cubics in x = s - 1 on [1, 1.5] (random, theta's fixed: 0.5 + 3.8x - 1.4x^2 +
    1.7x^3, rising through 1.2), as the (t, q, dq, ddq) of two steps, and the polynomials."""
    rng = np.random.default_rng(5)
    coef = rng.normal(size=(8, 4))
    coef[3] = [0.5, 3.8, -1.4, 1.7]
    coef[3] *= theta_sign
    P = [Polynomial(c) for c in coef]
    t = np.array([1.0, 1.5])
    x = t - 1.0
    rows = [np.array([[p.deriv(d)(xi) if d else p(xi) for p in P] for xi in x]) for d in range(3)]
    return t, rows, P


@pytest.mark.parametrize("theta_sign", [1.0, -1.0])
def test_the_event_of_a_cubic_is_its_root_and_its_values_there(theta_sign):
    """q, dq, ddq of two steps taken from eight cubics: the cubic Hermite interpolant of q
    from (q, dq) is each cubic itself, that of dq from (dq, ddq) its derivative (a quadratic),
    and the linear ddq its second derivative, so ``_hermite_event`` must return the time where
    |theta| = 1.2 (the root of 0.5 + 3.8x - 1.4x^2 + 1.7x^3 = 1.2 in (0, 0.5), from numpy's
    polynomial roots; the same for a lean to the left, theta negated) and there every cubic,
    its derivative and its second derivative (1e-12). The time to 2e-14 s: the root is
    bracketed to 1e-14 s (brentq's xtol; its default 2e-12 s leaves 5e-13 s on this cubic).
    Steps of 0.5 s from t0 = 1 (neither 0 nor 1, so that a step taken as t1 + t0 or an
    interpolation in s + t0 shows). Planted: the step t1 + t0, u^4 for u^3 in a Hermite basis
    function, dq at the end for dq at the start, u = (s - t0) x h or (s + t0) / h, the linear
    ddq with a wrong sign, weight or end, brentq's default tolerance."""
    t, (q, dq, ddq), P = _cubics(theta_sign)
    roots = Polynomial([0.5 - 1.2, 3.8, -1.4, 1.7]).roots()
    x = float(next(r.real for r in roots if abs(r.imag) < 1e-12 and 0 < r.real < 0.5))
    s, q_e, dq_e, ddq_e = _hermite_event(t, q, dq, ddq, 1.2)
    assert abs(s - (1.0 + x)) < 2e-14
    np.testing.assert_allclose(q_e, [p(x) for p in P], rtol=0, atol=1e-12)
    np.testing.assert_allclose(dq_e, [p.deriv()(x) for p in P], rtol=0, atol=1e-12)
    np.testing.assert_allclose(ddq_e, [p.deriv(2)(x) for p in P], rtol=0, atol=1e-12)
    assert abs(q_e[3]) == pytest.approx(1.2, abs=1e-13)


# -- the solver's error text ----------------------------------------------------------------------

class FakeSolver:
    def __init__(self, text, newton=None):
        self.text = text
        if newton is not None:
            self.it = types.SimpleNamespace(newtonStepsCount=newton)

    def GetErrorString(self):
        return self.text


def test_the_solver_error_string_is_one_line_or_empty():
    """Exudyn's error string of the stored dynamic solver (``mbs.sys['dynamicSolver']``) on one
    line, runs of whitespace made single spaces; empty when there is no stored solver. Planted:
    the string joined by anything but a space, the solver looked up under another key, the
    fallback 'XXXX'."""
    solver = FakeSolver("  Newton\n  did not   converge \n")
    mbs = types.SimpleNamespace(sys={"dynamicSolver": solver})
    assert _solver_error_string(mbs) == "Newton did not converge"
    assert _solver_error_string(types.SimpleNamespace(sys={})) == ""


# -- the engine's options and Exudyn's settings ---------------------------------------------------

@pytest.mark.parametrize("kwargs, message", [
    ({"jacobian": "always"}, "unknown Jacobian update 'always'; choose one of: when-slow, "
                             "per-step"),
    ({"build": "bodies"}, "unknown Exudyn build 'bodies'; choose one of: tree, redundant"),
    ({"solver": "euler"}, "unknown Exudyn solver 'euler'; choose one of: generalizedAlpha, "
                          "trapezoidal"),
    ({"step": 0.0}, "step must be a positive time step in s; got 0.0"),
    ({"step": -1e-3}, "step must be a positive time step in s; got -0.001"),
    ({"step": True}, "step must be a positive time step in s; got True"),
    ({"step": float("nan")}, "step must be a positive time step in s; got nan"),
    ({"step": "1e-3"}, "step must be a positive time step in s; got '1e-3'"),
])
def test_bad_options_are_usage_errors_naming_the_choices(disc, kwargs, message):
    """Each option the engine does not know is an EngineUsageError naming it and the choices
    (the class docstring's builds, solvers and Jacobian updates), a step that is no positive
    time names the step. Planted: the choices joined by 'XX, XX', a message lost, a negative,
    zero or bool step let through ('or' for 'and', '>=' for '>')."""
    with pytest.raises(EngineUsageError) as err:
        ExudynEngine(disc, **kwargs)
    assert str(err.value) == message


def test_the_settings_are_a_fixed_step_quiet_run_without_files(disc):
    """What ``simulate`` hands Exudyn (module docstring: a fixed step, no step-size control;
    Newton's relative and absolute tolerance; verbose modes 0; no solution file; sensors
    storing every step; no timing or statistics printed): n steps from t0 to t1, the options
    given (spectral radius 0.7, tolerance 1e-9, Jacobian per step) and the defaults (Jacobian
    when slow). Planted: a verbose mode 1, automatic step size on, the solution file written,
    computation time or statistics shown."""
    eng = ExudynEngine(disc, step=2e-3, spectral_radius=0.7, newton_tolerance=1e-9,
                       jacobian="per-step")
    ss = eng._settings(40, 0.1, 0.18)
    ti = ss.timeIntegration
    assert (ti.numberOfSteps, ti.startTime, ti.endTime) == (40, 0.1, 0.18)
    assert ti.verboseMode == 0 and ti.verboseModeFile == 0
    assert ti.automaticStepSize is False and ti.adaptiveStep is False
    assert ti.newton.relativeTolerance == ti.newton.absoluteTolerance == 1e-9
    assert ti.newton.modifiedNewtonJacUpdatePerStep is True
    assert ti.generalizedAlpha.spectralRadius == 0.7
    assert ti.generalizedAlpha.computeInitialAccelerations is True
    assert ss.solution.file.write is False and ss.solution.sensors.writePeriod == 2e-3
    assert ss.show.computationTime is False and ss.show.statistics is False
    assert ExudynEngine(disc)._settings(1, 0.0, 1e-3).timeIntegration.newton \
        .modifiedNewtonJacUpdatePerStep is False


# -- generalized forces ---------------------------------------------------------------------------

def test_generalized_forces_for_one_state_and_by_default_without_torques(disc, engine):
    """One state (8,) gives one (8,) vector: the reference's generalized forces with the given
    torques, and with none given the reference's at zero torques (1e-12 relative); a batch with
    one torque triple applies it to every state. A (1, 3) torque array for one state is
    refused as the reference refuses it. Planted: the single-state flag lost on the torques
    (a (1, 3) array accepted)."""
    q, dq, rng = random_states(3, seed=41)
    T = rng.uniform(-10, 10, 3)
    for k in range(3):
        F = engine.generalized_forces(q[k], dq[k], T)
        F_ref = disc.generalized_forces(q[k], dq[k], T)
        assert F.shape == (8,)
        assert np.abs(F - F_ref).max() < 1e-12 * np.abs(F_ref).max()
        F0, F0_ref = engine.generalized_forces(q[k], dq[k]), disc.generalized_forces(q[k], dq[k],
                                                                                     np.zeros(3))
        assert np.abs(F0 - F0_ref).max() < 1e-12 * np.abs(F0_ref).max()
    Fb = engine.generalized_forces(q, dq, T)
    assert Fb.shape == (3, 8)
    assert np.abs(Fb - disc.generalized_forces(q, dq, T)).max() < 1e-12 * np.abs(Fb).max()
    with pytest.raises(ValueError) as err:
        engine.generalized_forces(q[0], dq[0], T[None, :])
    assert str(err.value) == ("torques must have shape (3,) [Mdir, Mped, Mvue] in N m; got shape "
                              "(1, 3)")


def test_the_redundant_build_has_no_generalized_forces(disc):
    """build='redundant' narrows the capabilities to simulate: generalized_forces is a
    CapabilityError naming it. Planted: the capability's name lost from the message."""
    with pytest.raises(CapabilityError) as err:
        ExudynEngine(disc, build="redundant").generalized_forces(np.zeros(8), np.zeros(8))
    assert str(err.value) == ("engine 'exudyn' cannot compute generalized_forces; it provides: "
                              "simulate")


def test_the_forces_helper_writes_no_file_and_prints_nothing(disc, tmp_path, monkeypatch, capfd):
    """``TreeForces`` built and evaluated outside the engine's ``quiet()`` in an empty working
    folder leaves the folder empty and prints nothing (module docstring: no solution files,
    nothing on the console), and its forces are the reference's (1e-12 relative) with the
    rolling discs switched off (no constraint force enters). Planted: the solution file on,
    the static solver verbose, a disc left active."""
    monkeypatch.chdir(tmp_path)
    tf = TreeForces(disc.params)
    q, dq, rng = random_states(2, seed=42)
    for k in range(2):
        T = rng.uniform(-10, 10, 3)
        F, F_ref = tf(q[k], dq[k], T), disc.generalized_forces(q[k], dq[k], T)
        assert np.abs(F - F_ref).max() < 1e-12 * np.abs(F_ref).max()
    assert sorted(p.name for p in tmp_path.rglob("*")) == []
    out, err = capfd.readouterr()
    assert out == "" and err == ""


# -- simulate: options ----------------------------------------------------------------------------

@pytest.fixture
def monitors(monkeypatch):
    """The arguments of every _Monitor the engine makes."""
    made = []

    class Recording(_Monitor):
        def __init__(self, *args, **kwargs):
            made.append((args, kwargs))
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(exudyn_engine, "_Monitor", Recording)
    return made


def test_a_run_on_the_grid_and_at_every_step(engine, full):
    """By default the output is on the scenario's grid (every 10th step of 1 ms from t0 =
    0.1 s: 0.1, 0.11, 0.12), with ``every_step`` every step (21 samples t0 + k h), the same
    states there; ddq is the central difference of dq on the step grid (one-sided at the
    ends, second order), by hand; 20 steps. Planted: every_step ignored or its default made
    True, the interval or the span taken as a sum of grid times."""
    tr = engine.simulate(SHORT)
    assert tr.status == "completed" and tr.message == "reached the end of the grid"
    np.testing.assert_allclose(tr.t, [0.1, 0.11, 0.12], rtol=0, atol=1e-12)
    assert tr.settings["grid"] == "scenario grid (every 10 steps)"
    assert tr.timing["steps"] == 20
    np.testing.assert_allclose(full.t, T0 + H * np.arange(21), rtol=0, atol=1e-12)
    assert full.settings["grid"] == "every step"
    np.testing.assert_array_equal(tr.q, full.q[::10])
    dq = full.dq
    central = (dq[2:] - dq[:-2]) / (2 * H)
    np.testing.assert_allclose(full.ddq[1:-1], central, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(full.ddq[0], (-3 * dq[0] + 4 * dq[1] - dq[2]) / (2 * H),
                               rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(full.ddq[-1], (dq[-3] - 4 * dq[-2] + 3 * dq[-1]) / (2 * H),
                               rtol=1e-9, atol=1e-9)


def test_the_run_records_its_settings_and_timing(disc, engine):
    """A default tree run records what it was (the class and module docstrings): engine,
    Exudyn's version, build, step, solver and Exudyn's solver type, spectral radius 0.9,
    Newton tolerance 1e-10, Jacobian 'when-slow', the disc contact realised by Exudyn's
    rolling disc, stop_at_fall True, the reference-only options given (rtol, atol: ignored,
    sorted), the torques and drag, no rear hub drift (the redundant build's); its torques T
    the scenario's constant ones on every row; C the reference's residual on its states;
    timing: wall time at least build plus solve, 20 steps, Newton's iterations. Planted:
    stop_at_fall's default False or lost, an ignored option popped by another name, the hub
    drift recorded as None, the timing's wall time counted from the wrong end."""
    tr = engine.simulate(SHORT, rtol=1e-3, atol=1e-4)
    s = tr.settings
    expected = {"engine": "exudyn", "exudyn_version": exu.__version__, "build": "tree",
                "step": 1e-3, "solver": "generalizedAlpha", "solver_type": "GeneralizedAlpha",
                "spectral_radius": 0.9, "newton_tolerance": 1e-10, "jacobian": "when-slow",
                "contact": "disc", "front_contact": "ObjectJointRollingDisc (true lowest point)",
                "rear_contact": "ObjectJointRollingDisc",
                "torques": "constant body-fixed LoadTorqueVector",
                "drag": "CartesianSpringDamper frame CoM - ground, symbolic force cv |v| v "
                        "(evaluated in C++)",
                "fall_limit": 1.4, "stop_at_fall": True, "ignored_options": ["atol", "rtol"],
                "dq": "tree coordinates' velocities"}
    assert {k: s[k] for k in expected} == expected
    assert s["stop_at_fall"] is True
    assert "rear_hub_height_drift" not in s           # the redundant build's diagnostic only
    assert s["ddq"] == ("central finite differences of dq on the step grid (second order, "
                        "one-sided at the ends); not Exudyn's stored accelerations")
    assert s["C"] == "reference model's constraint_residual on the Exudyn states"
    init = initial_state(disc, SHORT)
    assert s["initial_correction"] == init.describe()
    assert s["beta_correction"] == init.beta_correction
    np.testing.assert_array_equal(tr.T, np.tile(SHORT.torques, (3, 1)))
    np.testing.assert_allclose(tr.C, disc.constraint_residual(tr.q, tr.dq), rtol=0, atol=1e-15)
    tm = tr.timing
    assert 0 <= tm["build_seconds"] and 0 <= tm["solve_seconds"]
    assert tm["build_seconds"] + tm["solve_seconds"] <= tm["wall_seconds"] < 60
    assert tm["steps"] == 20 and isinstance(tm["newton_iterations"], int)
    assert tm["newton_iterations"] >= 20 and "user_constraint_calls" not in tm


def test_the_solver_option_reaches_exudyn(disc, full, monkeypatch):
    """solver='trapezoidal' runs Exudyn's TrapezoidalIndex2 (the class docstring): the solver
    type handed to SolveDynamic, the settings, and the run, which differs from the
    generalized-alpha run (by ~1e-6 rad/s in dq over 20 ms, far more than the 1e-10 Newton
    tolerance could). Planted: the solver type not passed (SolveDynamic's default)."""
    seen = []
    real = exu.SolveDynamic

    def solve(mbs, ss, **kwargs):
        seen.append(kwargs.get("solverType"))
        return real(mbs, ss, **kwargs)

    monkeypatch.setattr(exu, "SolveDynamic", solve)
    tr = ExudynEngine(disc, solver="trapezoidal").simulate(SHORT)
    assert seen == [exu.DynamicSolverType.TrapezoidalIndex2]
    assert tr.settings["solver"] == "trapezoidal"
    assert tr.settings["solver_type"] == "TrapezoidalIndex2"
    assert np.abs(tr.dq - full.dq[::10]).max() > 1e-8


def test_bad_run_options_are_refused_before_the_run(engine):
    """Unknown options are a TypeError naming them all; an inverse scenario is refused (Exudyn
    runs forward ones); a t_end leaving fewer than two samples is refused, one leaving exactly
    two runs them (10 steps). Planted: the names joined by 'XX, XX', a message lost, two
    samples refused ('<= 2', '< 3')."""
    with pytest.raises(TypeError) as err:
        engine.simulate(SHORT, tolerance=1, order=2)
    assert str(err.value) == "ExudynEngine.simulate got unknown option(s): tolerance, order"
    with pytest.raises(ValueError) as err:
        engine.simulate(SCENARIOS["zigzag"])
    assert str(err.value) == ("scenario 'zigzag' is an inverse scenario; Exudyn runs only "
                              "forward scenarios")
    with pytest.raises(ValueError) as err:
        engine.simulate(SHORT, t_end=0.105)
    assert str(err.value) == "t_end = 0.105 leaves fewer than 2 grid samples"
    tr = engine.simulate(SHORT, t_end=0.11)
    np.testing.assert_allclose(tr.t, [0.1, 0.11], rtol=0, atol=1e-12)
    assert tr.timing["steps"] == 10


def test_the_monitor_gets_the_run_and_its_callbacks(engine, monitors):
    """The run's monitor is given the number of steps (20), the grid's first and last time,
    'exudyn tree on stability-psid10', the caller's notify and progress, and whether the run
    was announced (no: 20 x 1.2 ms); progress is called after each of the 20 steps with the
    time reached, t0 + k h. Planted: any of the monitor's arguments None, progress dropped or
    read under another name."""
    times, lines = [], []
    engine.simulate(SHORT, progress=times.append, notify=lines.append)
    (args, kwargs), = monitors
    assert args[:4] == (20, float(SHORT.t[0]), float(SHORT.t[-1]), WHAT)
    assert args[4] == lines.append and args[5] == times.append
    assert kwargs == {"announced": False}
    np.testing.assert_allclose(times, T0 + H * np.arange(1, 21), rtol=0, atol=1e-12)
    assert lines == []


def test_a_long_run_is_announced_before_it_starts(engine, monkeypatch, monitors, capfd):
    """A run estimated (steps x STEP_SECONDS) longer than LONG_RUN_SECONDS is announced before
    it starts, through ``notify`` or by default on stderr prefixed 'bicycle-xval: ', with its
    steps, step, estimate, cost per step and the progress interval; an estimate equal to the
    limit is not longer; notify=None silences it. With a cost of 0.1 s per step made up here,
    20 steps are 2 s: announced above a 1 s limit, not at a 2 s one. Planted: the comparison
    '>=', notify None taken as the one to call, the default notify lost, the cost in ms
    computed with 1/1000 or 1001, the estimate or the whole line lost."""
    monkeypatch.setitem(exudyn_engine.STEP_SECONDS, "tree", 0.1)
    monkeypatch.setattr(exudyn_engine, "LONG_RUN_SECONDS", 2.0)
    lines = []
    engine.simulate(SHORT, notify=lines.append)
    assert lines == [] and monitors[-1][1] == {"announced": False}
    monkeypatch.setattr(exudyn_engine, "LONG_RUN_SECONDS", 1.0)
    engine.simulate(SHORT, notify=lines.append)
    line = (f"{WHAT}: 20 steps of h = 0.001 s, estimated 2 s (100.0 ms per step); progress "
            "every 30 s")
    assert lines == [line] and monitors[-1][1] == {"announced": True}
    capfd.readouterr()
    engine.simulate(SHORT)
    assert capfd.readouterr().err == f"bicycle-xval: {line}\n"
    engine.simulate(SHORT, notify=None)
    assert capfd.readouterr().err == ""
    assert monitors[-1][0][4] is None


# -- simulate: falls ------------------------------------------------------------------------------

def _expected_event(full, limit):
    """The fall located on the every-step run by scipy: the first step k with |theta| >=
    limit, the cubic Hermite interpolants of q (from q, dq) and dq (from dq, ddq) between
    steps k - 1 and k, the time where theta's reaches the limit, and the values there."""
    k = int(np.flatnonzero(np.abs(full.q[:, 3]) >= limit)[0])
    t = full.t[k - 1:k + 1]
    Q = CubicHermiteSpline(t, full.q[k - 1:k + 1], full.dq[k - 1:k + 1])
    V = CubicHermiteSpline(t, full.dq[k - 1:k + 1], full.ddq[k - 1:k + 1])
    roots = CubicHermiteSpline(t, full.q[k - 1:k + 1, 3], full.dq[k - 1:k + 1, 3]).solve(limit)
    te = float(next(r for r in roots if t[0] <= r <= t[1]))
    u = (te - t[0]) / (t[1] - t[0])
    return k, te, Q(te), V(te), (1 - u) * full.ddq[k - 1] + u * full.ddq[k]


@pytest.mark.parametrize("stop", [True, False])
def test_a_fall_ends_the_run_at_the_located_event(engine, full, stop):
    """|theta| passes FALL between steps 8 and 9: the run ends with status 'fell', its last row
    the event located by cubic Hermite interpolation (scipy's, on the every-step run of the
    same states: the time to 1e-12 s, q there to 1e-12, theta on the limit), after the grid
    rows before it (t0); the message gives the limit and the time. With the default
    stop_at_fall the run stops one step after the pass (10 steps, progress 10 times), with
    stop_at_fall=False it runs all 20 and is cut afterwards, where dq and ddq at the event are
    scipy's interpolants too (1e-9). Planted: stop_at_fall ignored, its default False, read
    under another name."""
    k, te, q_e, dq_e, ddq_e = _expected_event(full, FALL)
    assert k == 9
    times = []
    opts = {} if stop else {"stop_at_fall": False}
    tr = engine.simulate(SHORT, fall_limit=FALL, progress=times.append, **opts)
    assert tr.status == "fell"
    assert tr.message == f"|theta| reached the fall limit {FALL:.4f} rad at t = {te:.6f} s"
    assert tr.t.size == 2 and tr.t[0] == T0 and abs(tr.t[-1] - te) < 1e-12 and tr.t_end == tr.t[-1]
    np.testing.assert_allclose(tr.q[-1], q_e, rtol=0, atol=1e-12)
    assert abs(tr.q[-1, 3]) == pytest.approx(FALL, abs=1e-12)
    assert tr.timing["steps"] == len(times) == (10 if stop else 20)
    assert tr.settings["stop_at_fall"] is stop
    if not stop:
        np.testing.assert_allclose(tr.dq[-1], dq_e, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(tr.ddq[-1], ddq_e, rtol=1e-9, atol=1e-9)


def test_a_fall_at_every_step_keeps_the_steps_before_it(engine, full):
    """With every_step the rows are the steps before the pass (0..8) and the event."""
    k, te, q_e, _, _ = _expected_event(full, FALL)
    tr = engine.simulate(SHORT, fall_limit=FALL, every_step=True)
    np.testing.assert_array_equal(tr.t[:-1], full.t[:k])
    np.testing.assert_array_equal(tr.q[:-1], full.q[:k])
    assert abs(tr.t[-1] - te) < 1e-12


@pytest.mark.parametrize("every_step", [False, True])
def test_a_run_started_beyond_the_limit_falls_at_its_start(engine, every_step):
    """Leaned pi/16 = 0.196 rad against a limit 0.1: fell at once, one row (the start, also
    with every_step: the step taken before the check stopped the run is not kept), one step,
    the message giving |theta| to 3 decimals. Planted: two rows kept."""
    tr = engine.simulate(SHORT, fall_limit=0.1, every_step=every_step)
    assert tr.status == "fell" and tr.message == "|theta| = 0.196 rad >= fall limit at the start"
    np.testing.assert_array_equal(tr.t, [T0])
    assert tr.q.shape == (1, 8) and tr.timing["steps"] == 1


# -- simulate: failures ---------------------------------------------------------------------------

def _failing_solve(monkeypatch, steps, error, solver=None):
    """Exudyn's SolveDynamic made to run only ``steps`` steps (none: it fails at once), then
    raise ``error``; ``solver`` replaces the stored solver (its error string, its counts)."""
    real = exu.SolveDynamic

    def solve(mbs, ss, **kwargs):
        if steps:
            ti = ss.timeIntegration
            h = (ti.endTime - ti.startTime) / ti.numberOfSteps
            ti.endTime, ti.numberOfSteps = ti.startTime + steps * h, steps
            real(mbs, ss, **kwargs)
        if solver is not None:
            mbs.sys["dynamicSolver"] = solver
        raise error

    monkeypatch.setattr(exu, "SolveDynamic", solve)


@pytest.mark.parametrize("error, name", [(exu.SolverError("Newton\n  failed  to converge"),
                                          "SolverError"),
                                         (exu.ExudynArithmeticError("x / 0"),
                                          "ExudynArithmeticError")])
def test_a_solver_error_returns_the_steps_reached(engine, full, monkeypatch, error, name):
    """Exudyn failing after 15 steps (a SolverError or an ExudynArithmeticError): status
    'failed', the message naming the error class and its text on one line, Exudyn's own error
    string in parentheses, and the last step reached; the rows on the grid (0.1, 0.11) and the
    last step before the failure (0.115), equal to the states of the full run; Newton's count
    from the stored solver (7). Planted: one of the two errors not caught, the failure's text
    or time lost."""
    _failing_solve(monkeypatch, 15, error, FakeSolver("Newton:\n no  convergence", newton=7.0))
    tr = engine.simulate(SHORT)
    assert tr.status == "failed"
    assert tr.message == (f"Exudyn solver failed: {name}: {' '.join(str(error).split())} "
                          "(Newton: no convergence); last step reached t = 0.115000 s")
    np.testing.assert_allclose(tr.t, [0.1, 0.11, 0.115], rtol=0, atol=1e-12)
    np.testing.assert_allclose(tr.q, full.q[[0, 10, 15]], rtol=0, atol=1e-12)
    assert tr.timing["newton_iterations"] == 7 and tr.timing["steps"] == 15


def test_a_solver_error_at_the_first_step_returns_the_start(disc, engine, monkeypatch):
    """Exudyn failing before any step (no samples stored, no stored solver to ask): one row,
    the projected initial state at t0, ddq zero, the message without an error string, and no
    Newton count in the timing. Planted: the empty read-back taken for samples (the grid check
    on no samples), an error string invented."""
    _failing_solve(monkeypatch, 0, exu.SolverError("no start"))
    tr = engine.simulate(SHORT)
    init = initial_state(disc, SHORT)
    assert tr.status == "failed"
    assert tr.message == ("Exudyn solver failed: SolverError: no start; last step reached "
                          "t = 0.100000 s")
    np.testing.assert_array_equal(tr.t, [T0])
    np.testing.assert_array_equal(tr.q, [init.q])
    np.testing.assert_array_equal(tr.dq, [init.dq])
    np.testing.assert_array_equal(tr.ddq, np.zeros((1, 8)))
    assert tr.timing["steps"] == 0 and "newton_iterations" not in tr.timing


def test_a_run_failing_before_its_first_step_beyond_the_limit_fell_at_its_start(
        disc, engine, monkeypatch):
    """Exudyn failing before any step on a start beyond the fall limit: the one row is the
    initial state, and the run fell at its start (|theta| = 0.196 rad read from that one
    row). Planted: |theta| read from a second row (there is none)."""
    _failing_solve(monkeypatch, 0, exu.SolverError("no start"))
    tr = engine.simulate(SHORT, fall_limit=0.1)
    assert tr.status == "fell" and tr.message == "|theta| = 0.196 rad >= fall limit at the start"
    np.testing.assert_array_equal(tr.q, [initial_state(disc, SHORT).q])


@pytest.mark.parametrize("steps", [1, 2])
def test_a_run_of_one_or_two_steps_has_its_accelerations(engine, full, monkeypatch, steps):
    """After one step (two samples) there is no second-order difference: ddq is zero; after two
    (three samples) it is the one-sided and central differences of dq (by hand, as in the
    full run). With every_step the rows are every sample. Planted: the three-sample threshold
    moved."""
    _failing_solve(monkeypatch, steps, exu.SolverError("stop"))
    tr = engine.simulate(SHORT, every_step=True)
    assert tr.t.size == steps + 1
    if steps == 1:
        np.testing.assert_array_equal(tr.ddq, np.zeros((2, 8)))
    else:
        dq = tr.dq
        np.testing.assert_allclose(tr.ddq[1], (dq[2] - dq[0]) / (2 * H), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(tr.ddq[0], (-3 * dq[0] + 4 * dq[1] - dq[2]) / (2 * H),
                                   rtol=1e-9, atol=1e-9)


def test_a_failure_after_a_fall_reports_both(engine, full, monkeypatch):
    """A run that passes the limit (step 9) and then fails (Exudyn raising after the stop at
    step 10): status 'fell', the fall first and the failure after it, one message."""
    k, te, _, _, _ = _expected_event(full, FALL)
    _failing_solve(monkeypatch, 20, exu.SolverError("late"))
    tr = engine.simulate(SHORT, fall_limit=FALL)
    assert tr.status == "fell"
    assert tr.message == (f"|theta| reached the fall limit {FALL:.4f} rad at t = {te:.6f} s; "
                          "after the fall, Exudyn solver failed: SolverError: late; last step "
                          "reached t = 0.110000 s")


@pytest.fixture
def spoilt_read(monkeypatch):
    """TreeBuild.read with one sample of q or dq made NaN, or the time stamps moved."""
    read = TreeBuild.read
    plan = {}

    def spoilt(self, mbs, q0):
        t, q, dq = read(self, mbs, q0)
        if "q" in plan:
            q[plan["q"], 2] = np.nan
        if "dq" in plan:
            dq[plan["dq"], 5] = np.inf
        if "t" in plan:
            t = t.copy()
            t[-1] += plan["t"]
        return t, q, dq

    monkeypatch.setattr(TreeBuild, "read", spoilt)
    return plan


@pytest.mark.parametrize("where, k, rows", [("q", 13, [0.1, 0.11, 0.112]), ("dq", 7, [0.1, 0.106]),
                                            ("q", 0, [0.1])])
def test_a_non_finite_state_ends_the_run_before_it(disc, engine, full, spoilt_read, where, k,
                                                   rows):
    """A sample with a non-finite q or dq (planted in the read-back at step k) ends the run at
    the step before: status 'failed', the message giving the last finite time (t0 when the
    first sample is bad, then the initial state is returned), the grid rows before it and that
    last step, equal to the full run's states. Planted: q and dq combined by 'or', the last
    finite step lost."""
    spoilt_read[where] = k
    tr = engine.simulate(SHORT)
    last = T0 + H * max(k - 1, 0)
    assert tr.status == "failed"
    assert tr.message == (f"state became non-finite after t = {last:.6f} s; last step reached "
                          f"t = {last:.6f} s")
    np.testing.assert_allclose(tr.t, rows, rtol=0, atol=1e-12)
    if k:
        steps = np.round((np.array(rows) - T0) / H).astype(int)
        np.testing.assert_array_equal(tr.q, full.q[steps])
    else:
        np.testing.assert_array_equal(tr.q, [initial_state(disc, SHORT).q])


def test_a_non_finite_state_after_a_solver_error_keeps_the_solvers_message(
        engine, monkeypatch, spoilt_read):
    """Exudyn failing after 15 steps, the state non-finite from step 13: the run is cut before
    the bad state, but the message is the solver's failure (the first cause), with the last
    finite step. Planted: the solver's message replaced by the non-finite one."""
    _failing_solve(monkeypatch, 15, exu.SolverError("stop"))
    spoilt_read["q"] = 13
    tr = engine.simulate(SHORT)
    assert tr.status == "failed"
    assert tr.message == ("Exudyn solver failed: SolverError: stop; last step reached "
                          "t = 0.112000 s")
    np.testing.assert_allclose(tr.t, [0.1, 0.11, 0.112], rtol=0, atol=1e-12)


def test_time_stamps_off_the_step_grid_are_an_error(engine, spoilt_read):
    """The sensors' time stamps must lie on the step grid to 1e-6 h (module docstring: checked
    before the output is taken): 5e-10 s off passes, 2e-9 s is an EngineError giving the
    offset. Planted: the tolerance 1e-6 / h."""
    spoilt_read["t"] = 5e-10
    assert engine.simulate(SHORT).status == "completed"
    spoilt_read["t"] = 2e-9
    with pytest.raises(EngineError) as err:
        engine.simulate(SHORT)
    assert str(err.value) == ("Exudyn's sensor time stamps left the step grid (max offset "
                              "2.000e-09 s)")


def test_a_torque_history_is_evaluated_on_the_output_rows(disc, engine, monkeypatch):
    """A torque function of time (here a function the engine cannot take for a spline, so a
    Python user function): the run's T is that function on the output times, the event row
    included. Planted: T taken as the constant broadcast."""
    def torque(t):
        return np.array([0.1 * np.sin(40 * t), 0.5, -0.2 * t])

    monkeypatch.setattr(exudyn_engine, "torque_input", lambda model, scenario: torque)
    tr = engine.simulate(SHORT)
    assert tr.settings["torques"].endswith("(torque function of time)")
    np.testing.assert_allclose(tr.T, [torque(t) for t in tr.t], rtol=0, atol=1e-15)


@pytest.mark.parametrize("as_function", [False, True])
def test_torques_given_as_integers_are_recorded_in_floats(engine, monkeypatch, as_function):
    """Torques written as integers, (0, 1, 0) N m, constant or returned by a function of time,
    are recorded as floats (T in N m, as every engine's). Planted: T kept in the integers it
    was given in."""
    if as_function:
        monkeypatch.setattr(exudyn_engine, "torque_input", lambda model, sc: lambda t: [0, 1, 0])
        tr = engine.simulate(SHORT)
    else:
        tr = engine.simulate(dataclasses.replace(SHORT, torques=(0, 1, 0)))
    assert tr.T.dtype == np.float64
    np.testing.assert_array_equal(tr.T, [[0.0, 1.0, 0.0]] * 3)


def test_a_thesis_contact_run_counts_its_user_constraint_calls(thesis):
    """On the thesis contact the tree's front contact is user constraints (Python): the
    settings say so and the timing counts their calls (positive)."""
    tr = ExudynEngine(thesis).simulate(dataclasses.replace(SHORT, grid=(T0, DT, 2)))
    assert tr.settings["front_contact"] == ("thesis fork-axis point, user constraints (Python) "
                                           "on the tree")
    assert tr.timing["user_constraint_calls"] > 0


def test_a_redundant_run_starts_at_the_initial_state_and_records_its_mapping(disc):
    """The redundant build starts from the scenario's projected initial state (module
    docstring), whole turns of the yaw included: started at phi = 2 pi + 0.5 (a pose Exudyn's
    rotations give as 0.5), the first row is that state (1e-12) and the yaw stays near it.
    Its dq comes from the bodies' velocities, said in the settings, which also carry the rear
    hub height drift. Planted: the read-back not given the initial state (angles left within
    (-pi, pi])."""
    q0 = list(SHORT.q0)
    q0[2] = 2 * np.pi + 0.5
    sc = dataclasses.replace(SHORT, grid=(T0, DT, 2), q0=tuple(q0))
    tr = ExudynEngine(disc, build="redundant").simulate(sc)
    np.testing.assert_allclose(tr.q[0], initial_state(disc, sc).q, rtol=0, atol=1e-12)
    assert np.abs(tr.q[:, 2] - (2 * np.pi + 0.5)).max() < 0.1
    assert tr.settings["dq"] == ("solved from the bodies' angular velocities and the rear hub "
                                 "velocity (linear map, engines.exudyn.mapping)")
    assert "rear_hub_height_drift" in tr.settings


def test_a_run_writes_no_files(engine, tmp_path, monkeypatch):
    """No solution or sensor files (module docstring): a run in an empty folder leaves it
    empty. Planted: the solution file written."""
    monkeypatch.chdir(tmp_path)
    engine.simulate(SHORT)
    assert sorted(p.name for p in tmp_path.rglob("*")) == []
