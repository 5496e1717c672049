"""The generic linearization's edges (engines/linear.py): the critical-speed search on
synthetic eigenvalues whose crossings are set by hand (so the expected speeds are exact), the
speed checks, the upright configurations' Newton, and the reuse of solved configurations that
makes a root search cheap. Written from the survivors of `make mutants` on the module. The
engines are Pinocchio's terms on the benchmark bicycle (0.01 s a call), counted by a wrapper;
about 0.5 s in all.
"""

from __future__ import annotations

import numpy as np
import pytest

from engines import load_engine
from engines.linear import (DIFFERENCE_STEP, DifferenceEigenvalues, critical_speeds,
                            eigenvalues_by_differences, upright_configurations)
from reference_model import load_model
from reference_model.linearize import LinearizationError
from reference_model.names import COORDINATES

BETA = COORDINATES.index("beta")


def _synthetic(weave_re, capsize):
    """Eigenvalues sorted as `sort_eigenvalues`: a pair ``weave_re(v) +- 1 i`` (imaginary part
    exactly 1), then the real roots ``capsize(v)`` and -5; det has the sign of -capsize."""
    def lam(v):
        v = np.atleast_1d(np.asarray(v, dtype=float))
        out = np.empty((v.size, 4), dtype=complex)
        out[:, 0] = weave_re(v) + 1j
        out[:, 1] = weave_re(v) - 1j
        out[:, 2], out[:, 3] = capsize(v), -5.0
        return out
    return lam


def test_crossings_between_grid_points_are_refined_to_xtol():
    """Weave where 3.3 - v crosses zero, capsize where v - 6.2 does: 3.3 and 6.2 m/s to 1e-10,
    with an imaginary part of exactly 1 (planted: 'imag != 1' as the complex test fails)."""
    weave, capsize = critical_speeds(_synthetic(lambda v: 3.3 - v, lambda v: v - 6.2), (0.0, 10.0))
    assert weave == pytest.approx(3.3, abs=1e-10) and capsize == pytest.approx(6.2, abs=1e-10)


def test_a_capsize_mode_that_crosses_twice_within_a_metre_is_found():
    """A real root positive only between 6.2 and 6.6 m/s: the default 0.5 m/s grid brackets the
    first crossing; a grid of 1.5 m/s (or the step multiplied instead of divided) jumps over
    both."""
    lam = _synthetic(lambda v: 3.3 - v, lambda v: -(v - 6.2) * (v - 6.6))
    assert critical_speeds(lam, (0.0, 10.0))[1] == pytest.approx(6.2, abs=1e-10)


def test_a_crossing_in_the_last_interval():
    """Weave at 3.3 m/s in [0, 3.5]: the last grid interval (planted: bracket grid[i + 2],
    an IndexError)."""
    weave, capsize = critical_speeds(_synthetic(lambda v: 3.3 - v, lambda v: v - 6.2), (0.0, 3.5))
    assert weave == pytest.approx(3.3, abs=1e-10) and capsize is None


def test_a_weave_crossing_exactly_on_the_last_grid_point():
    """3 - v is exactly 0 at v = 3.0, the range's end: the weave speed is that grid point."""
    weave, _ = critical_speeds(_synthetic(lambda v: 3.0 - v, lambda v: v - 6.2), (0.0, 3.0))
    assert weave == 3.0


def test_a_zero_at_the_range_end_does_not_stand_for_a_crossing_at_its_start():
    """(0.3 - v)(3 - v): + to - at 0.3 m/s, and exactly 0 again at 3.0, the range's end: the
    weave speed is 0.3 (refined), not the first interval's end (planted: re[i - 1] == 0)."""
    weave, _ = critical_speeds(_synthetic(lambda v: (0.3 - v) * (3.0 - v), lambda v: v - 6.2),
                               (0.0, 3.0))
    assert weave == pytest.approx(0.3, abs=1e-10)


def test_a_pair_already_stable_at_the_range_start_has_no_weave_there():
    """The pair's real part is 0 at the first speed and negative after: it does not cross from
    + to - within the range, so there is no weave speed (planted: re >= 0 as the start)."""
    weave, capsize = critical_speeds(_synthetic(lambda v: 1.0 - v, lambda v: v - 2.2), (1.0, 3.0))
    assert weave is None and capsize == pytest.approx(2.2, abs=1e-10)


def test_known_samples_outside_the_range_are_not_searched():
    """``known`` holds 0..10 m/s: within (0, 5) there is no capsize at 6.2; a capsize in the
    last interval (9.8 in (0, 10)) and a weave in the first (0.3) are found (planted: | for &,
    or either end left out)."""
    grid = np.linspace(0.0, 10.0, 21)
    lam = _synthetic(lambda v: 3.3 - v, lambda v: v - 6.2)
    assert critical_speeds(lam, (0.0, 5.0), known=(grid, lam(grid)))[1] is None
    late = _synthetic(lambda v: 3.3 - v, lambda v: v - 9.8)
    assert critical_speeds(late, (0.0, 10.0), known=(grid, late(grid)))[1] == \
        pytest.approx(9.8, abs=1e-10)
    early = _synthetic(lambda v: 0.3 - v, lambda v: v - 6.2)
    assert critical_speeds(early, (0.0, 10.0), known=(grid, early(grid)))[0] == \
        pytest.approx(0.3, abs=1e-10)


# -- the engine side ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def bench():
    m = load_model("benchmark")
    return m, load_engine("pinocchio", m)


class _Counting(DifferenceEigenvalues):
    """Pinocchio's terms, counting the Newton's residual calls (what a solved upright saves)."""

    def __init__(self, eng):
        self.name, self.model, self._eng, self.residual_calls = "counted", eng.model, eng, 0

    def constraint_residual(self, q, dq):
        self.residual_calls += 1
        return self._eng.constraint_residual(q, dq)

    def constraint_jacobian(self, q):
        return self._eng.constraint_jacobian(q)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._eng.forward_acceleration(q, dq, torques)


@pytest.mark.parametrize("speeds", [[[1.0, 2.0]], [1.0, np.inf], [np.nan]])
def test_speeds_must_be_finite_and_one_dimensional(bench, speeds):
    with pytest.raises(ValueError, match=r"speeds must be a finite speed or a 1-D array"):
        eigenvalues_by_differences(_Counting(bench[1]), speeds)


def test_the_upright_configurations_sit_on_the_front_contact(bench):
    """Five configurations (upright, theta +-h, gamma +-h), each with beta solved so the front
    contact's height is below 1e-15 m; the benchmark's upright beta is its head-angle pitch
    (not 0, so Newton's step r / slope is exercised: r * slope does not converge), and the step
    is recorded."""
    model, eng = bench
    up = upright_configurations(eng, h=1e-6)
    assert up.q.shape == (5, 8) and up.D.shape == (5, 5, 8) and up.h == 1e-6
    r = np.asarray(eng.constraint_residual(up.q, np.zeros_like(up.q)))[:, 0]
    assert np.abs(r).max() < 1e-15
    assert abs(up.q[0, BETA]) > 1e-3
    # Newton's quadratic convergence from beta = 0 (0.31 m off): at most 6 residual calls,
    # where a step of r * slope (slope -1.02 here) contracts by 0.04 a call and needs ~12
    counted = _Counting(eng)
    upright_configurations(counted, h=1e-6)
    assert counted.residual_calls <= 6, counted.residual_calls
    np.testing.assert_array_equal(up.q[1:, COORDINATES.index("theta")], [1e-6, -1e-6, 0.0, 0.0])
    np.testing.assert_array_equal(up.q[1:, COORDINATES.index("gamma")], [0.0, 0.0, 1e-6, -1e-6])


def test_a_newton_that_never_converges_is_named():
    class Never(_Counting):
        def __init__(self, eng):
            super().__init__(eng)
            self.name = "never"

        def constraint_residual(self, q, dq):
            return np.ones((np.shape(q)[0], 5))

    eng = load_engine("pinocchio", load_model("benchmark"))
    with pytest.raises(LinearizationError, match=r"engine 'never': Newton on the front contact's "
                                                 r"height .* did not converge in 50 iterations "
                                                 r"\(last residual 1\.0e\+00 m\); check the "
                                                 r"model's geometry$"):
        upright_configurations(Never(eng))


def test_a_model_with_drag_has_no_upright_steady_motion():
    import dataclasses
    m = load_model("benchmark")
    dragged = m.with_params(dataclasses.replace(m.params, cv=0.1))
    eng = load_engine("pinocchio", m)

    class Dragged(_Counting):
        def __init__(self, eng):
            super().__init__(eng)
            self.model = dragged

    with pytest.raises(LinearizationError, match=r"cv = 0.1 kg/m: with drag, upright straight "
                                                 r"running is not a steady motion; fix: "
                                                 r"linearize a copy with cv = 0$"):
        upright_configurations(Dragged(eng))


def test_a_solved_upright_is_reused_at_its_step_only(bench):
    """The configurations solved at h are reused at h (no Newton call), solved again at
    another h (an upright at 1e-6 used at 1e-7 would perturb by 1e-6 and divide by 2e-7), and
    an engine's own `eigenvalues` solves them once for all its calls."""
    model, eng = bench
    c = _Counting(eng)
    up = upright_configurations(c)
    n = c.residual_calls
    v = np.array([2.0, 5.0])
    fresh = eigenvalues_by_differences(c, v, upright=up)
    assert c.residual_calls == n
    stale = upright_configurations(c, h=1e-6)
    again = eigenvalues_by_differences(c, v, upright=stale)       # h = DIFFERENCE_STEP
    assert c.residual_calls > n + 1
    np.testing.assert_array_equal(again, fresh)
    coarse = eigenvalues_by_differences(c, v, h=1e-6)
    assert np.abs(coarse - model.eigenvalues(v)).max() < 1e-8      # h^2 truncation ~4e-10
    counted = _Counting(eng)
    first = counted.eigenvalues(v)
    calls = counted.residual_calls
    second = counted.eigenvalues(np.array([3.0]))
    assert counted.residual_calls == calls
    np.testing.assert_array_equal(first, eigenvalues_by_differences(counted, v))
    assert np.abs(second - model.eigenvalues(np.array([3.0]))).max() < 1e-12
    assert DIFFERENCE_STEP == 1e-7
