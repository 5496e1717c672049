"""`engines.linear.critical_speeds` held to the part of its definition that
tests/test_engine_eigenvalues.py leaves open: the weave speed is where the first complex
pair's real part crosses from + to -, and where all four eigenvalues are real there is no such
pair, so no real part to find a root of (`reference_model.linearize._weave_real`, whose
definitions it follows: NaN there). Eigenvalues here are those of a hand-made system known in
closed form: a damped oscillator x'' + c x' + k x = 0 (roots (-c +- sqrt(c^2 - 4 k)) / 2) with
c = v - 1.25 and k = (v - 1.25)^2 + k0, beside two fixed real roots -3 and -4 (1/s). Each test
names the planted bugs (mutmut's survivors of the module's measurement) it was seen failing on.
~0.05 s.
"""

from __future__ import annotations

import numpy as np
import pytest

from engines.linear import critical_speeds
from reference_model.linearize import sort_eigenvalues


def _oscillator(k0: float):
    """Eigenvalues (n, 4) at speeds v of the block system [[0, 1], [-k, -c]] (+) diag(-3, -4),
    sorted as `sort_eigenvalues` (numpy's eigenvalues of the real matrix)."""
    def eigenvalues(v):
        out = []
        for s in np.atleast_1d(np.asarray(v, dtype=float)):
            c, k = s - 1.25, (s - 1.25) ** 2 + k0
            A = np.diag([0.0, 0.0, -3.0, -4.0])
            A[0, 1], A[1, 0], A[1, 1] = 1.0, -k, -c
            out.append(np.linalg.eigvals(A))
        return sort_eigenvalues(np.array(out))
    return eigenvalues


def test_a_pair_that_stays_oscillatory_has_its_weave_where_the_damping_vanishes():
    """k0 = 0.01: c^2 - 4 k = -3 (v - 1.25)^2 - 0.04 < 0 at every speed, so the pair stays
    complex with real part -c / 2 = (1.25 - v) / 2: the weave speed is 1.25 m/s exactly
    (bracketed by the grid's 1.0 and 1.5), and det = 12 k > 0 everywhere: no capsize. The
    control for the test below (the same search with the pair intact)."""
    weave, capsize = critical_speeds(_oscillator(0.01), (0.0, 3.0))
    assert weave == pytest.approx(1.25, abs=1e-10)
    assert capsize is None


def test_a_pair_turned_real_inside_the_bracket_has_no_weave_real_part():
    """k0 = -0.01: the grid's 1.0 and 1.5 m/s hold the pair (real parts +0.125 and -0.125, a
    + to - bracket), but for |v - 1.25| < 0.2 / sqrt(3) it is two real roots (at 1.25: +-0.1,
    with -3 and -4: all four real), where the pair has no real part. brentq's first step lands
    on 1.25, finds no real part (NaN) and stops: a ValueError naming the NaN, not a speed.
    (What such a bicycle's weave speed should be is open, issue 24's notes; none of the
    measured bicycles has a bracket like it. What this test holds is that no wrong speed is
    reported.)
    Reading the largest real root there instead would report 1.35 m/s, where that real root
    crosses zero (k = 0: a capsize-like crossing, not a weave) as the weave speed.
    Planted: the complex test made always true (1.35 returned as the weave speed); the NaN
    written float(None) (a TypeError instead of the solver's refusal)."""
    lam = _oscillator(-0.01)
    at = lam(np.array([1.0, 1.25, 1.5]))
    assert np.all(at[[0, 2], 0].imag != 0) and np.all(at[1].imag == 0)   # the premise
    with pytest.raises(ValueError, match=r"The function value at x=1\.25 is NaN"):
        critical_speeds(lam, (0.0, 3.0))
