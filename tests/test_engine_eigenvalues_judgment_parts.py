"""The eigenvalue judgment's arithmetic (comparisons/judgments/engine_eigenvalues.py) held to the
part of its contract that tests/test_engine_eigenvalues.py leaves open: `matched_error` is the
module docstring's formula, max |got - expected| under the best pairing over
max(1, max |expected|), evaluated in double precision whatever the precision of the arrays it is
handed. The expected values are worked by hand. The test names the planted bugs (mutmut's
survivors of the module's first measurement) it fails on. ~0.01 s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from comparisons.judgments.engine_eigenvalues import matched_error


@pytest.mark.parametrize("precision", [np.complex128, np.complex64])
def test_a_single_precision_reference_is_scaled_by_its_exact_magnitude(precision):
    """One speed by hand: the reference's 1 +- 1j, -0.5, -0.25 (each exact in single
    precision), the engine's the same but for +0.25 in place of -0.25. The best pairing leaves
    |0.25 - (-0.25)| = 0.5 (the other real pairing leaves 0.75), and the largest |reference|
    is |1 + 1j| = sqrt(2), so the error is 0.5 / sqrt(2) = sqrt(2) / 4, to 1e-15, whether the
    reference arrives as complex128 or as complex64. Planted: the reference's conversion to
    complex dropped (dtype=None, or no dtype): for complex64, |1 + 1j| is then taken in single
    precision (1.4142135381...), 1.7e-8 relative off sqrt(2)."""
    expected = np.array([[1 + 1j, 1 - 1j, -0.5, -0.25]], dtype=precision)
    got = [[1 - 1j, 0.25, 1 + 1j, -0.5]]
    err = matched_error(got, expected)
    assert err.shape == (1,)
    assert err[0] == pytest.approx(math.sqrt(2.0) / 4.0, rel=1e-15, abs=0.0)
