"""comparisons/judgments/term_checks.py, the parts tests/test_term_checks.py leaves open:
what the terms become when an engine computes in another float precision, which calls
`engine_terms` makes, the constrained solve on one state and on a grid of states, and how
`check_block` names entries at its boundaries (ties, an entry exactly at the tolerance, a
mirror whose error is the same to the relative 1e-9 the module allows).

Expected values: the reference model's own methods (called directly), docs/engines.md's
engine contract ("Return numpy float arrays", the documented calls of `engine_terms`), a
2-coordinate constrained solve worked out by hand, and blocks whose errors are placed by hand
at exactly representable values. Each test names the planted bugs (mutmut's survivors of the
module's measurement) it was seen failing on. ~0.3 s."""

import numpy as np
import pytest

from comparisons.judgments.term_checks import (Block, check_block, engine_terms, extract,
                                               model_terms, solve_values)
from comparisons.judgments.terms import random_states
from engines import Engine

STATES = random_states(3, seed=11)


def _close(a, b):
    # round-off of the interface's differences (F(q, dq) - F(q, 0)), as in test_term_checks
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * max(1.0, np.abs(b).max()))


class LongDouble(Engine):
    """The reference model behind every term method, answering in numpy's extended precision
    (np.longdouble): 'numpy float arrays' as docs/engines.md asks, just not float64."""

    name = "long-double"
    capabilities = frozenset({"mass_matrix", "inverse_dynamics", "gravity", "generalized_forces",
                              "constraint_jacobian", "constraint_bias", "forward_acceleration"})

    def _ld(self, a):
        return np.asarray(a, dtype=np.longdouble)

    def mass_matrix(self, q):
        return self._ld(self.model.mass_matrix(q))

    def inverse_dynamics(self, q, dq, ddq):
        return self._ld(self.model.inverse_dynamics(q, dq, ddq))

    def gravity(self, q):
        return self._ld(self.model.Qgrav(q))

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._ld(self.model.generalized_forces(q, dq, torques))

    def constraint_jacobian(self, q):
        return self._ld(self.model.constraint_jacobian(q))

    def constraint_bias(self, q, dq):
        return self._ld(self.model.constraint_bias(q, dq))

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._ld(self.model.forward_acceleration(q, dq, torques))


def test_a_long_double_engine_is_taken_in_float64_and_its_solve_is_checked(thesis):
    """An engine answering in np.longdouble: every term the module converts, every copy and
    the solve's arrays come out float64 with the model's values (numpy's linalg has no long
    double, so without the conversion the forward-solve check cannot run at all).
    Planted: dtype=float dropped (or None) on mass_matrix, gravity, F at rest, F(q, +dq),
    F(q, -dq), -inverse_dynamics, ID at rest and ID's columns, D, dD dq, the solve's F and
    the engine's forward accelerations."""
    s = STATES
    terms, copies, solve = extract(LongDouble(thesis), s, extras=True)
    want = model_terms(thesis, s)
    # S is left out of the dtype check: its columns are differences of F taken without the
    # conversion (line 93), so a long-double engine's S stays long double (reported)
    for name in ("M", "Qv", "Qgrav", "Qaero", "D", "dD dq"):
        assert terms[name].dtype == np.float64, name
        _close(terms[name], want[name])
    _close(np.asarray(terms["S"], dtype=float), want["S"])
    assert sorted(copies) == ["M", "Qgrav", "Qv"]
    for name, copy in copies.items():
        assert copy.dtype == np.float64, name
        _close(copy, want[name])
    ddq = thesis.forward_acceleration(s.q, s.dq, s.T)
    for field in ("ddq", "own", "unconstrained", "bias_flipped"):
        assert getattr(solve, field).dtype == np.float64, field
    _close(solve.ddq, ddq)
    _close(solve.own, ddq)


class Counting(LongDouble):
    """Counts the calls of each method; its forward accelerations are never wanted by
    engine_terms."""

    name = "counting"

    def __init__(self, model):
        super().__init__(model)
        self.calls = {}

    def __getattribute__(self, attr):
        if attr in Engine.__dict__ and attr in object.__getattribute__(self, "capabilities"):
            calls = object.__getattribute__(self, "calls")
            calls[attr] = calls.get(attr, 0) + 1
        return object.__getattribute__(self, attr)


def test_engine_terms_makes_only_the_calls_its_docstring_names(thesis):
    """engine_terms: M from mass_matrix, Qgrav from gravity, Qv from one inverse_dynamics
    call, Qaero and S from F at rest, at +-dq and at the three unit torques (6 calls), D and
    dD dq once each; never forward_acceleration (no solve) nor the 1 + 8 inverse_dynamics
    calls of M's copy. Planted: engine_terms passing extras=True."""
    e = Counting(thesis)
    terms = engine_terms(e, STATES)
    assert list(terms) == ["M", "Qv", "Qgrav", "Qaero", "S", "D", "dD dq"]
    assert e.calls == {"mass_matrix": 1, "gravity": 1, "inverse_dynamics": 1,
                       "generalized_forces": 6, "constraint_jacobian": 1, "constraint_bias": 1}


def _by_hand(b):
    """M = I (2x2), one constraint x1 + x2 with bias b, F = (1, 0): x1 + lambda = 1,
    x2 + lambda = 0, x1 + x2 = -b -> x = ((1 - b)/2, -(1 + b)/2); with +b: ((1 + b)/2,
    -(1 - b)/2)."""
    return [(1 - b) / 2, -(1 + b) / 2], [(1 + b) / 2, -(1 - b) / 2]


def test_the_solve_of_one_state_and_of_a_grid_of_states_by_hand():
    """solve_values takes numpy's stacked-matrix shapes: one state (no batch axis) and a
    (2, 3) grid of states with a different bias in each, each the hand solution.
    Planted: the right-hand side concatenated on axis +1 (fails without a batch axis); n read
    from M.shape[+1] (a batch size, not the coordinate count, once the batch has two axes)."""
    own, flipped = _by_hand(0.5)
    sv = solve_values(np.zeros(2), np.eye(2), np.array([1.0, 0.0]), np.array([[1.0, 1.0]]),
                      np.array([0.5]))
    np.testing.assert_allclose(sv.own, own, rtol=0, atol=1e-15)
    np.testing.assert_allclose(sv.bias_flipped, flipped, rtol=0, atol=1e-15)
    np.testing.assert_allclose(sv.unconstrained, [1.0, 0.0], rtol=0, atol=0)
    b = np.array([[0.0, 0.5, 1.0], [-1.0, 2.0, 0.25]])
    M = np.broadcast_to(np.eye(2), (2, 3, 2, 2))
    D = np.broadcast_to(np.array([[1.0, 1.0]]), (2, 3, 1, 2))
    F = np.broadcast_to(np.array([1.0, 0.0]), (2, 3, 2))
    sv = solve_values(np.zeros((2, 3, 2)), M, F, D, b[..., None])
    assert sv.own.shape == sv.bias_flipped.shape == sv.unconstrained.shape == (2, 3, 2)
    for i in range(2):
        for j in range(3):
            own, flipped = _by_hand(b[i, j])
            np.testing.assert_allclose(sv.own[i, j], own, rtol=0, atol=1e-15)
            np.testing.assert_allclose(sv.bias_flipped[i, j], flipped, rtol=0, atol=1e-15)


def test_tied_errors_name_the_upper_entries_first():
    """Equal errors are named in row-major order (the upper entry first): a D row off by the
    same amount in every column names its first three columns, a D column off in every row
    its first three rows. Planted: np.argsort without kind='stable' (numpy's default sort
    reorders ties in arrays this size)."""
    D = np.zeros((1, 5, 8))
    row = D.copy()
    row[0, 1, :] = 2e-6                       # the whole vC_x row
    c = check_block(Block("e", "D", "", row, D, np.ones(1), 1e-6))
    assert c.entries == ("D[vC_x, xc]", "D[vC_x, yc]", "D[vC_x, phi]")
    col = D.copy()
    col[0, :, 6] = 2e-6                       # the whole gamma column
    c = check_block(Block("e", "D", "", col, D, np.ones(1), 1e-6))
    assert c.entries == ("D[rD_z, gamma]", "D[vC_x, gamma]", "D[vC_y, gamma]")


def test_an_entry_exactly_at_the_tolerance_is_not_named_after_the_worst():
    """Entries are named while above the tolerance: one at exactly the tolerance (0.5 here,
    error 0.5 at scale 1, exact in binary) is not named after the worst (1.5), one just
    above it (0.625) is. Planted: '<' for '<=' in the stop (the entry at tolerance named)."""
    ref = np.zeros((1, 8))
    value = ref.copy()
    value[0, 3] = 1.5
    value[0, 5] = 0.5
    c = check_block(Block("e", "Qv", "", value, ref, np.ones(1), 0.5))
    assert c.entries == ("Qv[theta]",) and c.passed is False
    value[0, 5] = 0.625
    c = check_block(Block("e", "Qv", "", value, ref, np.ones(1), 0.5))
    assert c.entries == ("Qv[theta]", "Qv[beta]")


def test_a_mirror_differing_by_exactly_1e9_of_its_error_is_the_same_error():
    """M's mirror is 'the same error' up to 1e-9 of it, boundary included: x = 1e9 * 2^-30
    and its mirror x + 2^-30 (1e-9 x is exactly 2^-30 in binary) are named once; a mirror
    2^-29 away (2e-9 of x) is named too. Planted: '<' for '<=' in the mirror's comparison."""
    x = 1e9 * 2.0 ** -30
    assert 1e-9 * x == 2.0 ** -30                # the boundary is hit exactly
    M = np.zeros((1, 8, 8))
    value = M.copy()
    value[0, 3, 6] = x + 2.0 ** -30          # M[theta, gamma], the worse: named first
    value[0, 6, 3] = x                       # its mirror, at the boundary: not named again
    value[0, 0, 0] = 0.5                     # a third entry above tolerance
    c = check_block(Block("e", "M", "", value, M, np.ones(1), 1e-6))
    assert c.entries == ("M[theta, gamma]", "M[xc, xc]")
    value[0, 3, 6] = x + 2.0 ** -29
    c = check_block(Block("e", "M", "", value, M, np.ones(1), 1e-6))
    assert c.entries == ("M[theta, gamma]", "M[gamma, theta]", "M[xc, xc]")
