"""The capsize search's reading of its grid (reference_model/linearize.py, `capsize_speed`): a
root of det(g K0 + v^2 K2) is a capsize speed where the determinant changes sign, whether the
root falls between two samples (brentq on that interval, xtol 1e-14) or exactly on one (that
sample); a zero the determinant does not cross, a zero at the range's start, and the search's
first sign change are each read as the docstring says. The determinants here are synthetic
polynomials with known roots on a 0.25 m/s grid (every sample exact in binary), no weave pair,
so the search runs over the whole range given; warnings are errors (a sign read by division
warns). Each test names the planted bugs (mutmut's survivors of the fix's first measurement)
it fails on. ~0.1 s.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import reference_model.linearize as lz
from reference_model import load_model
from reference_model.linearize import CriticalSpeedError, capsize_speed

EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


def _no_weave(model, v):
    v = np.asarray(v, dtype=float)
    return np.zeros(v.shape + (4,), dtype=complex) + np.array([-1.0, -2.0, -3.0, -4.0])


def _capsize(monkeypatch, bench, det):
    monkeypatch.setattr(lz, "eigenvalues", _no_weave)
    monkeypatch.setattr(lz, "_capsize_function", lambda model: det)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return capsize_speed(bench, (0.0, 2.0), step=0.25)


@pytest.mark.parametrize("det", [lambda v: -(v - 1.5) ** 2, lambda v: -(v - 1.5) * (v - 1.75)],
                         ids=["touch-from-below", "two-zero-samples"])
def test_zeros_the_grid_does_not_see_crossed_are_no_capsize_speed(bench, monkeypatch, det):
    """-(v - 1.5)^2 touches zero at the sample 1.5 from below; -(v - 1.5)(v - 1.75) is zero at
    the two samples 1.5 and 1.75 and negative on both sides of them (its positive part lies
    between two samples): the samples read -, 0, -, and -, 0, 0, -, no sign change, so no
    capsize speed in the range. Planted: the signs compared by division (-1 / 0 = -inf < 0
    reads a crossing, with a division warning), an on-sample zero accepted when its
    neighbours' signs multiply to <= 0 or < 1 (a zero neighbour)."""
    with pytest.raises(CriticalSpeedError, match=r"no capsize speed in \[0, 2\] m/s"):
        _capsize(monkeypatch, bench, det)


def test_a_zero_at_the_ranges_start_is_not_the_crossing(bench, monkeypatch):
    """det = v (v - 1.3) is zero at the range's start, 0 m/s, then negative, and crosses to
    positive at 1.3 m/s, between the samples 1.25 and 1.5: the capsize speed is 1.3, the sign
    change after the start. Planted: each sample's sign compared with the first sample's
    (sign[:1]: a zero start hides every later crossing)."""
    assert abs(_capsize(monkeypatch, bench, lambda v: v * (v - 1.3)) - 1.3) <= 1e-14 + 4 * EPS * 1.3


def test_the_first_crossing_between_samples_is_refined_whatever_the_last_sample(bench, monkeypatch):
    """det = (v - 0.1)(v - 2.0) crosses at 0.1 m/s, inside the first interval [0, 0.25], and is
    zero again at the range's last sample, 2 m/s: the capsize speed is 0.1 (brentq), not the
    interval's end. Planted: the on-sample test read at the sample before the interval
    (values[i - 1], which for the first interval is the last sample)."""
    assert abs(_capsize(monkeypatch, bench, lambda v: (v - 0.1) * (v - 2.0)) - 0.1) \
        <= 1e-14 + 4 * EPS * 0.1


def test_a_sample_of_exactly_one_after_a_crossing_is_not_taken_for_the_root(bench, monkeypatch):
    """det = 8 v - 5 is -1 at 0.5 m/s and exactly +1 at 0.75: the root is 0.625, inside the
    interval. Planted: the on-sample test comparing the sample with 1.0 instead of 0.0 (it
    returns 0.75)."""
    assert abs(_capsize(monkeypatch, bench, lambda v: 8.0 * v - 5.0) - 0.625) <= 1e-14 + 4 * EPS * 0.625
