"""The benchmark's critical speeds are found without a warning (reference_model/linearize.py):
a user running `bicycle-xval` with warnings shown (or turned into errors, as a CI might) sees
none from the reference's own searches. Planted: np.finfo(None) for np.finfo(float) in the
weave search's brentq tolerance (numpy 2.4's DeprecationWarning "finfo() dtype cannot be
None", an error in a future numpy). The speeds are Meijaard et al. (2007)'s published 4.2924
and 6.0243 m/s."""

from __future__ import annotations

import warnings

import pytest

from reference_model import load_model
from reference_model.linearize import capsize_speed, weave_speed


def test_the_benchmarks_critical_speeds_raise_no_warning():
    bench = load_model("benchmark")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert weave_speed(bench) == pytest.approx(4.2924, abs=5e-5)
        assert capsize_speed(bench) == pytest.approx(6.0243, abs=5e-5)
