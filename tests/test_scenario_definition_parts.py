"""Sampled rider torques (`TorqueSamples.function`, reference_model/scenarios/definition.py)
held to their docstring: the samples' times and (Mdir, Mped, Mvue) rows interpolated as
"cubic" (a not-a-knot spline), "linear" or "previous" (a zero-order hold: the last sample at or
before the time), a (3,) row for one time and (N, 3) rows for N times, and any other name refused
in one line naming it and the three choices. The expected values are independent of the code:
a cubic polynomial, which a not-a-knot spline through four or more of its samples reproduces
exactly (scipy's CubicSpline docs: the first two and the last two pieces are each one
polynomial, so the spline is the unique cubic through the samples); straight lines between
samples and held samples worked out by hand. tests/test_scenario_definition.py covers the
`Scenario` record (its default quantities by kind and the refusal of an unknown one). Each test
names the planted bugs (mutmut's mutants of the module, which no test reached) it fails on.
~0.1 s.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from reference_model.scenarios import TorqueSamples

# Uneven sample times (0.5, 0.75, 0.75, 1 s apart) so that no interval rule is hidden by symmetry.
_KNOTS = (0.0, 0.5, 1.25, 2.0, 3.0)


def _cubics(s):
    """Mdir = s^3 - 2 s^2 + 1, Mped = -2 s^3 + s, Mvue = s^2 / 2 - 3 (a quadratic is a cubic
    too): rows (N, 3) for times s (N,)."""
    s = np.asarray(s, dtype=float)
    return np.stack([s**3 - 2 * s**2 + 1, -2 * s**3 + s, 0.5 * s**2 - 3], axis=-1)


def test_a_cubic_spline_through_samples_of_cubics_is_those_cubics():
    """Samples of three cubic polynomials at uneven times, interpolated "cubic": between the
    samples the function gives the polynomials (the not-a-knot spline reproduces a cubic
    exactly; the end conditions of a natural spline, f'' = 0, would not hold here, since
    Mdir'' = 6 s - 4 is -4 at s = 0), as one (3,) row for one time and (N, 3) rows for N times.
    Planted and failing: "cubic" compared with != or misspelt (the samples fall to linear or
    to the refusal); the spline built without its times or values, along axis 1 or None, with
    bc_type None or an unknown name; the spline None; the function returning None or the
    spline at None."""
    samples = TorqueSamples(t=_KNOTS, T=tuple(tuple(r) for r in _cubics(_KNOTS).tolist()),
                            interpolation="cubic")
    f = samples.function()
    one = f(0.9)
    assert one.shape == (3,)
    np.testing.assert_allclose(one, _cubics(0.9), rtol=0, atol=1e-12)
    s = np.array([0.2, 0.9, 1.6, 2.7])
    rows = f(s)
    assert rows.shape == (4, 3)
    np.testing.assert_allclose(rows, _cubics(s), rtol=0, atol=1e-12)


# Three samples at 0, 1 and 3 s; straight lines between them, worked out by hand.
_LINEAR = TorqueSamples(t=(0.0, 1.0, 3.0), T=((0.0, 0.0, 0.0), (2.0, -1.0, 4.0), (6.0, 3.0, 0.0)),
                        interpolation="linear")


def test_linear_interpolation_is_the_straight_line_between_neighbouring_samples():
    """At 0.25 s, a quarter of the way from (0, 0, 0) to (2, -1, 4): (0.5, -0.25, 1); at 2 s,
    halfway from (2, -1, 4) to (6, 3, 0): (4, 1, 2); on the samples, the samples. One time
    gives a (3,) row, N times (N, 3) rows (one per time, not one per torque). Planted and
    failing: "linear" compared with != or misspelt; the function returning None; the stack
    of the three columns given None, nothing, or stacked along axis None, 0, 1 or -2 (a
    (3, N) array, or an error for one time); np.interp given None for the time, the sample
    times or the values, or short of an argument; the columns counted as range(None) or
    range(4)."""
    f = _LINEAR.function()
    one = f(0.25)
    assert one.shape == (3,)
    np.testing.assert_allclose(one, [0.5, -0.25, 1.0], rtol=0, atol=1e-15)
    rows = f(np.array([0.0, 0.25, 1.0, 2.0, 3.0]))
    assert rows.shape == (5, 3)
    np.testing.assert_allclose(rows, [[0.0, 0.0, 0.0], [0.5, -0.25, 1.0], [2.0, -1.0, 4.0],
                                      [4.0, 1.0, 2.0], [6.0, 3.0, 0.0]], rtol=0, atol=1e-15)


_HELD_ROWS = ((1.0, 2.0, 3.0), (-1.0, 0.5, 7.0), (4.0, -4.0, 0.25), (9.0, 8.0, -6.0))
_HELD = TorqueSamples(t=(0.0, 1.0, 2.5, 4.0), T=_HELD_ROWS, interpolation="previous")


def test_previous_holds_the_last_sample_at_or_before_each_time():
    """A zero-order hold: from each sample's time up to (not including) the next one, that
    sample; at 4 s, the last sample's own time, the last sample. Times on the samples are
    where the rule "at or before" decides (1 s gives the second sample, not the first). One
    time gives a (3,) row, N times (N, 3) rows. Planted and failing: "previous" compared with
    != or misspelt; searchsorted with side "left" (the default, or None, or a misspelt side),
    or given None, or short of the times or the sample times; the index found plus 1 or
    minus 2; clipped from 1 (the first interval gets the second sample) or to len - 2 (the
    last time gets the one before); the index None or the clip short of an argument."""
    f = _HELD.function()
    assert f(0.5).shape == (3,) and np.array_equal(f(0.5), _HELD_ROWS[0])
    s = np.array([0.0, 0.5, 1.0, 2.0, 2.5, 3.9, 4.0])
    want = np.array([_HELD_ROWS[i] for i in (0, 0, 1, 1, 2, 2, 3)])
    rows = f(s)
    assert rows.shape == (7, 3)
    assert np.array_equal(rows, want)


def test_before_the_first_sample_the_hold_gives_the_first_sample_as_linear_does():
    """A time before the first sample (outside what a scenario file allows: its samples must
    cover the run) has no sample at or before it: the hold gives the first sample, the value
    the linear interpolation gives there too (np.interp's documented left value, fp[0]), and
    never the last sample. Planted and failing: the clip's lower bound None (the index -1
    wraps round to the last sample)."""
    held = _HELD.function()(-0.5)
    linear = TorqueSamples(t=_HELD.t, T=_HELD_ROWS, interpolation="linear").function()(-0.5)
    assert np.array_equal(held, _HELD_ROWS[0]) and np.array_equal(linear, _HELD_ROWS[0])


def test_an_unknown_interpolation_is_refused_naming_it_and_the_three_choices():
    """"spline" (a user's guess at "cubic") is refused when the function is asked for, in one
    line that names it and the three interpolations of the docstring. Planted and failing:
    "previous" compared with != (any other name gets the hold); the message None or its last
    choice misspelt or upper-cased."""
    samples = TorqueSamples(t=(0.0, 1.0), T=((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)),
                            interpolation="spline")
    exact = "^" + re.escape("unknown interpolation 'spline'; use cubic, linear or previous") + "$"
    with pytest.raises(ValueError, match=exact):
        samples.function()
