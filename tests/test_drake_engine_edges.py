"""The Drake adapter (engines/drake/engine.py) at the edges the term comparison does not reach:
one state instead of a batch (tests/test_drake.py's comparison passes batches only),
``forward`` itself (its multipliers, its status per state, its Baumgarte terms; the comparison
sees only ``forward_acceleration`` at finite states), the non-finite, singular and overflowing
states, ``forward_acceleration``'s one-line error, and the run options that reach the engine's
settings. Expected values: the reference model's own terms, ``forward`` and
``forward_acceleration`` (generated C, an independent formulation) and the documented contract
(docs/engines.md, the engine's docstrings, options.RunSettings). Each test names the planted
bugs (mutmut's survivors of the module's first measurement) it was seen failing on.

Cost: ~1 s to import pydrake (once per process, shared with tests/test_drake.py), a few ms per
plant (two built here), a few dozen single-state evaluations.
"""

from __future__ import annotations

import numpy as np
import pytest

from comparisons.judgments.terms import random_states
from engine_edge_checks import SINGULAR, close
from reference_model import load_model

pytest.importorskip("pydrake")

from engines.drake import DrakeEngine  # noqa: E402


@pytest.fixture(scope="module")
def built():
    """(thesis-disc model, its Drake engine), built once for the module."""
    model = load_model("thesis-disc")
    return model, DrakeEngine(model)


@pytest.fixture(scope="module")
def states():
    """Three random states (large lean, steer near +-pi/2, rates to 20 rad/s), away from the
    constraints: C and D dq are not zero, so the Baumgarte terms count."""
    return random_states(3, seed=7)


def test_generalized_forces_of_one_state_with_torques_are_the_references(built, states):
    """Contract (docs/engines.md): generalized_forces(q (8,), dq (8,), torques (3,)) returns
    Qv + Qgrav + Qaero + S T of that state, (8,), the reference's to 1e-10 of the largest
    entry (the comparison's bound for the forces), at each of the three states with its own
    torques (several N m: S T is of the size of the other terms). Planted: the one-state flag
    lost (None, or ndim of None: the torques broadcast to 8 rows and all of them passed on);
    the torques of the one state passed as the whole (1, 3) row block or as its second row."""
    model, eng = built
    for q, dq, T in zip(states.q, states.dq, states.T):
        close(eng.generalized_forces(q, dq, T), model.generalized_forces(q, dq, T), 1e-10)


def test_forward_on_one_state_is_the_references_with_baumgarte_terms(built, states):
    """forward(q, dq, T, baumgarte=(a1, a2)) on one state solves [M D'; D 0][ddq; lambda] =
    [F + S T; -dD dq - 2 a1 D dq - a2^2 C] (its docstring): ddq (8,), the multipliers (5,) and
    the status as an array of one state (the reference's solvers read ``status[0]``), equal to
    the reference's forward with the same (a1, a2) = (5, 7) at a state off the constraints,
    where 2 a1 D dq and a2^2 C are of the size of ddq itself (1e-9 of the largest entry, the
    comparison's bound for ddq). The engine's forward stands in for the reference's (duck-typed,
    the module docstring), so its status is the same kind of array, the reference's np.intc.
    Planted: either Baumgarte term's sign flipped, 2 a1 D dq made 2 a1 / D dq or 3 a1 D dq,
    a2^2 C made a2^2 / C; the one-state flag lost or its count made 2 (q read as 8 or 2
    states); the one-state result's ddq or lambda replaced by None, by the second row or
    dropped; the status None or dropped; the status array's dtype left to numpy (int64)."""
    model, eng = built
    q, dq, T = states.q[0], states.dq[0], states.T[0]
    res, ref = eng.forward(q, dq, T, baumgarte=(5.0, 7.0)), model.forward(q, dq, T, (5.0, 7.0))
    exact = model.forward(q, dq, T)
    assert np.abs(ref.ddq - exact.ddq).max() > 1.0          # the Baumgarte terms do count
    close(res.ddq, ref.ddq, 1e-9)
    close(res.lam, ref.lam, 1e-9)
    assert res.status.shape == (1,) and res.status[0] == 0 and ref.status[0] == 0
    assert res.status.dtype == ref.status.dtype == np.intc


def test_forward_on_a_batch_gives_the_multipliers_row_by_row(built, states):
    """A batch of three states with one torque row each: ddq (3, 8), lambda (3, 5) and status
    (3,), the reference's with (a1, a2) = (0.5, 2) (1e-9 of the largest entry). Planted: the
    multipliers replaced by the status column or by None, on the batch path or on both."""
    model, eng = built
    res = eng.forward(states.q, states.dq, states.T, baumgarte=(0.5, 2.0))
    ref = model.forward(states.q, states.dq, states.T, (0.5, 2.0))
    close(res.ddq, ref.ddq, 1e-9)
    close(res.lam, ref.lam, 1e-9)
    assert res.lam.shape == (3, 5) and list(res.status) == [0, 0, 0]


@pytest.mark.parametrize("method", ["forward", "generalized_forces"])
def test_one_state_with_a_row_of_torques_is_refused_like_the_reference(built, states, method):
    """Contract: torques are (3,) for one state; a (1, 3) row (the batch form) with one state
    is refused with torque_array's one-line ValueError, word for word the reference's refusal.
    Planted: the one-state flag not passed to torque_array (None: the (1, 3) row then taken as
    one state's torques)."""
    model, eng = built
    q, dq, T = states.q[0], states.dq[0], states.T[:1]
    with pytest.raises(ValueError, match=r"torques must have shape \(3,\)") as theirs:
        getattr(model, method)(q, dq, T)
    with pytest.raises(ValueError) as mine:
        getattr(eng, method)(q, dq, T)
    assert str(mine.value) == str(theirs.value)


def test_a_non_finite_state_is_status_2_with_nan_and_the_others_are_solved(built, states):
    """forward never raises (its docstring: 2 non-finite state): a batch of four states, the
    first finite, then a NaN lean, an infinite steer rate, a NaN pedal torque (q and dq
    finite). The reference's status is [0, 2, 2, 2]; Drake's must be the same, the three bad
    rows NaN in float arrays of the batch's shapes, the good row the reference's. Planted: the
    finiteness check's `and` made `or` in either place (a NaN in q, or in T alone, then passes
    to the solve and comes back as status 1); the NaN rows built with None as their fill or
    size (an object array, or a TypeError), or with the status 3."""
    model, eng = built
    q, dq, T = np.repeat(states.q[:1], 4, 0), np.repeat(states.dq[:1], 4, 0), \
        np.repeat(states.T[:1], 4, 0)
    q[1, 3], dq[2, 6], T[3, 1] = np.nan, np.inf, np.nan
    res, ref = eng.forward(q, dq, T), model.forward(q, dq, T)
    assert list(ref.status) == [0, 2, 2, 2]
    assert list(res.status) == [0, 2, 2, 2]
    assert res.ddq.shape == (4, 8) and res.lam.shape == (4, 5)
    assert res.ddq.dtype == np.float64 and res.lam.dtype == np.float64
    assert np.isnan(res.ddq[1:]).all() and np.isnan(res.lam[1:]).all()
    close(res.ddq[0], ref.ddq[0], 1e-9)


def test_the_singular_state_is_status_1_with_nan(built):
    """At SINGULAR the constrained system is singular: the reference's forward says 1, and so
    must Drake's (its docstring: 1 singular), with NaN accelerations and multipliers of the
    one-state shapes, never raising. Planted: the singular result's arrays built with None as
    their fill or size, or the singular state reported as status 2."""
    model, eng = built
    zero = np.zeros(8)
    assert model.forward(SINGULAR, zero).status[0] == 1
    res = eng.forward(SINGULAR, zero)
    assert list(res.status) == [1]
    assert res.ddq.shape == (8,) and res.lam.shape == (5,)
    assert res.ddq.dtype == np.float64 and res.lam.dtype == np.float64
    assert np.isnan(res.ddq).all() and np.isnan(res.lam).all()


def test_a_finite_state_whose_solve_overflows_is_not_reported_as_solved(built):
    """A finite state with rates of 1e200: the quadratic velocity terms overflow and the solve
    comes back non-finite. Its status is the reference's on the same state, 2 ('the state or
    the result is not finite'; it was 1, 'singular', a false cause), never 0 (docs/engines.md:
    never NaN as a result). Planted: the finiteness test of the solution made always true (NaN
    returned as solved); the non-finite solution reported as status 1."""
    model, eng = built
    with np.errstate(all="ignore"):
        res = eng.forward(np.zeros(8), np.full(8, 1e200))
        ref = model.forward(np.zeros(8), np.full(8, 1e200))
    assert list(ref.status) == [2]
    assert list(res.status) == list(ref.status)
    assert not np.isfinite(np.concatenate([res.ddq, res.lam])).all()


def test_forward_acceleration_names_the_engine_the_call_and_the_first_bad_state(built, states):
    """docs/engines.md: a state that cannot be evaluated raises ArithmeticError with a one-line
    message naming the engine, the call and the cause. Two batches whose second state is bad,
    the singular one and a NaN rate: the message is the reference's own forward_acceleration
    message for the same batch (raise_on_status: the state's index, the count, the reason),
    prefixed with 'drake '. Planted: the status not passed (None: nothing raised, NaN
    returned; dropped: a TypeError); the message's prefix None, dropped, in capitals or
    wrapped in XX."""
    model, eng = built
    q, dq, T = states.q[:2].copy(), states.dq[:2].copy(), states.T[:2]
    q[1], dq[1] = SINGULAR, 0.0
    bad_dq = states.dq[:2].copy()
    bad_dq[1, 0] = np.nan
    for args in ((q, dq, T), (states.q[:2], bad_dq, T)):
        with pytest.raises(ArithmeticError) as theirs:
            model.forward_acceleration(*args)
        with pytest.raises(ArithmeticError) as mine:
            eng.forward_acceleration(*args)
        assert str(theirs.value).startswith("forward_acceleration: state 1 (1 state(s) in all): ")
        assert str(mine.value) == "drake " + str(theirs.value)
        assert "\n" not in str(mine.value)


@pytest.fixture(scope="module")
def tuned():
    """A Drake engine built with every point-contact and geometry option away from its default
    (options.RunSettings: friction 2, point stiffness 1e8 N/m, dissipation 10 s/m,
    hydroelastic modulus 1e9 Pa, wheel half-width 1e-6 m)."""
    return DrakeEngine(load_model("thesis-disc"), friction=0.8, point_stiffness=4e7,
                       dissipation=3.0, hydroelastic_modulus=3e8, wheel_half_width=1e-3)


@pytest.mark.parametrize("option, value", [
    ("friction", 0.8), ("point_stiffness", 4e7), ("dissipation", 3.0),
    ("hydroelastic_modulus", 3e8), ("wheel_half_width", 1e-3)])
def test_each_run_option_reaches_the_settings(tuned, option, value):
    """The engine's keyword options are its run settings (its __init__, docs/engines.md's
    table): each value given is the one the engine keeps for its runs, none replaced by its
    default. Planted: friction, point_stiffness, dissipation, hydroelastic_modulus or
    wheel_half_width not passed on to settings_from (the default kept)."""
    assert getattr(tuned.settings, option) == value
    assert getattr(tuned.settings, option) != getattr(type(tuned.settings)(), option)
