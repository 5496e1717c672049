"""The reference model's calling conventions (reference_model/model.py), issue 24.

What the model promises (its docstrings, docs/model.md): every function takes one state (8,)
or a batch (N, 8) and returns the matching shape; the C and the numpy backends are the same
generated code, equal to round-off; the single-state fast path and the batch loop give the same
numbers; a wrong shape or a mismatched batch is one ValueError that names the argument and the
shapes; integers are read as floats. The independent sides here: the numpy backend against the
C one (the same expressions evaluated by numpy instead of compiled C: any glue that passes the
wrong array, offset or count to one of them shows), a batch row against its single state, and
inverse dynamics against M ddq - Qv - Qgrav composed from the other terms. Planted bugs each
test was seen failing on are named in its docstring.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from reference_model.model import (DEP, IND, Model, ModelEvaluationError, load_model,
                                   torque_array)
from round_off import assert_round_off

DATA = Path(__file__).resolve().parent / "data" / "benchmark"
Q = np.array([0.1, -0.2, 0.3, 0.2, 0.4, -0.3, 0.5, 0.1])
DQ = np.array([0.2, 0.1, -0.3, 0.4, 5.0, -0.2, 0.3, 0.6])
T = np.array([0.5, 2.0, -1.0])
#: a batch of exactly N_Q = 8 states: its first dimension is 8, like a single state's only one
BATCH = np.stack([Q + 0.01 * k for k in range(8)])
DBATCH = np.stack([DQ - 0.02 * k for k in range(8)])
TBATCH = np.stack([T * (1 + 0.1 * k) for k in range(8)])


@pytest.fixture(scope="module")
def numpy_thesis(thesis):
    """The thesis model on the numpy backend (~3 s to load its generated code, once)."""
    return Model(thesis.params, backend="numpy")


TERMS = [("mass_matrix", False), ("Qgrav", False), ("S", False), ("constraint_jacobian", False),
         ("points", False), ("potential_energy", False), ("Qv", True), ("Qaero", True),
         ("generalized_forces", True), ("constraint_residual", True), ("constraint_bias", True),
         ("kinetic_energy", True)]


def _call(model, name, q, dq):
    out = getattr(model, name)(q, dq) if dq is not None else getattr(model, name)(q)
    return np.stack([out[k] for k in sorted(out)], axis=-2) if isinstance(out, dict) else out


@pytest.mark.parametrize("name, rates", TERMS)
def test_every_term_is_the_same_on_both_backends_single_and_batched(thesis, numpy_thesis, name, rates):
    """Planted (mutmut): the numpy kernels given None or their arguments shifted, `_kernels`
    None, `backend != "c"` for the fast path (the numpy model then reads C buffers it has
    not), out[1] for out[0], the batch of 8 states taken for one state (`or` in the fast
    path's test, ndim == 2)."""
    for q, dq in ((Q, DQ), (BATCH, DBATCH)):
        want = _call(thesis, name, q, dq if rates else None)
        got = _call(numpy_thesis, name, q, dq if rates else None)
        assert np.shape(got) == np.shape(want)
        assert_round_off(got, want)
    rows = _call(thesis, name, BATCH, DBATCH if rates else None)
    one = _call(thesis, name, BATCH[3], DBATCH[3] if rates else None)
    assert_round_off(rows[3], one)


def test_forward_is_the_same_on_both_backends_paths_and_batches(thesis, numpy_thesis):
    """The fast path (one state, (3,) torques) against the batch loop and the numpy kernel:
    accelerations, multipliers and the status with its dtype. Planted: the C fast path asked
    for 2 states (its second written over the multipliers), the multipliers read at 9 N_Q,
    N_Q - N_C for N_Q + N_C, lam None, the status buffer float or of 2, each argument of the
    numpy kernel dropped or None, a1 and a2 swapped or None, the batch loop's single-state
    result read at row 1 or as the whole batch."""
    ab = (3.0, 7.0)
    fast = thesis.forward(Q, DQ, T, baumgarte=ab)
    loop = thesis.forward(BATCH, DBATCH, TBATCH, baumgarte=ab)
    by_row = thesis.forward(Q[None], DQ[None], T, baumgarte=ab)        # (1, 8): the loop
    for res in (numpy_thesis.forward(Q, DQ, T, baumgarte=ab), by_row):
        assert_round_off(res.ddq.reshape(-1), fast.ddq)
        assert_round_off(res.lam.reshape(-1), fast.lam)
    assert fast.ddq.shape == (8,) and fast.lam.shape == (5,)
    assert fast.status.shape == (1,) and fast.status.dtype == np.intc and fast.status[0] == 0
    np_loop = numpy_thesis.forward(BATCH, DBATCH, TBATCH, baumgarte=ab)
    assert_round_off(np_loop.ddq, loop.ddq)
    assert_round_off(np_loop.lam, loop.lam)
    assert np_loop.status.shape == loop.status.shape == (8,) and not loop.status.any()
    one = thesis.forward(BATCH[5], DBATCH[5], TBATCH[5], baumgarte=ab)
    assert_round_off(loop.ddq[5], one.ddq)
    assert_round_off(loop.lam[5], one.lam)
    # the gains are used, each as itself: a1 multiplies D dq, a2^2 the residual C
    swapped = thesis.forward(Q, DQ, T, baumgarte=ab[::-1])
    assert np.abs(swapped.ddq - fast.ddq).max() > 1e-6
    single = numpy_thesis.forward(Q, DQ, T)
    assert single.ddq.shape == (8,) and single.status.shape == (1,)
    # one state with its rates as a batch of one: the C batch loop, read back as one state
    mixed = thesis.forward(Q, DQ[None], T, baumgarte=ab)
    assert mixed.ddq.shape == (8,) and mixed.lam.shape == (5,) and mixed.status.shape == (1,)
    assert_round_off(mixed.ddq, fast.ddq)
    assert_round_off(mixed.lam, fast.lam)


def test_the_13x13_system_is_the_same_on_both_backends_and_returns_the_given_accelerations(
        thesis, numpy_thesis):
    """Planted: each argument of the numpy kernel None or dropped, a single state reshaped to
    (8,) instead of (1, 8), the independent accelerations not put back at IND."""
    ind = np.array([0.3, -0.5, 0.2])
    for q, dq, a in ((Q, DQ, ind), (BATCH, DBATCH, np.stack([ind * k for k in range(8)]))):
        want = thesis.inverse_dynamics_step(q, dq, a)
        got = numpy_thesis.inverse_dynamics_step(q, dq, a)
        for g, w in zip(got, want):
            assert np.shape(g) == np.shape(w)
            assert_round_off(g, w)
    ddq, torques, lam, status = thesis.inverse_dynamics_step(Q, DQ, ind)
    assert ddq.shape == (8,) and torques.shape == (3,) and lam.shape == (5,) and status.shape == (1,)
    np.testing.assert_array_equal(ddq[IND], ind)
    # the forward solve with those torques gives those accelerations back (a physical law:
    # the two systems are one)
    assert_round_off(thesis.forward_acceleration(Q, DQ, torques), ddq)
    assert set(DEP) | set(IND) == set(range(8))


def test_inverse_dynamics_is_m_ddq_minus_qv_minus_qgrav(thesis):
    """Unconstrained inverse dynamics from the other terms. Planted: mb.shape[:+1] (a single
    state's M mis-shaped), a.shape[+1:] (every single ddq refused), + for -."""
    ddq = np.linspace(-1.0, 1.0, 8)
    want = thesis.mass_matrix(Q) @ ddq - thesis.Qv(Q, DQ) - thesis.Qgrav(Q)
    assert_round_off(thesis.inverse_dynamics(Q, DQ, ddq), want)
    rows = thesis.inverse_dynamics(BATCH, DBATCH, np.stack([ddq] * 8))
    assert rows.shape == (8, 8)
    assert_round_off(rows[2], thesis.mass_matrix(BATCH[2]) @ ddq - thesis.Qv(BATCH[2], DBATCH[2])
                     - thesis.Qgrav(BATCH[2]))
    with pytest.raises(ValueError) as info:
        thesis.inverse_dynamics(Q, DQ, ddq[:7])
    assert str(info.value) == "ddq must have shape (8,) or (N, 8); got (7,)"


def test_integer_states_and_torques_are_read_as_floats(thesis):
    """Planted: dtype dropped when the states or the torques are made C arrays (the C code
    then reads int64 bits as doubles)."""
    qi, dqi, ti = np.array([0, 0, 0, 1, 0, 0, 1, 0]), np.array([0, 0, 0, 0, 5, 0, 0, 0]), np.array([1, 2, 3])
    batch = np.stack([qi, qi])
    assert_round_off(thesis.mass_matrix(batch)[1], thesis.mass_matrix(qi.astype(float)))
    res = thesis.forward(batch, np.stack([dqi, dqi]), np.stack([ti, ti]))
    assert_round_off(res.ddq[0], thesis.forward(qi.astype(float), dqi.astype(float), ti.astype(float)).ddq)


@pytest.mark.parametrize("call, message", [
    (lambda m: m.mass_matrix(Q[:7]), "q must have shape (8,) or (N, 8); got shape (7,)"),
    (lambda m: m.mass_matrix(np.zeros((2, 7))), "q must have shape (8,) or (N, 8); got shape (2, 7)"),
    (lambda m: m.Qv(Q, DQ[:7]), "dq must have shape (8,) or (N, 8); got shape (7,)"),
    (lambda m: m.Qv(Q, np.stack([DQ, DQ])), "q and dq must hold the same number of states; got 1 and 2"),
    (lambda m: m.Qv(np.stack([Q, Q]), np.stack([DQ] * 3)), "q and dq must hold the same number of states; got 2 and 3"),
    (lambda m: m.Qv(Q, None), "Qv needs the rates dq (shape (8,) or (N, 8)); got None"),
    (lambda m: m.forward(np.stack([Q] * 3), DQ), "q and dq must hold the same number of states; got 3 and 1"),
    (lambda m: m.forward(Q, np.stack([DQ] * 2)), "q and dq must hold the same number of states; got 1 and 2"),
    (lambda m: m.forward(Q, DQ[:7]), "dq must have shape (8,) or (N, 8); got shape (7,)"),
    (lambda m: m.forward(Q[:7], DQ), "q must have shape (8,) or (N, 8); got shape (7,)"),
    (lambda m: m.forward(Q, DQ, 1.0), "torques must have shape (3,) [Mdir, Mped, Mvue] in N m; got shape () "
                                      "(a scalar is not applied to all three: write (0, T, 0))"),
    (lambda m: m.forward(Q, DQ, np.zeros(4)), "torques must have shape (3,) [Mdir, Mped, Mvue] in N m; got shape (4,)"),
    (lambda m: m.forward(Q, DQ, np.zeros((1, 3))), "torques must have shape (3,) [Mdir, Mped, Mvue] in N m; got shape (1, 3)"),
    (lambda m: m.forward(np.stack([Q, Q]), np.stack([DQ, DQ]), np.zeros((3, 3))),
     "torques must have shape (3,) or (2, 3), one row per state [Mdir, Mped, Mvue] in N m; got shape (3, 3)"),
    (lambda m: m.inverse_dynamics_step(Q, DQ, np.zeros(4)), "ddq_ind must have shape (3,) or (N, 3); got shape (4,)"),
    (lambda m: m.inverse_dynamics_step(Q, DQ[:7], np.zeros(3)), "dq must have shape (8,) or (N, 8); got shape (7,)"),
    (lambda m: m.inverse_dynamics_step(Q[:7], DQ, np.zeros(3)), "q must have shape (8,) or (N, 8); got shape (7,)"),
    (lambda m: m.inverse_dynamics_step(Q, DQ, np.zeros((2, 3))), "q, dq and ddq_ind must hold the same number of states"),
    (lambda m: m.inverse_dynamics_step(Q, np.stack([DQ] * 2), np.zeros(3)), "q, dq and ddq_ind must hold the same number of states"),
])
def test_each_shape_refusal_names_the_argument_and_the_shapes(thesis, call, message):
    """Planted: the argument's name dropped or upper-cased, shape[1] for shape[0] in the
    count, `and` for `or` in either check, the (n, 3) form offered to a single state, the
    scalar's hint shown for every shape or none."""
    with pytest.raises(ValueError) as info:
        call(thesis)
    assert str(info.value) == message


def test_torque_array_broadcasts_one_row_and_keeps_per_state_rows():
    np.testing.assert_array_equal(torque_array((1, 2, 3), 2, False), [[1.0, 2.0, 3.0]] * 2)
    rows = np.arange(6.0).reshape(2, 3)
    np.testing.assert_array_equal(torque_array(rows, 2, False), rows)
    assert torque_array([[1, 2, 3], [4, 5, 6]], 2, False).dtype == np.float64


def test_a_non_finite_state_is_one_error_naming_the_call_and_the_state(thesis):
    """Planted: raise_on_status given None, or its name dropped."""
    bad = np.stack([Q, Q])
    bad[1, 3] = np.nan                    # the roll angle (xc, yc and phi are cyclic)
    with pytest.raises(ModelEvaluationError) as info:
        thesis.forward_acceleration(bad, np.stack([DQ, DQ]))
    assert str(info.value) == ("forward_acceleration: state 1 (1 state(s) in all): the state or "
                               "the result is not finite (NaN or inf in the input?)")
    res = thesis.forward(Q * np.nan, DQ)
    assert res.status.tolist() == [2]


def test_the_coordinate_indices_are_read_only():
    """IND and DEP are shared module constants: a caller cannot change them. Planted:
    writeable True or None."""
    for idx in (IND, DEP):
        with pytest.raises(ValueError):
            idx[0] = 7


def test_a_variant_is_kept_by_with_params_and_load_model_passes_its_options(thesis, numpy_thesis):
    """Planted: with_params dropping the backend or the gyroscopic flag, the backend not
    passed to the library, load_model's contact override dropped (None), the triangle flag
    not passed or on by default, its default model's name changed."""
    broken = Model(thesis.params, gyroscopic=False, backend="numpy")
    again = broken.with_params(thesis.params)
    assert (again.backend, again.gyroscopic, numpy_thesis.backend) == ("numpy", False, "numpy")
    assert load_model().name == "thesis" and load_model().contact == "thesis"
    assert load_model("thesis", contact="disc").contact == "disc"
    src = DATA / "TriangleBenchmark.txt"
    with pytest.raises(ValueError, match="triangle"):
        load_model(src)
    assert len(load_model(src, allow_triangle_violation=True).warnings) == 1
