"""Drake's forward run (engines/drake/run.py): the fall event, the rider torques late in a run
and the per-wheel normal forces, against the module's docstring.

* The fall: "|theta| >= fall_limit after a step ends the run; the event is interpolated
  linearly between the two steps around it" (docs/engines.md: 'fell', "the final row is the
  fall itself"). The two steps are read from the same run sampled at every Drake step (the
  scenario replay, starting upright and leaning steadily), the fall limit placed between them
  by the test, and the final row checked against the linear interpolation formed here: the
  fraction s of the step at which |theta| reaches the limit, the state and rates at s, the time
  t_k + s h and the scenario's torque function evaluated at that time.
* The loads: the rider torques single-sided on the thesis's bodies (steer on the fork, pedal
  on the rear wheel, anti-roll on the frame), held against the reference's S(q) T at every
  step of a run whose front wheel has turned (test_drake_run.py checks the start only, where
  the front wheel's axes are the fork's).
* The normal forces: "the ground's vertical force on the wheel from Drake's contact results".
  Drake's contact results report each point pair's force on its body B (the force on A is its
  opposite) and each hydroelastic surface's force on the body of its geometry M; several
  contacts on one wheel add up. The run's own plant (one cylinder per wheel on one half-space)
  gives at most one contact per wheel with the wheel as body A, so the function is given
  contact results in which Drake's documented API reports the other cases (a wrapper around
  the run's real plant, its bodies and geometries).

Each test names the planted bugs (mutmut's survivors of the module's second measurement) it
fails on.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from reference_model.scenarios import get_scenario, torque_input

pytest.importorskip("pydrake")

from pydrake.geometry import PenetrationAsPointPair  # noqa: E402
from pydrake.multibody.math import SpatialForce  # noqa: E402
from pydrake.multibody.plant import PointPairContactInfo  # noqa: E402
from pydrake.multibody.tree import MultibodyForces  # noqa: E402

import engines.drake.run as drake_run  # noqa: E402
from engines.drake.contact_plant import build_run_plant  # noqa: E402
from engines.drake.options import RunSettings  # noqa: E402

from test_drake_run import _loaded_scenario, _Spy, engine, model  # noqa: E402,F401  (its fixtures)

#: the grid's start (s), off the step lattice; Drake's default step (s); the output interval
T0 = 1e-4
H = 5e-4
DT = 2e-3
THETA = 3
#: Drake steps in the per-step run (6 ms)
STEPS = 12


def _replay(dt, n):
    return dataclasses.replace(get_scenario("replay"), grid=(T0, dt, n))


@pytest.fixture(scope="module")
def steps(engine):
    """replay sampled at every Drake step (grid interval = the step), 12 steps, no fall (the
    scenario's limit 1.4 rad): the states the fall runs below interpolate between."""
    run = engine.simulate(_replay(H, STEPS + 1))
    assert run.status == "completed"
    lean = np.abs(run.q[:, THETA])
    assert lean[0] == 0.0 and np.all(np.diff(lean) > 1e-4)     # upright, leaning steadily
    return run


def _expected_fall(steps, k, fall_limit):
    """The final row of a fall during step k (from sample k-1 to k of the per-step run): the
    linear interpolation at the fraction s where |theta| reaches the limit."""
    th0, th1 = abs(steps.q[k - 1, THETA]), abs(steps.q[k, THETA])
    s = (fall_limit - th0) / (th1 - th0)
    assert 0.0 < s <= 1.0
    q = steps.q[k - 1] + s * (steps.q[k] - steps.q[k - 1])
    dq = steps.dq[k - 1] + s * (steps.dq[k] - steps.dq[k - 1])
    return s, float(steps.t[k - 1]) + s * H, q, dq


def _check_fall(run, steps, model, k, fall_limit):
    s, t_event, q, dq = _expected_fall(steps, k, fall_limit)
    assert run.status == "fell", run.message
    assert run.t_end == run.t[-1] == pytest.approx(t_event, rel=0, abs=1e-15)
    assert run.message == (f"|theta| reached the fall limit {fall_limit:.4f} rad at "
                           f"t = {run.t_end:.6f} s")
    assert run.timing["steps"] == k
    scale = np.abs(steps.dq[k]).max()
    assert np.allclose(run.q[-1], q, rtol=0, atol=1e-14)
    assert np.allclose(run.dq[-1], dq, rtol=0, atol=1e-12 * scale)
    assert abs(abs(run.q[-1, THETA]) - fall_limit) < 1e-15
    f = torque_input(model, _replay(DT, 4))
    assert np.array_equal(run.T[-1], np.asarray(f(run.t_end), dtype=float).reshape(3))
    return s


def test_a_fall_in_the_first_step_ends_the_run_at_the_interpolated_instant(engine, steps,
                                                                           model):
    """The lean reaches a limit of 0.4 x |theta| after the first step inside that step (s =
    0.4, |theta| starts at 0): the run holds two rows, the initial state and the fall, the
    latter the per-step run's first two states and rates interpolated at s = 0.4, at t0 +
    0.4 h, with the torque function evaluated there; one step taken. Planted: the rates set
    back with s subtracted, divided by the step's change or the change taken as a sum; the
    event time t_k - s h; the extra sample's test read from the second row or the
    second-to-last (there is only one row before it); the torque evaluated at None."""
    fall_limit = 0.4 * abs(steps.q[1, THETA])
    run = engine.simulate(_replay(DT, 4), fall_limit=fall_limit)
    s = _check_fall(run, steps, model, 1, fall_limit)
    assert s == pytest.approx(0.4, rel=1e-12)
    assert run.t.size == 2
    assert np.array_equal(run.q[0], steps.q[0]) and np.array_equal(run.dq[0], steps.dq[0])


def test_a_fall_between_samples_is_interpolated_between_the_two_steps_around_it(engine,
                                                                                steps, model):
    """A limit 30 % of the way from |theta| after step 6 to after step 7, on the 2 ms grid (4
    steps a sample): the samples at steps 0 and 4 are the per-step run's, then the fall,
    interpolated between steps 6 and 7 (not between the samples), at t0 + 6.3 h; 7 steps.
    Planted: as above (the rates, the event time, the torque at None)."""
    th6, th7 = abs(steps.q[6, THETA]), abs(steps.q[7, THETA])
    fall_limit = th6 + 0.3 * (th7 - th6)
    run = engine.simulate(_replay(DT, 4), fall_limit=fall_limit)
    _check_fall(run, steps, model, 7, fall_limit)
    assert run.t.size == 3
    assert np.array_equal(run.q[:2], steps.q[[0, 4]])
    assert np.array_equal(run.dq[:2], steps.dq[[0, 4]])


def test_a_lean_exactly_at_the_limit_after_a_step_is_a_fall_at_that_step(engine, steps,
                                                                         model):
    """The module docstring: "|theta| >= fall_limit after a step ends the run". A limit equal,
    bit for bit, to |theta| after step 6 (read from the per-step run, the same Drake steps)
    ends the run at step 6 (s = 1): the final row is that step's state at its time t0 + 6 h.
    Planted: the fall's test strict (the run goes on to step 7)."""
    fall_limit = float(abs(steps.q[6, THETA]))
    run = engine.simulate(_replay(DT, 4), fall_limit=fall_limit)
    s = _check_fall(run, steps, model, 6, fall_limit)
    assert s == 1.0
    assert run.t_end == pytest.approx(T0 + 6 * H, rel=0, abs=1e-15)


def test_a_fall_at_the_start_to_round_off_adds_no_second_row_at_the_same_time(engine, steps):
    """A fall limit of 1e-25 rad on replay's upright start (|theta| = 0 there, so no fall at
    the start): the first step passes it at s = 1e-25 / |theta_1| ~ 6e-22, and the fall
    instant t0 + s h is t0 itself in floating point (s h ~ 3e-25 s, far below t0's round-off
    ~1e-20 s). The run ends there with its single row, the initial state, which is the fall to
    round-off; it adds no second row at the same time (docs/engines.md: the run reports on the
    scenario's grid, strictly increasing, "the final row is the fall itself"). Planted: the
    extra sample added when its time equals the last row's (a duplicate row at t0)."""
    s = 1e-25 / abs(steps.q[1, THETA])
    assert T0 + s * H == T0
    run = engine.simulate(_replay(DT, 4), fall_limit=1e-25)
    assert run.status == "fell"
    assert run.t.tolist() == [T0] and run.t_end == T0 and run.q.shape == (1, 8)
    assert np.array_equal(run.q[0], steps.q[0]) and np.array_equal(run.dq[0], steps.dq[0])
    assert run.timing["steps"] == 1
    assert run.message == "|theta| reached the fall limit 0.0000 rad at t = 0.000100 s"


@pytest.fixture(scope="module")
def loaded(engine):
    """The loaded scenario of test_drake_run.py (turned, leaned, steered, rolling at 10 rad/s,
    torques 2, -3, 5 N m) with its loads recorded at every step."""
    spy = _Spy()
    with pytest.MonkeyPatch.context() as mp:
        spy.install(mp)
        run = engine.simulate(_loaded_scenario())
    return run, spy


def test_the_rider_torques_are_the_references_at_every_step(loaded, model):
    """The rider torques Drake is given, mapped to generalized forces by Drake itself (each
    recorded applied spatial force's torque added to its body, MultibodyPlant's
    CalcGeneralizedForces; the drag's force left out), are the reference's S(q) T at every
    step's state (generated code, the thesis's single-sided torques), to round-off (1e-12 of
    the largest, ~5 N m). Over the 20 ms the front wheel turns by ~0.2 rad relative to the
    fork, so a steer torque about the front wheel's axis instead of the fork's shows (~0.4 N m).
    Planted: the steer torque's axis read from the front wheel's orientation."""
    _, spy = loaded
    rp = spy.rp
    plant, mp = rp.plant, rp.mapping
    ctx = plant.CreateDefaultContext()
    eps = []
    for call in spy.calls:
        plant.SetPositions(ctx, call["x"])
        plant.SetVelocities(ctx, call["v"])
        forces = MultibodyForces(plant)
        for body_index, _, F in call["forces"]:
            torque_only = SpatialForce(np.array(F.rotational()), np.zeros(3))
            plant.get_body(body_index).AddInForce(ctx, np.zeros(3), torque_only,
                                                  plant.world_frame(), forces)
        got = np.delete(mp.v_from_drake(plant.CalcGeneralizedForces(ctx, forces)), 2)
        q = np.delete(mp.q_from_drake(call["x"]), 2)
        expected = np.asarray(model.S(q)) @ call["T"]
        assert np.abs(got - expected).max() <= 1e-12 * np.abs(expected).max()
        eps.append(q[7])
    assert len(spy.calls) > 40 and np.ptp(eps) > 0.1      # the front wheel has turned


class _Results:
    """Contact results as Drake's ContactResults reports them (its accessors), holding the
    given point pairs and hydroelastic contacts."""

    def __init__(self, pairs=(), surfaces=()):
        self.pairs, self.surfaces = list(pairs), list(surfaces)

    def num_point_pair_contacts(self):
        return len(self.pairs)

    def point_pair_contact_info(self, i):
        return self.pairs[i]

    def num_hydroelastic_contacts(self):
        return len(self.surfaces)

    def hydroelastic_contact_info(self, i):
        return self.surfaces[i]


class _Surface:
    """A hydroelastic contact as Drake's HydroelasticContactInfo reports it: the contact
    surface's geometries M and N and the force on the body of M (F_Ac_W)."""

    def __init__(self, id_M, id_N, fz):
        self._ids, self._F = (id_M, id_N), SpatialForce(np.zeros(3), np.array([0.3, -0.2, fz]))

    def contact_surface(self):
        return self

    def id_M(self):
        return self._ids[0]

    def id_N(self):
        return self._ids[1]

    def F_Ac_W(self):
        return self._F


class _Port:
    def __init__(self, value):
        self._value = value

    def Eval(self, ctx):
        return self._value


class _ReportingPlant:
    """The run's real plant, its contact results output port reporting ``results``."""

    def __init__(self, plant, results):
        self._plant, self._results = plant, results

    def __getattr__(self, name):
        return getattr(self._plant, name)

    def get_contact_results_output_port(self):
        return _Port(self._results)


@pytest.fixture(scope="module")
def run_plant(model):
    return build_run_plant(model.params, RunSettings())


def _pair(a, b, fz):
    """A point pair between bodies a and b, the force on b (N) vertical fz (and some
    horizontal force, which is not the normal force)."""
    return PointPairContactInfo(a.index(), b.index(), np.array([5.0, -7.0, fz]),
                                np.zeros(3), 0.0, 0.0, PenetrationAsPointPair())


def test_the_normal_forces_add_every_point_pair_on_each_wheel(run_plant):
    """Drake's PointPairContactInfo: contact_force() is the force on body B, the force on A
    its opposite. The ground pushing up 300 N on the rear wheel as body A (the ground's force
    -300 N) and 120 N as body B, 250 N on the front wheel as body A, and a pair between the
    frame and the ground (not a wheel): the normal forces are 300 + 120 = 420 N rear, 250 N
    front. Planted: the force on body B doubled; a pair's force replacing the wheel's sum
    instead of adding to it."""
    rear, front = run_plant.wheels[2], run_plant.wheels[5]
    plant = run_plant.plant
    world, frame = plant.world_body(), plant.GetBodyByName("frame")
    results = _Results(pairs=[_pair(rear, world, -300.0), _pair(world, rear, 120.0),
                              _pair(front, world, -250.0), _pair(frame, world, -999.0)])
    rp = dataclasses.replace(run_plant, plant=_ReportingPlant(plant, results))
    assert drake_run._normal_forces(rp) == (420.0, 250.0)


def test_the_normal_forces_add_every_hydroelastic_surface_on_each_wheel(run_plant):
    """Drake's HydroelasticContactInfo: F_Ac_W is the force on the body of the surface's
    geometry M. Two surfaces between the rear wheel's cylinder and the ground, the wheel as M
    (pushed up 200 N) and as N (the ground, as M, pushed down 150 N), and one on the front
    wheel (pushed up 80 N): the normal forces are 350 N rear and 80 N front, the sizes of the
    vertical forces (the ground pushes up). Planted: a surface's force replacing the wheel's
    sum instead of adding to it."""
    plant = run_plant.plant
    rear, front = (plant.GetCollisionGeometriesForBody(run_plant.wheels[b])[0] for b in (2, 5))
    ground = plant.GetCollisionGeometriesForBody(plant.world_body())[0]
    results = _Results(surfaces=[_Surface(rear, ground, 200.0), _Surface(ground, rear, -150.0),
                                 _Surface(front, ground, 80.0)])
    rp = dataclasses.replace(run_plant, plant=_ReportingPlant(plant, results))
    assert drake_run._normal_forces(rp) == (350.0, 80.0)
