"""The Kane engine's edges (engines/kane/engine.py), issue 24: the condition estimate that
chooses the dependent speeds, the refusals of bad shapes (each naming its argument), one
state against a batch, Baumgarte's two gains apart, the statuses and messages of failed
solves. Expected values: numpy's own condition number, and the reference model (the thesis's
equations on the disc-contact bicycle, a formulation independent of Moore's), to 1e-9 of each
quantity's size (they agree to ~3e-11 relative there). Each test names the planted bugs
(mutmut's survivors of its first run) it was seen failing on."""

import dataclasses
import re
import warnings

import numpy as np
import pytest

from comparisons.judgments.terms import random_states
from engines.base import CapabilityError
from reference_model import load_model
from round_off import assert_round_off
from reference_model.scenarios import SCENARIOS

pytest.importorskip("sympy")

from engines.kane import KaneEngine  # noqa: E402
from engines.kane.engine import _DEP, RCOND_MOORE, _inverse, _speed_partition  # noqa: E402

STATES = random_states(3, seed=11)
T3 = (1.5, -2.0, 0.75)


@pytest.fixture(scope="module")
def model():
    return load_model("thesis-disc")


@pytest.fixture(scope="module")
def engine(model):
    return KaneEngine(model)


def test_the_condition_estimate_is_lapacks_one_norm_rcond():
    """rcond = 1 / (||A||_1 ||A^-1||_1), numpy's `cond(A, 1)` inverted, on a matrix whose
    columns and rows have unequal sums (so any other axis or norm gives another number);
    an exactly singular matrix gives (0, None). Planted: `*` or `/` for `/` or `*`, 2.0 for
    1.0, a sum over rows or over everything, a singular matrix reported as rcond 1."""
    A = np.array([[4.0, 1, 0, 0, 2], [0, 3, 1, 0, 0], [1, 0, 5, 2, 0], [0, 7, 0, 1, 1],
                  [2, 0, 0, 0, 6]])
    rcond, inv = _inverse(A)
    assert rcond == pytest.approx(1.0 / np.linalg.cond(A, 1), rel=1e-12)
    np.testing.assert_allclose(inv @ A, np.eye(5), atol=1e-12)
    assert _inverse(np.zeros((5, 5))) == (0.0, None)


def test_moores_partition_is_kept_where_it_is_well_conditioned(engine, model):
    """Upright at rest on the disc bicycle Moore's A_d is well conditioned: his dependent
    speeds are kept (the pivoted QR's choice is for near-singular steer angles only).
    Planted: the estimate taken of nothing (always pivoting)."""
    A = engine._generated("jacobian", (5, 8), np.zeros((1, 8)))[0]
    dep, ind, rcond, _ = _speed_partition(A)
    assert rcond >= RCOND_MOORE and list(dep) == list(_DEP)


@pytest.mark.parametrize("shape", [(7,), (2, 3, 8), (8, 2)])
def test_a_state_of_the_wrong_shape_is_refused_by_name(engine, shape):
    """Planted: the shape test's `or` as `and` (a (2, 3, 8) array let through), the message
    lost, the argument's name lost or changed."""
    good = STATES.q[0]
    with pytest.raises(ValueError, match=rf"^q must have shape \(8,\) or \(N, 8\); got {re.escape(str(shape))}$"):
        engine.mass_matrix(np.zeros(shape))
    with pytest.raises(ValueError, match=rf"^q must have shape \(8,\) or \(N, 8\); got {re.escape(str(shape))}$"):
        engine.forward(np.zeros(shape), good)
    with pytest.raises(ValueError, match=rf"^dq must have shape \(8,\) or \(N, 8\); got {re.escape(str(shape))}$"):
        engine.forward(good, np.zeros(shape))
    with pytest.raises(ValueError, match=rf"^dq must have shape \(8,\) or \(N, 8\); got {re.escape(str(shape))}$"):
        engine.constraint_bias(good, np.zeros(shape))


@pytest.mark.parametrize("call", ["forward", "generalized_forces", "constraint_bias"])
def test_states_and_rates_of_different_counts_are_refused(engine, call):
    """Planted: the message or the names lost."""
    with pytest.raises(ValueError, match=r"^q and dq must have the same shape; got \(2, 8\) and \(3, 8\)$"):
        getattr(engine, call)(STATES.q[:2], STATES.dq)


def test_torques_of_the_wrong_shape_are_refused(engine):
    """A batch of 3 states with 2 torque rows. Planted: the message lost."""
    with pytest.raises(ValueError, match=r"^torques must have shape \(3,\) or \(3, 3\) "
                       r"\[Mdir, Mped, Mvue\]; got \(2, 3\)$"):
        engine.generalized_forces(STATES.q, STATES.dq, np.zeros((2, 3)))


def test_one_state_gives_one_result_and_a_batch_a_batch(engine, model):
    """F + S T and the constraint bias for one state are (8,) and (5,), and for a batch
    (3, 8) and (3, 5), each as the reference's. Planted: a one-state result left as a batch
    of one (`_out(..., None)`)."""
    q, dq = STATES.q[0], STATES.dq[0]
    one = engine.generalized_forces(q, dq, T3)
    assert one.shape == (8,)
    assert_round_off(one, model.generalized_forces(q, dq, T3))
    bias = engine.constraint_bias(q, dq)
    assert bias.shape == (5,)
    assert_round_off(bias, model.constraint_bias(q, dq))
    assert_round_off(engine.constraint_bias(STATES.q, STATES.dq), model.constraint_bias(STATES.q, STATES.dq))


def test_integer_states_are_read_as_floats(engine, model):
    """Planted: nothing here is known to fail: integer states give the reference's M (the
    conversion to float is numpy's either way, see tests/mutation_equivalents.toml)."""
    assert_round_off(engine.mass_matrix(np.zeros(8, dtype=int)), model.mass_matrix(np.zeros(8)))


@pytest.mark.parametrize("baumgarte", [(0.0, 0.0), (10.0, 0.0), (0.0, 5.0), (10.0, 3.0)])
def test_each_baumgarte_gain_acts_on_its_own(engine, model, baumgarte):
    """D ddq = -dD dq - 2 a1 D dq - a2^2 C with either gain alone or both, at a state that
    violates the constraints (random states: C and D dq are not zero), as the reference's.
    Planted: the gains applied only when both are set (`and` for `or`), a1 read as a2."""
    q, dq = STATES.q[1], STATES.dq[1]
    got = engine.forward(q, dq, T3, baumgarte)
    ref = model.forward(q, dq, T3, baumgarte)
    assert got.status.tolist() == [0]
    assert_round_off(got.ddq, ref.ddq)
    assert_round_off(got.lam, ref.lam)


def test_a_batch_gives_every_states_multipliers(engine, model):
    """Planted: a batch's multipliers dropped (None), the status's dtype dropped."""
    T = np.array([T3, (0.0, 1.0, 0.0), (-3.0, 0.0, 2.0)])
    got = engine.forward(STATES.q, STATES.dq, T)
    ref = model.forward(STATES.q, STATES.dq, T)
    assert got.status.dtype == np.intc and got.status.tolist() == [0, 0, 0]
    assert_round_off(got.ddq, ref.ddq)
    assert_round_off(got.lam, ref.lam)


def test_one_state_refuses_a_row_of_torques(engine, model):
    """One state with torques (1, 3): refused as the reference refuses it. Planted: the
    one-state flag not passed to `torque_array`."""
    with pytest.raises(ValueError, match=r"torques must have shape \(3,\)") as ref:
        model.forward(STATES.q[0], STATES.dq[0], [list(T3)])
    with pytest.raises(ValueError, match=r"torques must have shape \(3,\)") as got:
        engine.forward(STATES.q[0], STATES.dq[0], [list(T3)])
    assert str(got.value) == str(ref.value)


def test_each_failed_solve_has_its_status_and_nan_results(engine):
    """The docstring's statuses: 1 for a finite state whose solve is not finite (rates of
    1e160 rad/s overflow in the bias), 2 for a non-finite state (a NaN torque); ddq (8,) and
    lambda (5,) NaN there. Planted: `finite` None, status 1 never given, NaN results of
    another size or of None."""
    q = STATES.q[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        big = engine.forward(q, np.full(8, 1e160))
        nan = engine.forward(q, STATES.dq[0], (np.nan, 0.0, 0.0))
    assert big.status.tolist() == [1] and nan.status.tolist() == [2]
    for res in (big, nan):
        assert res.ddq.shape == (8,) and res.lam.shape == (5,)
        assert res.ddq.dtype == float and np.isnan(res.ddq).all() and np.isnan(res.lam).all()


def test_forward_acceleration_names_the_state_and_the_failure(engine):
    """The first failed state of a batch by its index, with the reason its status gives.
    Planted: the index lost or taken from the last failure, the two reasons swapped or
    one given for both, the message lost."""
    q = np.vstack([STATES.q[0], STATES.q[0], STATES.q[0]])
    dq = np.vstack([STATES.dq[0], np.full(8, 1e160), STATES.dq[0]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        T = np.array([T3, T3, (np.nan, 0.0, 0.0)])
        with pytest.raises(ArithmeticError, match=r"^engine 'kane': at state 1 the constraints do "
                           r"not determine five speeds \(a kinematic singularity\)$"):
            engine.forward_acceleration(q, dq, T)       # states 1 and 2 fail: 1 is named
        dq[1] = STATES.dq[0]
        with pytest.raises(ArithmeticError, match=r"^engine 'kane': at state 2 the state is not finite$"):
            engine.forward_acceleration(q, dq, T)


@pytest.mark.parametrize("q", [np.full(8, np.inf), np.array([0.0] * 7 + [np.nan])])
def test_a_non_finite_term_is_an_arithmetic_error_naming_the_engine(engine, q):
    """M at a state where Moore's scalar code raises (cos(inf): a math domain error) or
    returns NaN: one ArithmeticError naming the engine. Planted: the NaN placeholder built
    with a bad shape or fill (a TypeError escapes), the message lost."""
    with pytest.raises(ArithmeticError, match=r"^engine 'kane': a non-finite value at this state$"):
        engine.mass_matrix(q)


def test_the_thesis_contact_is_refused_with_the_fix(thesis):
    """Planted: the fix's words changed."""
    with pytest.raises(CapabilityError, match=r"^engine 'kane' cannot use the front contact "
                       r"'thesis': .* use a disc-contact model \(e\.g\. thesis-disc\)$"):
        KaneEngine(thesis)


def test_a_forward_run_passes_its_options_to_the_solvers(engine):
    """Planted: the options dropped."""
    sc = SCENARIOS["stability-psid5"]
    short = dataclasses.replace(sc, model="thesis-disc", grid=(sc.grid[0], sc.grid[1], 11))
    seen = []
    traj = engine.simulate(short, progress=seen.append)
    assert seen and max(seen) >= 0.1 - 1e-12 and len(traj.t) == 11
