"""The reference linearization's edges (reference_model/linearize.py): the eigenvalue order on
hand-made spectra, the critical speeds against the published 14-digit values, the searches'
errors and their wording, and the fields of a `Linearization`. Written from the survivors of
`make mutants` on the module. Expected values: Meijaard et al. 2007 / Basu-Mandal et al. 2007
(the benchmark's weave and capsize speeds to 14 digits, comparisons/judgments/published.py)
and orders written out by hand. About 0.2 s (the benchmark's compiled evaluator is cached).
"""

import numpy as np
import pytest

from comparisons.judgments.published import MEIJAARD_CAPSIZE_SPEED, MEIJAARD_WEAVE_SPEED
from reference_model import load_model
from reference_model.linearize import (CriticalSpeedError, capsize_speed, eigenvalues,
                                       linearize, sort_eigenvalues, weave_speed)


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


def test_pairs_first_by_frequency_then_real_part_then_the_reals_decreasing():
    """A spectrum in scrambled order: the pair of largest |imag| first (+imag then -imag), pairs
    of equal |imag| by larger real part, then the real roots in decreasing order; an imaginary
    part of exactly 1 is a pair like any other."""
    lam = np.array([-1.0, 0.5 - 1j, 2.0, 1 - 3j, 0.5 + 1j, 1 + 3j, 2 - 1j, 2 + 1j])
    want = np.array([1 + 3j, 1 - 3j, 2 + 1j, 2 - 1j, 0.5 + 1j, 0.5 - 1j, 2.0, -1.0])
    np.testing.assert_array_equal(sort_eigenvalues(lam), want)


def test_every_row_is_sorted_on_its_own_along_the_last_axis():
    """(2, 2, 4): each row of four sorted alone (planted: the sort along another axis or over
    the flattened array)."""
    a = np.array([-1.0, 1 - 2j, 3.0, 1 + 2j])
    b = np.array([0.5, -0.5, 4 + 1j, 4 - 1j])
    lam = np.array([[a, b], [b, a]])
    out = sort_eigenvalues(lam)
    sa, sb = [1 + 2j, 1 - 2j, 3.0, -1.0], [4 + 1j, 4 - 1j, 0.5, -0.5]
    np.testing.assert_array_equal(out, np.array([[sa, sb], [sb, sa]]))
    np.testing.assert_array_equal(sort_eigenvalues([3.0, -1.0, 2.0]), [3.0, 2.0, -1.0])


def test_the_critical_speeds_are_the_published_ones_to_the_last_digits(bench):
    """Basu-Mandal et al.'s 14 digits: the weave speed 4.29238253634111 and capsize speed
    6.02426201538837 m/s; brentq at xtol 1e-14 and rtol 4 eps lands within 5e-14 (measured
    3.6e-15 and 1.5e-14). Planted: brentq at its default tolerances (2e-12)."""
    assert abs(weave_speed(bench) - MEIJAARD_WEAVE_SPEED) < 5e-14
    assert abs(capsize_speed(bench) - MEIJAARD_CAPSIZE_SPEED) < 5e-14


def test_a_range_without_a_weave_speed_says_so(bench):
    with pytest.raises(CriticalSpeedError, match=r"^model 'benchmark': no weave speed in \[5, 10\] "
                                                 r"m/s \(the oscillatory pair's real part does not "
                                                 r"change sign from \+ to -\); widen the range$"):
        weave_speed(bench, (5.0, 10.0))


def test_a_range_without_a_capsize_speed_says_so(bench):
    """Below 4 m/s there is neither a weave (4.29) nor a capsize speed: the capsize search runs
    over the range given, not over the default 0-20 m/s (planted: the weave searched over the
    default range, which then starts the capsize search above the range's end)."""
    with pytest.raises(CriticalSpeedError, match=r"^model 'benchmark': no capsize speed in \[0, 4\] "
                                                 r"m/s \(no real eigenvalue crosses zero\); widen "
                                                 r"the range$"):
        capsize_speed(bench, (0.0, 4.0))
    # above the weave speed only: the search starts at the range's low end
    assert abs(capsize_speed(bench, (5.0, 10.0)) - MEIJAARD_CAPSIZE_SPEED) < 5e-14


@pytest.mark.parametrize("speeds", [(3.0, 3.0), (-1.0, 5.0), (0.0, np.inf), (np.nan, 5.0)])
def test_a_speed_range_must_be_finite_and_increasing(bench, speeds):
    with pytest.raises(ValueError, match=r"^speeds must be \(low, high\) with 0 <= low < high "
                                         r"\(m/s\); got"):
        weave_speed(bench, speeds)


@pytest.mark.parametrize("v", [[[1.0, 2.0]], [1.0, np.inf]])
def test_speeds_must_be_finite_and_at_most_one_dimensional(bench, v):
    with pytest.raises(ValueError, match=r"^v must be a finite speed or a 1-D array of finite "
                                         r"speeds \(m/s\); got"):
        eigenvalues(bench, v)


def test_a_linearization_carries_its_state_matrix_read_only_and_its_checks(bench):
    """A at 5 m/s has the eigenvalues of `eigenvalues` (the same 4x4 problem); it cannot be
    written; beta0 is the benchmark's head-angle pitch pi/10; coupling and residual are round-off
    (0 by symmetry, 0 at the steady motion)."""
    lin = linearize(bench, 5.0)
    np.testing.assert_allclose(lin.eigenvalues(), eigenvalues(bench, 5.0), rtol=0, atol=1e-13)
    with pytest.raises(ValueError):
        lin.A[0, 0] = 1.0
    assert lin.beta0 == pytest.approx(-np.pi / 10, abs=1e-14)
    assert 0.0 <= lin.coupling < 1e-12 and 0.0 <= lin.residual < 1e-12
