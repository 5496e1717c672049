"""The reference model's parts that its other tests leave open (reference_model/model.py),
issue 24: the forward solve against the thesis's KKT system assembled from the model's own
public terms and solved by numpy (a second formulation of the same equations), the 13x13
inverse-dynamics system checked against the same equations, the single-state fast path the
integrators rely on, exact-type inputs (Fraction) read as floats, the status codes' wording,
the coordinate indices, the model's repr and its eigenvalues against Meijaard et al. (2007)
Table 2. Written from the survivors of `make mutants` on the module; the planted bug each test
was seen failing on is named in its docstring. About 0.2 s (the benchmark's linearization is
the bulk).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

import reference_model.model as model_module
from comparisons.judgments.published import table2_eigenvalues
from reference_model.model import (Model, ModelEvaluationError, _index, load_model,
                                   raise_on_status)
from round_off import assert_round_off

Q = np.array([0.1, -0.2, 0.3, 0.2, 0.4, -0.3, 0.5, 0.1])
DQ = np.array([0.2, 0.1, -0.3, 0.4, 5.0, -0.2, 0.3, 0.6])
T = np.array([0.5, 2.0, -1.0])
BATCH = np.stack([Q + 0.03 * k for k in range(4)])
DBATCH = np.stack([DQ - 0.05 * k for k in range(4)])
TBATCH = np.stack([T * (1 - 0.2 * k) for k in range(4)])


def _kkt(model, q, dq, torques, a1=0.0, a2=0.0):
    """[M D^T; D 0][ddq; lambda] = [F + S T; -dD dq - 2 a1 D dq - a2^2 C], assembled from the
    model's public terms and solved by numpy (docs/model.md's sign conventions; C's rows are
    rD_z and the contact velocities, its rate D dq)."""
    M, D = model.mass_matrix(q), model.constraint_jacobian(q)
    K = np.zeros((13, 13))
    K[:8, :8], K[:8, 8:], K[8:, :8] = M, D.T, D
    rhs = np.concatenate([model.generalized_forces(q, dq, torques),
                          -model.constraint_bias(q, dq) - 2 * a1 * D @ dq
                          - a2 ** 2 * model.constraint_residual(q, dq)])
    x = np.linalg.solve(K, rhs)
    return x[:8], x[8:]


@pytest.mark.parametrize("which", ["thesis", "disc"])
@pytest.mark.parametrize("gains", [(0.0, 0.0), (3.0, 7.0)])
def test_forward_solves_the_kkt_system_of_the_public_terms(request, which, gains):
    """The C solve against numpy's solve of the KKT system built from M, D, the forces, dD dq
    and C, one state and a batch (each row its own state and torques), with and without
    Baumgarte gains. The multipliers are compared too: they carry the sign of D^T lambda.
    Planted (seen failing; other tests kill them too): the fast path's multipliers read at
    9 N_Q instead of 8 N_Q, a2 passed as None."""
    model = request.getfixturevalue(which)
    res = model.forward(Q, DQ, T, baumgarte=gains)
    ddq, lam = _kkt(model, Q, DQ, T, *gains)
    assert_round_off(res.ddq, ddq)
    assert_round_off(res.lam, lam)
    assert res.status.tolist() == [0]
    rows = model.forward(BATCH, DBATCH, TBATCH, baumgarte=gains)
    assert rows.ddq.shape == (4, 8) and rows.lam.shape == (4, 5) and rows.status.tolist() == [0] * 4
    for k in range(4):
        ddq, lam = _kkt(model, BATCH[k], DBATCH[k], TBATCH[k], *gains)
        assert_round_off(rows.ddq[k], ddq)
        assert_round_off(rows.lam[k], lam)


def test_the_13x13_system_satisfies_the_equations_of_motion_and_the_constraints(disc):
    """inverse_dynamics_step's accelerations, torques and multipliers put back into the
    thesis's equations: M ddq + D^T lambda = F + S T and D ddq + dD dq = 0, one state and
    a batch row by row. Planted (seen failing; other tests kill them too): the dependent
    accelerations read as out[:, :6], the torques as out[:, 6:8], the multipliers as
    out[:, 9:13]."""
    ind = np.array([[0.3, -0.5, 0.2], [-1.0, 0.1, 0.4], [0.0, 2.0, -0.3], [0.5, 0.5, 0.5]])
    for q, dq, a in ((Q, DQ, ind[0]), *zip(BATCH, DBATCH, ind)):
        ddq, torques, lam, status = disc.inverse_dynamics_step(q, dq, a)
        M, D = disc.mass_matrix(q), disc.constraint_jacobian(q)
        assert_round_off(M @ ddq + D.T @ lam, disc.generalized_forces(q, dq, torques))
        assert_round_off(D @ ddq, -disc.constraint_bias(q, dq))
        assert status.tolist() == [0]
    ddq, torques, lam, status = disc.inverse_dynamics_step(BATCH, DBATCH, ind)
    assert status.tolist() == [0] * 4
    one = disc.inverse_dynamics_step(BATCH[2], DBATCH[2], ind[2])
    for got, want in zip((ddq[2], torques[2], lam[2]), one[:3]):
        assert_round_off(got, want)


def test_exact_fractions_give_the_float_results(thesis):
    """Fractions (exact rationals, e.g. from a symbolic caller) are read as the floats they
    round to: the same float64 numbers as the float input, not an object array. Planted: the
    float64 dtype dropped from inverse_dynamics's ddq (M @ an object array of Fractions gives
    an object array)."""
    ddq = np.linspace(-1.0, 1.0, 8)
    fr = [Fraction(x).limit_denominator(1000) for x in ddq]
    want = thesis.inverse_dynamics(Q, DQ, [float(x) for x in fr])
    got = thesis.inverse_dynamics(Q, DQ, fr)
    assert got.dtype == np.float64
    np.testing.assert_array_equal(got, want)
    got = thesis.inverse_dynamics(BATCH, DBATCH, [fr] * 4)
    assert got.dtype == np.float64 and got.shape == (4, 8)
    qf = [Fraction(x).limit_denominator(1000) for x in Q]
    dqf = [Fraction(x).limit_denominator(1000) for x in DQ]
    res = thesis.forward(qf, dqf, [Fraction(1, 2), Fraction(2), Fraction(-1)])
    want = thesis.forward([float(x) for x in qf], [float(x) for x in dqf], T)
    assert res.ddq.dtype == np.float64
    np.testing.assert_array_equal(res.ddq, want.ddq)
    np.testing.assert_array_equal(thesis.Qv(qf, dqf), thesis.Qv([float(x) for x in qf],
                                                                 [float(x) for x in dqf]))


def test_a_single_state_takes_the_fast_path(thesis, monkeypatch):
    """One state (8,) on the C backend is evaluated through the preallocated buffers, never
    through the batch conversion (`_states`, ~1 us of numpy per call: more than the C work;
    the integrators call forward once per stage). Its numbers are the batch loop's. Planted:
    the fast path's backend test "C" or "XXcXX", np.ndim / np.shape of None in its shape
    tests, `and` for `or` in _eval's dq test (each leaves every single state to the slow
    path)."""
    assert thesis.backend == "c"
    slow = (thesis.mass_matrix(Q[None])[0], thesis.Qv(Q[None], DQ[None])[0],
            thesis.potential_energy(Q[None])[0], thesis.forward(Q[None], DQ[None], T))

    def refused(*args, **kwargs):
        raise AssertionError("a single state went through the batch conversion")

    monkeypatch.setattr(model_module, "_states", refused)
    np.testing.assert_array_equal(thesis.mass_matrix(Q), slow[0])
    np.testing.assert_array_equal(thesis.Qv(Q, DQ), slow[1])
    assert thesis.potential_energy(Q) == slow[2]
    fast = thesis.forward(Q, DQ, T)
    np.testing.assert_array_equal(fast.ddq, slow[3].ddq[0])
    np.testing.assert_array_equal(fast.lam, slow[3].lam[0])
    # a batch does go through it
    with pytest.raises(AssertionError, match="batch conversion"):
        thesis.mass_matrix(BATCH)


@pytest.mark.parametrize("status, message", [
    ([0, 0, 7, 1], "solve: state 2 (2 state(s) in all): unknown failure"),
    ([0, 1], "solve: state 1 (1 state(s) in all): the linear system is singular (constraint "
             "Jacobian rank-deficient or M not positive definite): the state is at a kinematic "
             "singularity"),
    ([2, 2, 0], "solve: state 0 (2 state(s) in all): the state or the result is not finite "
                "(NaN or inf in the input?)"),
])
def test_each_status_code_has_its_message_and_an_unknown_one_says_so(status, message):
    """The user-facing text of a failed solve: the first bad state, how many, and what the
    code means; a code the model does not define (a newer kernel's) is an 'unknown failure',
    never a blank. Planted: the unknown code's text dropped (None), upper-cased or XX-wrapped."""
    with pytest.raises(ModelEvaluationError) as info:
        raise_on_status(np.array(status, dtype=np.intc), "solve")
    assert str(info.value) == message
    raise_on_status(np.zeros(3, dtype=np.intc), "solve")     # all ok: no error


def test_coordinate_indices_are_the_thesis_order_and_read_only():
    """Positions in the thesis order (xc, yc, phi, theta, psi, beta, gamma, eps), written out
    by hand, of a read-only array. Planted: idx None, np.array(None), index(None), rindex,
    writeable True."""
    ind = _index(("theta", "psi", "gamma"))
    np.testing.assert_array_equal(ind, [3, 4, 6])
    np.testing.assert_array_equal(_index(("xc", "yc", "phi", "beta", "eps")), [0, 1, 2, 5, 7])
    np.testing.assert_array_equal(_index(("eps", "xc")), [7, 0])
    with pytest.raises(ValueError):
        ind[0] = 0


def test_the_repr_names_the_parameters_and_only_the_non_default_variant(thesis):
    """The thesis model shows name, contact and source; gyroscopic=False and a numpy backend
    are shown only when chosen, in that order. Planted: variant None, either condition
    forced or inverted, its text XX-wrapped or re-cased, `=` or `-=` for `+=`."""
    src = repr(thesis.params.source)
    head = f"Model(name='thesis', contact='thesis', source={src}"
    assert repr(thesis) == head + ")"
    assert repr(Model(thesis.params, gyroscopic=False)) == head + ", gyroscopic=False)"
    assert repr(Model(thesis.params, backend="numpy")) == head + ", backend='numpy')"
    both = Model(thesis.params, gyroscopic=False, backend="numpy")
    assert repr(both) == head + ", gyroscopic=False, backend='numpy')"


def test_eigenvalues_are_meijaards_table_2():
    """The benchmark bicycle's four roll/steer eigenvalues against Meijaard et al. (2007)
    Table 2 (14 digits), one speed (4,) and several (n, 4). Planted: the model or the speed
    passed as None or dropped."""
    bench = load_model("benchmark")
    lam = bench.eigenvalues(5.0)
    assert lam.shape == (4,)
    np.testing.assert_allclose(lam, table2_eigenvalues(5), rtol=0, atol=1e-10)
    lam = bench.eigenvalues(np.array([2.0, 8.0]))
    assert lam.shape == (2, 4)
    np.testing.assert_allclose(lam, [table2_eigenvalues(2), table2_eigenvalues(8)], rtol=0,
                               atol=1e-10)
