"""comparisons/judgments/meijaard.py, the parts tests/test_linear_closed_form.py leaves open:
the closed form on Table 1 values of other number types (exact fractions; speeds as unsigned
integers) and on mass splits where a wrongly signed total mass would vanish, the critical
speeds of a bicycle whose capsize crossing runs from - to + and of one whose weave pair splits
into real eigenvalues a quarter m/s after turning stable, and the root bracketing at its
boundaries (a zero on the grid's first point, a crossing onto exactly 1, a triple root that
brentq needs over 100 iterations for, no warnings).

Expected values: Meijaard et al. (2007)'s printed M, C1, K0, K2 and Table 2 eigenvalues
(comparisons/judgments/published.py), the paper's formulas rewritten by hand without the
total mass (mT xT = sum m x, mT zT = sum m z), the capsize speed of a vertical steer axis in
closed form (det K = 0: v^2 = g w SA / ST), eigenvalues of the state matrix built here with
numpy, and functions whose roots are known exactly. Each test names the planted bugs
(mutmut's survivors of the module's measurement) it was seen failing on. ~0.3 s."""

from __future__ import annotations

import math
import warnings
from fractions import Fraction

import numpy as np
import pytest

from comparisons.judgments.meijaard import (MATRICES, _first_root, _grid, closed_form,
                                            closed_form_critical_speeds,
                                            closed_form_eigenvalues)
from comparisons.judgments.published import (MEIJAARD_CAPSIZE_SPEED, MEIJAARD_MATRICES,
                                             MEIJAARD_WEAVE_SPEED, table2_eigenvalues)
from reference_model.benchmark import TABLE1

B = TABLE1.as_dict()
#: the printed matrices carry 14 decimals (rounding 5e-15, entries up to 81: a few ulps)
TOL_PRINTED = 1e-13
#: Table 2 is good to ~1e-12 (tolerances.toml's [benchmark_eigenvalues] reason: its v = 7
#: castor value is 8.5e-13 from the paper's own matrices)
TOL_TABLE2 = 1e-12
TOL_SPEED = 1e-9


def _state(cf, v):
    """d/dt [q, q'] = A [q, q'] from M q'' + v C1 q' + (g K0 + v^2 K2) q = 0, built here."""
    Minv = np.linalg.inv(cf.M)
    return np.block([[np.zeros((2, 2)), np.eye(2)],
                     [-Minv @ (cf.g * cf.K0 + v * v * cf.K2), -v * Minv @ cf.C1]])


def test_exact_fraction_table1_values_give_the_printed_float64_matrices():
    """Table 1 given as exact fractions (as a parser keeping decimals exactly may give them):
    the matrices are float64 and the printed ones, and the eigenvalues at 5 m/s Table 2's.
    Planted: _frozen without dtype=np.float64 (an object array of Fractions and floats, which
    numpy's linalg refuses)."""
    cf = closed_form({k: Fraction(repr(v)) for k, v in B.items()})
    for key in MATRICES:
        m = getattr(cf, key)
        assert m.dtype == np.float64, key
        np.testing.assert_allclose(m, MEIJAARD_MATRICES[key], rtol=0, atol=TOL_PRINTED,
                                   err_msg=key)
    got = np.sort_complex(closed_form_eigenvalues(cf, 5.0))
    np.testing.assert_allclose(got, np.sort_complex(table2_eigenvalues(5)), rtol=0,
                               atol=TOL_TABLE2)


def test_table2s_integer_speeds_as_unsigned_integers_give_table2():
    """Table 2's speeds 0..10 m/s passed as an unsigned-integer array give Table 2's
    eigenvalues at each. Planted: the speeds kept in their own dtype (dtype=np.float64
    dropped): -v wraps around in unsigned arithmetic."""
    cf = closed_form(B)
    lam = closed_form_eigenvalues(cf, np.arange(11, dtype=np.uint8))
    assert lam.shape == (11, 4)
    for v in range(11):
        np.testing.assert_allclose(np.sort_complex(lam[v]), np.sort_complex(table2_eigenvalues(v)),
                                   rtol=0, atol=TOL_TABLE2, err_msg=f"v = {v}")


def _k0_by_hand(b):
    """K0 = [[mT zT, -SA], [-SA, -SA sin(lam)]] with the total mass written out of it:
    mT zT = sum m z, mT xT = sum m x, mA uA = (sum_A m x - (w + c) mA) cos(lam)
    - sum_A m z sin(lam), SA = mA uA + (c / w) cos(lam) sum m x."""
    sl, cl = math.sin(b["lam"]), math.cos(b["lam"])
    mz = -b["rR"] * b["mR"] + b["zB"] * b["mB"] + b["zH"] * b["mH"] - b["rF"] * b["mF"]
    mx = b["xB"] * b["mB"] + b["xH"] * b["mH"] + b["w"] * b["mF"]
    mA = b["mH"] + b["mF"]
    mxA, mzA = b["xH"] * b["mH"] + b["w"] * b["mF"], b["zH"] * b["mH"] - b["rF"] * b["mF"]
    SA = (mxA - (b["w"] + b["c"]) * mA) * cl - mzA * sl + b["c"] / b["w"] * cl * mx
    return np.array([[mz, -SA], [-SA, -SA * sl]])


@pytest.mark.parametrize("body, mass", [("mB", 9.0),      # a frame without its rider
                                        ("mH", 90.0), ("mF", 91.0)])
def test_the_closed_form_holds_for_any_split_of_the_mass(body, mass):
    """K0 is the hand formula (no total mass in it) whichever body holds the mass: the frame
    as light as the other three together (9 kg), or the handlebar or the front wheel as heavy
    as the rest (90, 91 kg), where a sign slip in mT's sum makes it 0. The benchmark's own
    K0 is the printed one. Planted: mT = mR + mB + mH - mF, mR + mB - mH + mF,
    mR - mB + mH + mF (ZeroDivisionError on these splits)."""
    np.testing.assert_allclose(_k0_by_hand(B), MEIJAARD_MATRICES["K0"], rtol=0, atol=TOL_PRINTED)
    b = dict(B, **{body: mass})
    cf = closed_form(b)
    np.testing.assert_allclose(cf.K0, _k0_by_hand(b), rtol=1e-14, atol=0)
    for key in MATRICES:
        assert np.isfinite(getattr(cf, key)).all(), key


def test_a_vertical_steer_axis_capsizes_from_minus_to_plus_at_the_det_k_root():
    """Steer axis vertical (lam = 0): K0 = [[mT zT, -SA], [-SA, 0]], det K0 = -SA^2 < 0, and
    det K = g^2 det K0 + g v^2 SA ST / w: the product of the eigenvalues (det K / det M)
    changes sign from - to + at v^2 = g w SA / ST (3.52 m/s here), with no weave in 0..10 m/s.
    A capsize is a sign change in either direction. Planted: the capsize search from + to -
    only (down_only=True: no capsize found)."""
    b = dict(B, lam=0.0)
    SA = -_k0_by_hand(b)[0, 1]
    ST = b["IRyy"] / b["rR"] + b["IFyy"] / b["rF"]
    expected = math.sqrt(b["g"] * b["w"] * SA / ST)
    cf = closed_form(b)
    weave, capsize = closed_form_critical_speeds(cf)
    assert weave is None
    assert capsize == pytest.approx(expected, abs=TOL_SPEED)
    below, above = (np.prod(np.linalg.eigvals(_state(cf, v))).real for v in
                    (expected - 0.01, expected + 0.01))
    assert below < 0 < above


def test_a_weave_pair_that_splits_soon_after_turning_stable_is_found_on_the_default_grid():
    """A benchmark variant whose oscillatory pair crosses to negative real part at 6.02 m/s
    and splits into two real eigenvalues ~0.27 m/s later: the default 0.01 m/s grid brackets
    the crossing (a coarse grid's next point would have no pair at all). The speed found is
    where the pair's real part, from eigenvalues computed here, is zero, falling; the capsize
    speed above it is the det K root. Planted: the default step 1.01 m/s (no weave found)."""
    b = dict(B, w=0.99, c=0.11, lam=0.5, IRyy=0.07, xB=0.2, zB=-1.54, mB=35.0, IBxz=2.25,
             xH=1.53, zH=-0.41, IFyy=0.41)
    cf = closed_form(b)
    weave, capsize = closed_form_critical_speeds(cf)
    assert weave is not None and 6.0 < weave < 6.05

    def pair(v):
        lam = np.linalg.eigvals(_state(cf, v))
        return lam[lam.imag > 0]

    assert abs(pair(weave)[0].real) < 1e-9
    assert pair(weave - 0.01)[0].real > 0 > pair(weave + 0.01)[0].real
    assert pair(weave + 0.3).size == 0                    # all four real by then
    K0, K2 = cf.K0, cf.K2
    det_k_root = math.sqrt(-cf.g * np.linalg.det(K0) / (K0[0, 0] * K2[1, 1] - K0[1, 0] * K2[0, 1]))
    assert capsize == pytest.approx(det_k_root, abs=TOL_SPEED)


GRID = _grid(0.0, 1.0, 0.125)


def _vec(fn):
    return lambda s: fn(np.asarray(s, dtype=float).reshape(-1))


def test_a_zero_on_the_grids_first_point_is_no_crossing():
    """s (s - 0.2) is 0 at the grid's start, negative, then rising through 0 at 0.2: its
    first sign change is at 0.2, and it never falls from + to -. s (0.2 - s), from 0 up and
    then falling through 0.2, falls at 0.2 (not at the next grid point 0.25). Planted: a*b <= 0
    for a*b < 0 (0.0 found), a >= 0 for a > 0 when falling (0.0 found), values[i - 1] for
    values[i + 1] in the exact-zero shortcut (0.25 returned)."""
    rising = _vec(lambda s: s * (s - 0.2))
    falling = _vec(lambda s: s * (0.2 - s))
    assert _first_root(rising, GRID, down_only=False) == pytest.approx(0.2, abs=1e-14)
    assert _first_root(rising, GRID, down_only=True) is None
    assert _first_root(falling, GRID, down_only=True) == pytest.approx(0.2, abs=1e-14)
    assert _first_root(falling, GRID, down_only=False) == pytest.approx(0.2, abs=1e-14)


def test_a_crossing_onto_exactly_one_is_refined_not_taken_at_the_grid_point():
    """16 s - 5 is -1 at 0.25 and exactly 1 at 0.375: its root 5/16 lies between, found by
    brentq. Planted: the exact-zero shortcut testing == 1.0 (0.375 returned)."""
    line = _vec(lambda s: 16.0 * s - 5.0)
    assert _first_root(line, GRID, down_only=False) == pytest.approx(5 / 16, abs=1e-14)


def test_a_triple_root_is_refined_to_xtol():
    """(s - 1/3)^3 crosses flatly: brentq needs ~130 iterations to bracket it to its xtol
    1e-14 (+ rtol 4 eps |x|), within the 200 allowed. Planted: xtol dropped (brentq's default
    2e-12: 4e-13 off), maxiter dropped (the default 100: RuntimeError)."""
    r = 1.0 / 3.0
    cube = _vec(lambda s: (s - r) ** 3)
    root = _first_root(cube, GRID, down_only=False)
    assert abs(root - r) <= 1e-14 + 4 * np.finfo(float).eps * r


def test_the_speeds_and_the_bracketing_run_without_warnings():
    """The critical speeds of the benchmark (the paper's 4.292 and 6.024 m/s)
    and a root on a grid point (8 (0.5 - s) is 0 at 0.5) raise no warning of any kind.
    Planted: np.finfo(None) (a DeprecationWarning), a / b < 0 for a * b < 0 (divide by
    zero at the grid point)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        weave, capsize = closed_form_critical_speeds(closed_form(B))
        assert _first_root(_vec(lambda s: 8.0 * (0.5 - s)), GRID, down_only=False) == 0.5
    assert weave == pytest.approx(MEIJAARD_WEAVE_SPEED, abs=TOL_SPEED)
    assert capsize == pytest.approx(MEIJAARD_CAPSIZE_SPEED, abs=TOL_SPEED)
