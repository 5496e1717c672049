"""compare_term (comparisons/judgments/terms.py), the part tests/test_terms.py leaves open: the
terms of an engine that does not answer in float64. docs/engines.md asks for "numpy float
arrays" and the engine boundary (engines/guard.py, applied by `load_engine`) takes any real
array, an integer or float32 one, a list of lists or numpy's long double, as its float64 values;
compare_term, called with an engine that is not behind the guard (a test's fake, a user's
script), must judge the same float64 values, on either side of the comparison.

Expected values: integer tables compared by hand (|difference| and max|entry| of the state),
and the same comparison made with the engine behind the guard. Each test names the planted
bugs (mutmut's survivors of the module's measurement) it was seen failing on. 8 cases, ~0.05 s."""

import numpy as np
import pytest

from comparisons.judgments.terms import States, compare_term
from comparisons.judgments.tolerances import Tolerance
from engines import Engine
from engines.guard import guard

N = 3
STATES = States(np.zeros((N, 8)), np.zeros((N, 8)), np.zeros((N, 8)), np.zeros((N, 3)))
TOL = Tolerance("gravity", 1e-12, "max_abs", "by hand: relative to max|Qgrav| of the state")

# Qgrav at three states, integers: exact in int64, float32, float64 and long double
G = np.array([[0, 0, 0, 12, 0, -3, 1, 0],
              [0, 0, 0, -6, 0, 2, -1, 0],
              [0, 0, 0, 4, 0, -3, 2, 0]])
# the long-double table carries 2^-60 more at state 2, beta: -3 + 2^-60 needs 62 bits of
# mantissa (x86's long double has 64), float64's spacing at 3 is 2^-51, so in float64 it is -3
TINY = np.longdouble(2.0) ** -60
LONG = G.astype(np.longdouble)
LONG[2, 5] += TINY

FORMS = {
    "int64": lambda: G.astype(np.int64),
    "float32": lambda: G.astype(np.float32),
    "list of lists": lambda: G.tolist(),
    "long double": lambda: LONG.copy(),
}


class Table(Engine):
    """A fake engine whose gravity is a fixed table (one row per state), handed back as
    ``answer()`` returns it; no model behind it (compare_term reads none for gravity)."""

    capabilities = frozenset({"gravity"})

    def __init__(self, name, answer):
        super().__init__(model=None)
        self.name, self._answer = name, answer

    def gravity(self, q):
        assert np.shape(q) == (N, 8)
        return self._answer()


@pytest.mark.parametrize("side", ["a", "b"])
@pytest.mark.parametrize("form", list(FORMS))
def test_an_engine_answering_in_another_form_is_judged_on_its_float64_values(form, side):
    """One engine answers in ``form`` (int64, float32, a list of lists, long double), the other
    in float64, as engine a (the reference side) or b. Identical values in float64 are judged
    identical: no difference (0 absolute, 0 relative), passed. A planted 0.5 at state 1, beta
    (2 -> 2.5) is found there: |diff| 0.5, relative 0.5 / max|Qgrav| of state 1 = 0.5 / 6,
    failing 1e-12. Both comparisons are the ones made with the same engine behind the guard
    (load_engine's boundary, which takes any real array as float64). Planted: dtype=float
    dropped from (or None in) the conversion of A (the long-double engine as a: the 2^-60 of
    state 2 seen as a difference, worst state 2, |diff| 8.7e-19) and of B (the same as b)."""
    if form == "long double":   # the premise: the integers in float64, and (where long double
        # is wider than float64, as on x86) not the integers before the conversion
        assert np.array_equal(np.asarray(LONG, dtype=float), G)
        if np.finfo(np.longdouble).nmant > 52:
            assert [tuple(i) for i in np.argwhere(LONG != G)] == [(2, 5)]

    def pair(raw_or_guarded, other):
        e = raw_or_guarded(Table(form, FORMS[form]))
        f = Table("float64", lambda: other.astype(np.float64))
        return (e, f) if side == "a" else (f, e)

    same = compare_term("gravity", *pair(lambda e: e, G), STATES, TOL)
    assert (same.max_abs_error, same.max_error, same.passed, same.n_states) == (0.0, 0.0, True, N)
    assert same.engines == ((form, "float64") if side == "a" else ("float64", form))
    assert same == compare_term("gravity", *pair(guard, G), STATES, TOL)

    plant = G.astype(np.float64)
    plant[1, 5] = 2.5
    got = compare_term("gravity", *pair(lambda e: e, plant), STATES, TOL)
    assert got.max_abs_error == 0.5 and got.max_error == pytest.approx(0.5 / 6, rel=1e-15)
    assert (got.worst_state, got.worst_entry, got.passed) == (1, "Qgrav[beta]", False)
    assert got == compare_term("gravity", *pair(guard, plant), STATES, TOL)



def test_no_states_is_refused_not_passed():
    """With no states nothing is compared: a pass would report the search's starting value
    (-1) as the largest error, and the mass matrix's entry name had no index to read (an
    IndexError). The comparison refuses in one line naming the quantity. Found here, fixed."""
    empty = States(np.zeros((0, 8)), np.zeros((0, 8)), np.zeros((0, 8)), np.zeros((0, 3)))
    engine = Table("a", lambda: np.zeros((0, 8)))
    for quantity in ("gravity", "mass_matrix"):
        with pytest.raises(ValueError, match=f"^no states to compare {quantity} at: give at "
                                              "least one$"):
            compare_term(quantity, engine, engine, empty, TOL)
