"""The Pinocchio adapter's edges (engines/pinocchio/engine.py), issue 24: the calling forms the
conformance suite does not use (one state, torques as a tuple, a list or another dtype, one
rate row for a batch, integer input), the status of each kind of failed solve, and the shapes
of the thesis's 13x13 solve. Expected values: the reference model's own terms and solves (a
second formulation: the thesis's generated equations, not Pinocchio's algorithms), to 1e-9
of each quantity's size (the two agree to ~4e-12 there: round-off of two independent
computations of M, the forces and D, amplified by the solves). Each test names the planted
bugs (mutmut's survivors of its first run) it was seen failing on."""

import dataclasses
import warnings

import numpy as np
import pytest

from comparisons.judgments.terms import random_states
from reference_model import load_model
from round_off import assert_round_off
from reference_model.model import ModelEvaluationError
from reference_model.scenarios import SCENARIOS

pin = pytest.importorskip("pinocchio")

from engines.pinocchio import PinocchioEngine  # noqa: E402

STATES = random_states(3, seed=11)
T3 = (1.5, -2.0, 0.75)                 # steer, pedal and anti-roll torques, N m


@pytest.fixture(scope="module")
def model():
    return load_model("thesis")


@pytest.fixture(scope="module")
def engine(model):
    return PinocchioEngine(model)


@pytest.mark.parametrize("form", ["tuple", "list", "float32", "int", "float64"])
def test_one_state_forward_takes_torques_in_any_form(engine, model, form):
    """One state with the torques as a tuple, a list, a float32 or an integer array, or the
    solvers' float64 (3,) array: the same accelerations and multipliers as the reference's.
    (The float32 torques are the values float32 holds; the integer ones are rounded.)
    Planted: the fast path taken for any input (`or True`), for any array or any (3,) shape
    (`and` -> `or`), for non-float64 arrays (`!=`), for shape (4,); the slow path's
    `torque_array` given no torques, another count or its first row skipped."""
    values = {"tuple": T3, "list": list(T3), "float32": np.array(T3, dtype=np.float32),
              "int": np.array([2, -1, 3]), "float64": np.array(T3)}[form]
    q, dq = STATES.q[0], STATES.dq[0]
    got = engine.forward(q, dq, values)
    ref = model.forward(q, dq, np.asarray(values, dtype=float))
    assert got.status.tolist() == [0]
    assert_round_off(got.ddq, ref.ddq)
    assert_round_off(got.lam, ref.lam)


def test_the_default_torques_are_zero_for_one_state(engine, model):
    """Planted: the default tuple handed to the solve unconverted."""
    q, dq = STATES.q[1], STATES.dq[1]
    assert_round_off(engine.forward(q, dq).ddq, model.forward(q, dq).ddq)
    assert_round_off(engine.forward_acceleration(q, dq), model.forward_acceleration(q, dq))


def test_integer_states_are_read_as_floats(engine, model):
    """q and dq as lists of integers (a state typed by hand), one state and a batch. Planted:
    the conversion to float dropped (Pinocchio refuses an integer vector)."""
    q = [0, 0, 0, 0, 0, 0, 0, 0]
    dq = [1, 0, 0, 0, 0, 0, 2, 0]
    ref = model.forward(np.array(q, float), np.array(dq, float), T3)
    assert_round_off(engine.forward(q, dq, T3).ddq, ref.ddq)
    batch = engine.forward([q, q], dq, T3)
    assert_round_off(batch.ddq, np.vstack([ref.ddq, ref.ddq]))


def test_a_batch_takes_one_rate_row_and_per_state_torques(engine, model):
    """Three states, one dq row for all (broadcast, as the docstring's solvers pass a
    constant rate), torques per state: each row as the reference's own solve of that state;
    the status an int array, one per state. Planted: the status array's dtype dropped, the
    torques read as one state's."""
    T = np.array([T3, (0.0, 1.0, 0.0), (-3.0, 0.0, 2.0)])
    dq = STATES.dq[0]
    got = engine.forward(STATES.q, dq, T)
    ref = model.forward(STATES.q, np.tile(dq, (3, 1)), T)
    assert got.status.dtype == np.intc and got.status.shape == (3,) and not got.status.any()
    assert_round_off(got.ddq, ref.ddq)
    assert_round_off(got.lam, ref.lam)


def test_each_failed_solve_has_its_status(engine):
    """The docstring's statuses: 0 solved, 1 a non-finite result from a finite state (rates of
    1e160 rad/s: their squares overflow in the bias, so the solve returns inf from finite
    input), 2 a non-finite state (a NaN torque). Planted: `finite` None (every failure 2),
    status 1 never given (`and False`, `2 if finite`)."""
    q = STATES.q[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        big = engine.forward(q, np.full(8, 1e160), (0.0, 0.0, 0.0))
        nan = engine.forward(q, STATES.dq[0], (np.nan, 0.0, 0.0))
    assert big.status.tolist() == [1] and nan.status.tolist() == [2]
    assert engine.forward(q, STATES.dq[0]).status.tolist() == [0]


def test_forward_acceleration_refuses_a_failed_solve_by_name(engine):
    """A NaN torque in the second of two states: the error names the engine's call, the
    state and its status (the harness prints it as the engine's failure). Planted: the status
    or the call's name not passed on."""
    T = np.array([T3, (np.nan, 0.0, 0.0)])
    with pytest.raises(ModelEvaluationError, match=r"^pinocchio forward_acceleration: state 1 "
                       r"\(1 state\(s\) in all\): "):
        engine.forward_acceleration(STATES.q[:2], STATES.dq[:2], T)


def test_the_thesis_solve_splits_its_unknowns(engine, model):
    """The 13x13 system's unknowns: ddq (8), the rider torques (3), the multipliers (5) and a
    status per state (int), for one state and a batch, each as the reference's own solve.
    Planted: every slice boundary moved by one, the status's size, dtype or count."""
    ind = np.array([0.3, -0.2, 0.5])
    one = engine.inverse_dynamics_step(STATES.q[0], STATES.dq[0], ind)
    ref = model.inverse_dynamics_step(STATES.q[0], STATES.dq[0], ind)
    assert [np.shape(x) for x in one] == [(8,), (3,), (5,), (1,)]
    assert one[3].dtype == np.intc and not one[3].any()
    for got, want in zip(one[:3], ref[:3]):
        assert_round_off(got, want)
    inds = np.array([ind, -ind, 2 * ind])
    many = engine.inverse_dynamics_step(STATES.q, STATES.dq, inds)
    refs = model.inverse_dynamics_step(STATES.q, STATES.dq, inds)
    assert [np.shape(x) for x in many] == [(3, 8), (3, 3), (3, 5), (3,)]
    assert many[3].dtype == np.intc and not many[3].any()
    for got, want in zip(many[:3], refs[:3]):
        assert_round_off(got, want)


def test_generalized_forces_with_torques_one_state_and_a_batch(engine, model):
    """F + S T for one state (an (8,) result) and for a batch with a torque row per state.
    Planted: one state taken for a batch (`single` None or from another argument), the
    torques' count or row, the bias-free kinematics switched (same numbers: not planted)."""
    q, dq = STATES.q[0], STATES.dq[0]
    one = engine.generalized_forces(q, dq, T3)
    assert one.shape == (8,)
    assert_round_off(one, model.generalized_forces(q, dq, T3))
    T = np.array([T3, (0.0, 0.0, 1.0), (2.0, 2.0, 2.0)])
    assert_round_off(engine.generalized_forces(STATES.q, STATES.dq, T),
           model.generalized_forces(STATES.q, STATES.dq, T))


def test_a_forward_run_passes_its_options_to_the_solvers(engine):
    """`simulate(scenario, progress=...)` reaches the integrator: the callback sees the
    integrator's times, up to the run's end. A 0.2 s piece of the psi_dot(0) = 5 rad/s run. Planted: the options
    dropped."""
    sc = SCENARIOS["stability-psid5"]
    short = dataclasses.replace(sc, grid=(sc.grid[0], sc.grid[1], 21))   # (t0, dt, n): 0.2 s
    seen = []
    traj = engine.simulate(short, progress=seen.append)
    assert seen and max(seen) >= 0.2 - 1e-12 and len(traj.t) == 21


@pytest.mark.parametrize("array", [False, True])
@pytest.mark.parametrize("call", ["forward", "generalized_forces"])
def test_one_state_refuses_a_row_of_torques_as_the_reference_does(engine, model, call, array):
    """One state with torques shaped (1, 3): a batch's row where one state's (3,) belongs is
    refused, naming the shape wanted, as the reference refuses it (a (1, 3) result where an
    (8,) was asked would follow), a list or a float64 array alike. Planted: the one-state flag
    not passed to `torque_array`, the solvers' fast path taken for any shape but (3,)."""
    q, dq = STATES.q[0], STATES.dq[0]
    row = np.array([T3]) if array else [list(T3)]
    with pytest.raises(ValueError, match=r"torques must have shape \(3,\)") as ref:
        getattr(model, call)(q, dq, row)
    with pytest.raises(ValueError, match=r"torques must have shape \(3,\)") as got:
        getattr(engine, call)(q, dq, row)
    assert str(got.value) == str(ref.value)
