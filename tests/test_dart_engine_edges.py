"""The DART adapter (engines/dart/engine.py) at the edges the term comparison does not reach:
one state instead of a batch (the comparison only passes batches), ``forward`` itself (its
multipliers, its status per state, its Baumgarte terms; the comparison sees only
``forward_acceleration`` at consistent, finite states), the non-finite and the singular states,
``forward_acceleration``'s one-line error, and the run options that reach the engine's
settings. Expected values: the reference model's own terms and ``forward`` (generated C, an
independent formulation) and the documented contract (docs/engines.md, the engine's
docstrings). Each test names the planted bugs (mutmut's survivors of the module's first
measurement) it was seen failing on.

Cost in make test: about 0.2 s (two skeletons, a few dozen single-state evaluations).
"""

from __future__ import annotations

import numpy as np
import pytest

from comparisons.judgments.terms import random_states
from engines import EngineUsageError
from engine_edge_checks import SINGULAR, close
from reference_model import load_model

dart = pytest.importorskip("dartpy")

from engines.dart import DartEngine  # noqa: E402

#: the reference's name of a term where it is not the engine's
REFERENCE_NAME = {"gravity": "Qgrav"}


@pytest.fixture(scope="module")
def built():
    """(thesis-disc model, its DART engine), built once."""
    model = load_model("thesis-disc")
    return model, DartEngine(model)


@pytest.fixture(scope="module")
def states():
    """Three random states (large lean, steer near +-pi/2, fast rates), away from the
    constraints: C and D dq are not zero, so the Baumgarte terms count."""
    return random_states(3, seed=7)


@pytest.mark.parametrize("term, args, rel", [
    ("mass_matrix", ("q",), 1e-12), ("gravity", ("q",), 1e-12), ("S", ("q",), 1e-12),
    ("inverse_dynamics", ("q", "dq", "ddq"), 1e-10),
    ("generalized_forces", ("q", "dq", "T"), 1e-10),
    ("constraint_residual", ("q", "dq"), 1e-12), ("constraint_jacobian", ("q",), 1e-12),
    ("constraint_bias", ("q", "dq"), 1e-10), ("forward_acceleration", ("q", "dq", "T"), 1e-9)])
def test_one_state_gives_the_terms_of_one_state(built, states, term, args, rel):
    """Contract (docs/engines.md): every method takes one state, (8,) (torques (3,)), and
    returns the one-state shape, (8, 8) / (8,) / (8, 3) / (5, 8) / (5,), with the reference's
    values at the term comparison's bounds (round-off: 1e-12 for M, gravity, S, C and D, 1e-10
    for the forces and dD dq, 1e-9 for ddq). Planted: S's row helper given None, no function,
    no state or the state twice; the torques dropped on the one-state path of the
    row helper; generalized_forces's one-state flag lost (the torques taken as one row per
    coordinate, the second row of the torques taken); forward's one-state flag lost (q read
    as 8 states or 2)."""
    model, eng = built
    values = [getattr(states, a)[1] for a in args]
    close(getattr(eng, term)(*values), getattr(model, REFERENCE_NAME.get(term, term))(*values),
           rel)


def test_s_on_a_batch_is_the_references_row_by_row(built, states):
    """S (the rider torques' generalised-force matrix, read by the reference's solvers and not
    by the term comparison) on a batch of three states: (3, 8, 3), the reference's to
    round-off (1e-12 of the largest entry: both are unit axes through Jacobians). Planted: S's
    row helper given None, no function, no state or the state twice."""
    model, eng = built
    close(eng.S(states.q), model.S(states.q), 1e-12)


def test_forward_on_one_state_is_the_references_with_baumgarte_terms(built, states):
    """forward(q, dq, T, baumgarte=(a1, a2)) on one state solves [M D'; D 0][ddq; lambda] =
    [F + S T; -dD dq - 2 a1 D dq - a2^2 C] (its docstring): ddq (8,), the multipliers (5,) and
    the status as an array of one state (the reference's solvers read ``status[0]``), equal to
    the reference's forward with the same (a1, a2) = (5, 7) at a state off the constraints,
    where 2 a1 D dq and a2^2 C are of the size of ddq itself (1e-9 of the largest entry, the
    comparison's bound for ddq). Planted: a1 read from baumgarte[1]; either Baumgarte term's
    sign flipped, a product made a quotient, 2 a1 made 3 a1; the first row of a one-state
    result replaced by the second, by None or dropped; the status left out."""
    model, eng = built
    q, dq, T = states.q[0], states.dq[0], states.T[0]
    res, ref = eng.forward(q, dq, T, baumgarte=(5.0, 7.0)), model.forward(q, dq, T, (5.0, 7.0))
    exact = model.forward(q, dq, T)
    assert np.abs(ref.ddq - exact.ddq).max() > 1.0          # the Baumgarte terms do count
    close(res.ddq, ref.ddq, 1e-9)
    close(res.lam, ref.lam, 1e-9)
    assert res.status.shape == (1,) and res.status[0] == 0 and ref.status[0] == 0


def test_forward_on_a_batch_gives_the_multipliers_row_by_row(built, states):
    """A batch of three states with one torque row each: ddq (3, 8), lambda (3, 5) and status
    (3,), the reference's (1e-9 of the largest entry). Planted: the multipliers replaced by
    the status column or by None, on the batch path or on both."""
    model, eng = built
    res = eng.forward(states.q, states.dq, states.T, baumgarte=(0.5, 2.0))
    ref = model.forward(states.q, states.dq, states.T, (0.5, 2.0))
    close(res.ddq, ref.ddq, 1e-9)
    close(res.lam, ref.lam, 1e-9)
    assert res.lam.shape == (3, 5) and list(res.status) == [0, 0, 0]


@pytest.mark.parametrize("method", ["forward", "generalized_forces"])
def test_one_state_with_a_row_of_torques_is_refused_like_the_reference(built, states, method):
    """Contract: torques are (3,) for one state; a (1, 3) row (the batch form) with one state
    is refused with torque_array's one-line ValueError, as the reference's methods refuse it.
    Planted: the one-state flag not passed to torque_array (a (1, 3) row then accepted)."""
    model, eng = built
    q, dq, T = states.q[0], states.dq[0], states.T[:1]
    with pytest.raises(ValueError, match=r"torques must have shape \(3,\)") as theirs:
        getattr(model, method)(q, dq, T)
    with pytest.raises(ValueError) as mine:
        getattr(eng, method)(q, dq, T)
    assert str(mine.value) == str(theirs.value)


def test_a_non_finite_state_is_status_2_with_nan_and_the_others_are_solved(built, states):
    """forward never raises (its docstring, docs/engines.md): a batch of four states, the
    first finite, then a NaN lean, an infinite steer rate, a NaN pedal torque (q and dq
    finite). The reference's status is [0, 2, 2, 2]; DART's must be the same, the three bad
    rows NaN in float arrays of the batch's shapes, the good row the reference's. Planted: the
    finiteness check's `and` made `or` in either place (a NaN in dq or in T alone then passes
    to the solve and comes back as status 1); the NaN rows built with None as their fill or
    size, or with the status 3."""
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
    """At SINGULAR the constrained system is singular: the reference's forward says 1,
    and so must DART's (its docstring: 1 singular), with NaN accelerations and multipliers of
    the one-state shapes, never raising. Planted: the singular result's arrays built with
    None as their fill or size, or the singular state reported as status 2."""
    model, eng = built
    zero = np.zeros(8)
    assert model.forward(SINGULAR, zero).status[0] == 1
    res = eng.forward(SINGULAR, zero)
    assert list(res.status) == [1]
    assert res.ddq.shape == (8,) and res.lam.shape == (5,)
    assert res.ddq.dtype == np.float64 and res.lam.dtype == np.float64
    assert np.isnan(res.ddq).all() and np.isnan(res.lam).all()


def test_a_finite_state_whose_solve_overflows_is_not_reported_as_solved(built, disc):
    """A finite state with rates of 1e200: DART's quadratic velocity terms overflow and the
    solve comes back NaN. Its status is the reference's on the same state, 2 ('the state or
    the result is not finite'; it was 1, 'singular', a false cause), never 0 (docs/engines.md:
    never NaN as a result). Planted: the finiteness test of the solution made always true
    (NaN returned as solved); the non-finite solution reported as status 1."""
    _, eng = built
    with np.errstate(all="ignore"):
        res = eng.forward(np.zeros(8), np.full(8, 1e200))
        ref = disc.forward(np.zeros(8), np.full(8, 1e200))
    assert list(ref.status) == [2]
    assert list(res.status) == list(ref.status)
    assert not np.isfinite(np.concatenate([res.ddq, res.lam])).all()


def test_forward_acceleration_names_the_first_bad_state_and_why_in_one_line(built, states):
    """docs/engines.md: a state that cannot be evaluated raises ArithmeticError with a
    one-line message. Batches where only the last state is bad: the singular one and the
    non-finite one, each named by its index and its reason. Planted: the message None or
    built with `-`; the index of the second bad state read (there is none); the reason chosen
    by status != 1, == 2, or always one of the two; either reason's text changed."""
    _, eng = built
    q, dq, T = states.q[:2].copy(), states.dq[:2].copy(), states.T[:2]
    q[1], dq[1] = SINGULAR, 0.0
    with pytest.raises(ArithmeticError) as err:
        eng.forward_acceleration(q, dq, T)
    assert str(err.value) == "engine 'dart': at state 1 the constrained system is singular"
    q = np.vstack([states.q, states.q[:1]])
    dq = np.vstack([states.dq, states.dq[:1]])
    dq[3, 0] = np.nan
    with pytest.raises(ArithmeticError) as err:
        eng.forward_acceleration(q, dq, np.zeros(3))
    assert str(err.value) == "engine 'dart': at state 3 the state or the result is not finite"


@pytest.fixture(scope="module")
def tuned():
    """A DART engine built with the two run options that are not the defaults' kind."""
    return DartEngine(load_model("thesis-disc"), wheel_half_width=0.02, split_impulse=True)


def test_the_wheel_half_width_and_split_impulse_options_reach_the_settings(tuned):
    """The engine's options are its run settings (options.RunSettings, docs/engines.md's
    table): a half-width of 2 cm (default 1e-6 m) and split impulse on (default off) are
    what the engine keeps. Planted: either option not passed on (its default kept)."""
    assert tuned.settings.wheel_half_width == 0.02
    assert tuned.settings.split_impulse is True


@pytest.mark.parametrize("option, value", [("wheel_half_width", 0.0),
                                           ("split_impulse", "sometimes")])
def test_a_bad_wheel_half_width_or_split_impulse_is_refused_in_one_line(built, option, value):
    """A zero half-width, a split impulse that is not true or false: EngineUsageError naming
    the option, in one line (options.RunSettings.checked). Planted: either option not passed
    on (the default checked instead, the bad value accepted)."""
    model, _ = built
    with pytest.raises(EngineUsageError, match=f"DART option {option} = ") as info:
        DartEngine(model, **{option: value})
    assert "\n" not in str(info.value)
