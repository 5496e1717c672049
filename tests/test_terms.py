"""comparisons/terms.py on a planted difference: what a TermComparison reports.

The second engine is the reference with one entry of one quantity changed at one state by a
known amount, so every field of the comparison (normalised and absolute error, worst state and
entry, pass/fail against the tolerance) is known from the plant, not from the code.
"""

import numpy as np
import pytest

from comparisons.judgments.terms import QUANTITIES, States, compare_term, compare_terms, random_states
from comparisons.judgments.tolerances import Tolerance, load_tolerances
from engines import load_engine
from engines.reference import ReferenceEngine

STATES = random_states(5, seed=3)
TOLS = load_tolerances()


class Planted(ReferenceEngine):
    """The reference, with ``delta`` added to entry ``index`` of ``quantity`` at state ``k``."""

    name = "planted"

    def __init__(self, model, quantity, k, index, delta):
        super().__init__(model)
        self.plant = (quantity, k, index, delta)

    def _changed(self, quantity, out):
        q, k, index, delta = self.plant
        out = np.array(out, dtype=float)
        if q == quantity:
            out[(k,) + index] += delta
        return out

    def mass_matrix(self, q):
        return self._changed("mass_matrix", super().mass_matrix(q))

    def gravity(self, q):
        return self._changed("gravity", super().gravity(q))

    def constraint_jacobian(self, q):
        return self._changed("constraint_jacobian", super().constraint_jacobian(q))

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._changed("generalized_forces", super().generalized_forces(q, dq, torques))


def test_mass_matrix_difference_is_measured_and_named(thesis):
    ref = load_engine("reference", thesis)
    delta = 3e-9
    res = compare_term("mass_matrix", ref, Planted(thesis, "mass_matrix", 2, (3, 6), delta),
                       STATES, TOLS["mass_matrix"])
    M = thesis.mass_matrix(STATES.q[2])
    assert res.quantity == "mass_matrix" and res.engines == ("reference", "planted")
    assert res.max_abs_error == pytest.approx(delta, rel=1e-6)
    # max_abs scale: relative to max|M| at that state
    assert res.max_error == pytest.approx(delta / np.abs(M).max(), rel=1e-6)
    assert res.worst_state == 2 and res.worst_entry == "M[theta, gamma]"
    assert res.n_states == 5 and res.tolerance == TOLS["mass_matrix"].tolerance
    assert res.passed is False
    assert "DIFFERS" in res.describe() and "M[theta, gamma]" in res.describe()


def test_the_largest_of_several_differences_is_reported(thesis):
    """Two states differ; the one with the larger normalised error is named."""
    ref = load_engine("reference", thesis)

    class Two(Planted):
        def gravity(self, q):
            out = np.array(super().gravity(q))
            out[4, 5] += 1e-6     # beta at state 4, smaller than the plant at state 1
            return out

    res = compare_term("gravity", ref, Two(thesis, "gravity", 1, (3,), 1e-3), STATES,
                       TOLS["gravity"])
    assert res.worst_state == 1 and res.worst_entry == "Qgrav[theta]"
    assert res.max_abs_error == pytest.approx(1e-3, rel=1e-6)


def test_a_difference_within_the_tolerance_passes(thesis):
    ref = load_engine("reference", thesis)
    tol = Tolerance("constraint_jacobian", 1e-6, "absolute", "test")
    res = compare_term("constraint_jacobian", ref,
                       Planted(thesis, "constraint_jacobian", 0, (4, 2), 5e-7), STATES, tol)
    assert res.passed is True and res.max_error == pytest.approx(5e-7, rel=1e-6)
    assert res.worst_entry == "D[vD_y, phi]" and res.tolerance == 1e-6
    # and at the tolerance exactly it still passes (error <= tolerance)
    exact = Tolerance("constraint_jacobian", res.max_error, "absolute", "test")
    assert compare_term("constraint_jacobian", ref,
                        Planted(thesis, "constraint_jacobian", 0, (4, 2), 5e-7),
                        STATES, exact).passed


def test_largest_term_scale_uses_the_parts_of_the_sum(thesis):
    """generalized_forces is judged relative to the largest of Qv, Qgrav, Qaero, S T."""
    ref = load_engine("reference", thesis)
    res = compare_term("generalized_forces", ref,
                       Planted(thesis, "generalized_forces", 0, (6,), 1e-4), STATES,
                       TOLS["generalized_forces"])
    q, dq, T = STATES.q[0], STATES.dq[0], STATES.T[0]
    parts = [thesis.Qv(q, dq), thesis.Qgrav(q), thesis.Qaero(q, dq), thesis.S(q) @ T]
    scale = max(1.0, max(np.abs(p).max() for p in parts))
    assert res.max_error == pytest.approx(1e-4 / scale, rel=1e-6)
    assert res.worst_entry == "Qv[gamma]"   # generalized forces are printed as Qv entries


def test_non_finite_output_is_an_infinite_error(thesis):
    ref = load_engine("reference", thesis)
    res = compare_term("mass_matrix", ref, Planted(thesis, "mass_matrix", 4, (0, 0), np.nan),
                       STATES, TOLS["mass_matrix"])
    assert res.max_error == np.inf and res.passed is False and res.worst_state == 4


def test_compare_terms_covers_what_both_provide(thesis):
    ref = load_engine("reference", thesis)
    results = compare_terms(ref, ref, STATES, TOLS)
    assert [r.quantity for r in results] == list(QUANTITIES)
    assert all(r.passed and r.max_error == 0.0 for r in results)
    only = compare_terms(ref, ref, STATES, TOLS, quantities=["gravity", "mass_matrix"])
    assert [r.quantity for r in only] == ["gravity", "mass_matrix"]


def test_random_states_are_deterministic_and_in_range():
    a, b = random_states(50, seed=9), random_states(50, seed=9)
    for name in ("q", "dq", "ddq", "T"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert isinstance(a, States) and len(a) == 50
    assert a.q.shape == (50, 8) and a.T.shape == (50, 3)
    assert np.abs(a.q[:, 3]).max() <= 1.2 and np.abs(a.q[:, 6]).max() <= 1.55
    assert np.abs(a.dq).max() <= 20 and np.abs(a.T).max() <= 10
    assert not np.array_equal(random_states(50, seed=10).q, a.q)


def test_compare_terms_skips_what_one_engine_lacks(thesis):
    """An engine providing only M (like Exudyn's tree) is compared on M alone, not asked for
    the rest (which would raise CapabilityError)."""
    from engines import Engine

    class OnlyM(Engine):
        name = "only-m"
        capabilities = frozenset({"mass_matrix"})

        def mass_matrix(self, q):
            return self.model.mass_matrix(q)

    results = compare_terms(load_engine("reference", thesis), OnlyM(thesis), STATES, TOLS)
    assert [r.quantity for r in results] == ["mass_matrix"] and results[0].passed
