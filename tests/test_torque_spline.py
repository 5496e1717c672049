"""The zig-zag torques' spline at one time (`reference_model.scenarios.runs.SplineAtTime`):
the integrator asks for it at every right-hand side, so it is evaluated in plain floats, and
it must give what scipy's `CubicSpline` gives, bit for bit (the reference's replay runs are
then unchanged to the last bit). scipy is the independent source. Costs ~0.2 s."""

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from reference_model.scenarios.runs import SplineAtTime


@pytest.fixture(scope="module")
def spline():
    rng = np.random.default_rng(11)
    t = 0.01 * np.arange(629)            # the zig-zag's grid: 0 ... 6.28 s
    return CubicSpline(t, rng.normal(size=(t.size, 3)), axis=0, bc_type="not-a-knot")


def test_one_time_is_scipys_value_bit_for_bit(spline):
    """Random times inside, beyond both ends (extrapolated from the end intervals), every knot
    and the floats either side of it, where the interval rule decides (x_i <= t < x_i+1, the
    last closed). Planted and failing: the interval found by bisect_left (at the knots); the
    sum as Horner's scheme (round-off anywhere)."""
    f = SplineAtTime(spline)
    x = spline.x
    times = np.concatenate([np.random.default_rng(5).uniform(-0.3, 6.6, 4000), x,
                            np.nextafter(x, -np.inf), np.nextafter(x, np.inf)])
    bad = [float(t) for t in times if not np.array_equal(f(t), spline(t))]
    assert not bad, f"{len(bad)} times differ, first {bad[:3]}"
    assert np.array_equal(f(np.float64(0.5)), spline(0.5)) and f(1).shape == (3,)


def test_arrays_and_non_finite_times_go_to_the_spline(spline):
    f = SplineAtTime(spline)
    t = np.linspace(0.0, 6.28, 7)
    assert np.array_equal(f(t), spline(t)) and f(t).shape == (7, 3)
    assert np.isnan(f(float("nan"))).all()
