"""One comparison for the engine-edge tests: an engine's quantity against the reference
model's, to 1e-9 of the quantity's size (at least 1). Two independent computations of M,
the forces and D agree to ~1e-12..1e-11 relative on the built-in bicycles (round-off,
amplified by the constrained solves): 1e-9 leaves two orders of margin and still fails on any
wrong term (their effects are O(1e-3) relative or more)."""

import numpy as np

__all__ = ["assert_round_off"]


def assert_round_off(got, expected, rel: float = 1e-9) -> None:
    expected = np.asarray(expected, dtype=float)
    np.testing.assert_allclose(got, expected, rtol=0,
                               atol=rel * max(1.0, float(np.abs(expected).max())))
