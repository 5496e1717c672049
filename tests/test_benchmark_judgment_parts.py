"""Parts of the benchmark's judgments (comparisons/judgments/benchmark.py) that
tests/test_benchmark_judgments.py leaves open, issue 24: the matrix pencil's contract (a
uniform grid of any start, thinned to ``sample``, refused in the module's words when the grid,
the sample or the number of samples will not do; each channel scaled to unit peak; sorted +imag
first, then by decreasing real part), the capsize eigenvalue picked among the real ones, the
envelope on flat-topped peaks and on a run that does not start at 0, the strict inequalities
of the verdicts (an envelope rate of 0 is no growth, a capsize rate of 0 no capsize, a steady
lean no monotone growth), the slowness over the run's own duration, the capsize mode fitted
only *above* the capsize speed and the benchmark's upright pitch -pi/10 to the last bit.
Expected values come from Table 2 (Meijaard et al. 2007, the exponents of the synthetic
signals), Table 1's head angle, the stage's docstring (comparisons/stages/benchmark.py) and
hand computations on small synthetic signals. Planted bugs each test was seen failing on are
named in it. ~0.2 s."""

import dataclasses
import re

import numpy as np
import pytest

from comparisons.judgments.benchmark import (_pick, capsize_measure, identify_eigenvalues,
                                             judge_outcome, mode_fits, roll_rate_envelope,
                                             speed_of, upright_state)
from comparisons.judgments.published import MEIJAARD_CAPSIZE_SPEED, MEIJAARD_TABLE2
from reference_model import load_model
from reference_model.scenarios import SCENARIOS
from reference_model.solvers import Trajectory

THETA, GAMMA = 3, 6
RE, IM, CAP, CAS = MEIJAARD_TABLE2[8]      # weave RE +- IM i, capsize CAP, castor CAS (1/s)
TABLE2_SORTED = np.array([complex(RE, IM), CAP, CAS, complex(RE, -IM)])


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


def _traj(t, theta, dtheta=None, gamma=None, status="completed"):
    t = np.asarray(t, float)
    q, dq = np.zeros((t.size, 8)), np.zeros((t.size, 8))
    q[:, THETA] = theta
    if dtheta is not None:
        dq[:, THETA] = dtheta
    if gamma is not None:
        q[:, GAMMA] = gamma
    return Trajectory(t, q, dq, np.zeros_like(q), np.zeros((t.size, 5)), np.zeros((t.size, 3)),
                      status, "", float(t[-1]))


def _table2_run(t, t0=0.0):
    """theta and gamma made of Table 2's four modes at 8 m/s, started at t0."""
    s = np.asarray(t) - t0
    theta = 1e-3 * (np.exp(RE * s) * np.cos(IM * s) + 0.5 * np.exp(CAP * s)
                    + 0.3 * np.exp(CAS * s))
    gamma = 1e-3 * (0.7 * np.exp(RE * s) * np.sin(IM * s) - 0.2 * np.exp(CAP * s)
                    + 0.4 * np.exp(CAS * s))
    return _traj(t, theta, gamma=gamma)


def _grid(n, step=0.01, start=0.0):
    return np.round(start + step * np.arange(n), 10)


def _rel(lam):
    return np.abs(lam - TABLE2_SORTED) / np.abs(TABLE2_SORTED)


# -- the matrix pencil --------------------------------------------------------------------------

def test_the_pencil_sorts_plus_imag_first_and_the_real_modes_by_decreasing_real_part():
    """Table 2's modes at 8 m/s come back sorted as the docstring says: the weave with +imag
    first; the two real ones (capsize +0.143, castor -20.3 /s, imaginary part exactly 0) by
    decreasing real part. Planted: the real parts' key sign flipped (castor before capsize); the
    imaginary parts' key flipped (the -imag weave first)."""
    lam = identify_eigenvalues(_table2_run(_grid(501)))
    assert lam[0] == pytest.approx(complex(RE, IM), rel=1e-9)
    real = lam[lam.imag == 0].real
    assert real.tolist() == pytest.approx([CAP, CAS], rel=1e-9)
    assert _rel(lam).max() < 1e-9


def test_a_run_that_does_not_start_at_zero_is_identified_the_same():
    """The step is t[1] - t[0], whatever t[0]: the same modes on a run from 1 s to 6 s (the
    signal started there). Planted: the step taken as t[1] + t[0] (2.01 s: the grid then looks
    non-uniform and is refused)."""
    lam = identify_eigenvalues(_table2_run(_grid(501, start=1.0), t0=1.0))
    assert _rel(lam).max() < 1e-9


def test_a_sample_equal_to_the_step_keeps_every_sample():
    """``sample`` a multiple of the step includes 1 times it: a run on the 0.04 s grid fitted
    at sample = 0.04 s (stride 1) gives Table 2's modes. Planted: stride 1 refused (stride
    <= 1; stride < 2)."""
    lam = identify_eigenvalues(_table2_run(_grid(126, step=0.04)), sample=0.04)
    assert _rel(lam).max() < 1e-9


def test_a_grid_that_is_not_uniform_is_refused_in_words():
    """An event row (a sample at 0.505 s between 0.50 and 0.51) and one sample moved by 1e-9 s
    (1e-7 of the 0.01 s step) are both not a uniform grid: refused with the module's message,
    exactly. Planted: the message None, wrapped in 'XX', upper-cased; the allowance 1e-9 / dt
    (1e-7 s: the moved sample let through); 1.000000001 dt (the event row let through)."""
    exact = ("^" + re.escape("identify_eigenvalues needs a uniform grid (the run's event row?)")
             + "$")
    t = _grid(101)
    with_event = np.insert(t, 51, 0.505)
    with pytest.raises(ValueError, match=exact):
        identify_eigenvalues(_table2_run(with_event))
    moved = t.copy()
    moved[50] += 1e-9
    with pytest.raises(ValueError, match=exact):
        identify_eigenvalues(_table2_run(moved))


def test_a_sample_that_is_not_a_multiple_of_the_step_is_refused_in_words():
    """sample = 0.033 s on the 0.01 s grid (3.3 steps) and 0.04 s + 1e-9 s (2.5e-8 of it off
    the 4 steps) are refused with the message naming both; 0.04 s itself is accepted (the
    default). Planted: the two conditions joined by 'and' (a stride of 3 passes); the allowance
    1.000000001 sample (0.033 passes); 1e-9 / sample (2.5e-8 s: 0.04 s + 1e-9 passes); the
    message None."""
    run = _table2_run(_grid(201))
    with pytest.raises(ValueError, match="^" + re.escape(
            "sample 0.033 s must be a multiple of the run's step 0.01 s") + "$"):
        identify_eigenvalues(run, sample=0.033)
    with pytest.raises(ValueError, match="^" + re.escape(
            "sample 0.04 s must be a multiple of the run's step 0.01 s") + "$"):
        identify_eigenvalues(run, sample=0.04 + 1e-9)
    assert _rel(identify_eigenvalues(run, sample=0.04)).max() < 1e-9


def test_ten_samples_fit_four_modes_and_nine_are_refused():
    """n thinned samples give a Hankel matrix of n/2 + 1 columns per channel, so four modes
    need n/2 > 4: 37 samples on the 0.01 s grid thin to 10 at 0.04 s (5 > 4) and give Table 2's
    modes exactly as exponentials do; 33 thin to 9 (4, not > 4) and are refused, counting the
    thinned samples. Planted: n/3 (10 refused); L - 1 columns (10 samples: a 4-column matrix
    has no shift pencil left); L < order (9 samples fitted); the message None; the count taken
    from q's width (8, the coordinates)."""
    assert _rel(identify_eigenvalues(_table2_run(_grid(37)))).max() < 1e-9
    with pytest.raises(ValueError, match="^" + re.escape(
            "9 samples are too few for 4 modes") + "$"):
        identify_eigenvalues(_table2_run(_grid(33)))


def test_the_channels_are_scaled_to_unit_peak():
    """Each channel is scaled to unit peak, so a channel's size does not weigh in the fit:
    theta carrying the capsize and the castor at 1e-15 the size of gamma's weave (0.1 rad)
    still gives all four modes to the fit's accuracy. Planted: the channel multiplied by its
    peak (theta's modes vanish under gamma's: 60x off); divided by 1 (theta left at 1e-15:
    ~1e-1 off)."""
    t = _grid(501)
    theta = 1e-16 * (0.5 * np.exp(CAP * t) + 0.3 * np.exp(CAS * t))
    gamma = 0.1 * np.exp(RE * t) * np.cos(IM * t)
    assert _rel(identify_eigenvalues(_traj(t, theta, gamma=gamma))).max() < 1e-9


# -- the mode picked ----------------------------------------------------------------------------

def test_the_weave_is_the_eigenvalue_with_the_largest_imaginary_part_wherever_it_is():
    """The weave is the +imag one whatever its place in the array (here last). Planted:
    argmax over None (the first element taken)."""
    lam = np.array([-20.0, 0.14, -2 - 8j, -2 + 8j])
    assert _pick(lam, "weave", -2 + 8j) == -2 + 8j


def test_the_capsize_is_picked_among_the_real_eigenvalues():
    """The capsize mode is real: the nearest *real* eigenvalue is picked, even with a complex
    one nearer (0.5 rather than 0.1 +- 0.2i for 0.1); real means |imag| <= 1e-12 |lambda|,
    a relative allowance: -20 with a roundoff imaginary part of 2e-12 (1e-13 of it) is real,
    and so is an eigenvalue of exactly 0 (the capsize at the capsize speed). Planted: every
    eigenvalue counted real (1.000000000001 |lambda|; the real pool never used); the allowance
    1e-12 / |lambda| (-20 + 2e-12i complex: the weave picked); < for <= (0 not real: the
    complex 0.3 +- 0.05i picked)."""
    assert _pick(np.array([0.5, 0.1 + 0.2j, 0.1 - 0.2j]), "capsize", 0.1) == 0.5
    assert _pick(np.array([-2 + 8j, -2 - 8j, -20 + 2e-12j]), "capsize", -3.0) == -20 + 2e-12j
    assert _pick(np.array([-2 + 8j, -2 - 8j, 0.0, 0.3 + 0.05j, 0.3 - 0.05j]), "capsize",
                 0.25) == 0.0


def test_the_capsize_mode_is_fitted_only_above_the_capsize_speed(bench):
    """mode_fits's docstring: the capsize mode at speeds *above* the capsize speed. At exactly
    6.02426201538837 m/s (psi_dot = v / R_rear, R_rear v / R_rear == v in floats) only the
    weave, and by default its engine is 'reference'. Planted: >= for > (the capsize fitted at
    the capsize speed too); the default engine wrapped in 'XX', upper-cased."""
    sc = SCENARIOS["benchmark-v8"]
    at = dataclasses.replace(sc, dq_ind0=(sc.dq_ind0[0], MEIJAARD_CAPSIZE_SPEED / 0.3,
                                          *sc.dq_ind0[2:]))
    assert bench.params.R_rear == 0.3 and speed_of(bench, at) == MEIJAARD_CAPSIZE_SPEED
    fits = mode_fits(bench, at, _table2_run(_grid(201)))
    assert [(f.mode, f.engine) for f in fits] == [("weave", "reference")]


# -- the envelope and the verdicts --------------------------------------------------------------

def test_a_flat_topped_peak_counts_once_at_its_middle_on_a_run_from_2_s():
    """|dtheta/dt| repeating 0, 0.5, 1, 1, 0.5 (period 5 samples of 0.01 s) from t = 2 s: each
    flat top is one peak, refined by the parabola through (-1, 1), (0, 1), (1, 0.5) (the second
    top sample and its neighbours), p(x) = 1 - x/4 - x^2/4, to x = -1/2 (midway between the two
    tops) and p = 17/16; 20 equal peaks, rate 0. Planted: > for >= on the left (a flat top is
    no peak); >= for > on the right (each counted twice); the step taken as t[1] + t[0] (the
    peaks 2 s off)."""
    t = _grid(100, start=2.0)
    y = np.tile([0.0, 0.5, 1.0, 1.0, 0.5], 20)
    env = roll_rate_envelope(_traj(t, 0 * t, y))
    assert env.peaks.tolist() == pytest.approx([17 / 16] * 20, rel=1e-15)
    assert env.t.tolist() == pytest.approx((2.0 + 0.01 * (5 * np.arange(20) + 2.5)).tolist(),
                                           abs=1e-12)
    assert env.rate == pytest.approx(0.0, abs=1e-12)


def test_a_neutral_weave_is_not_growth():
    """The stage's docstring: envelope rate > 0 grows. |dtheta/dt| repeating 0, 0.5, 1, 0.5:
    125 peaks of exactly 1 (a symmetric parabola: no shift), log 1 = 0, rate 0: at 4 m/s
    (growth predicted) it fails. Planted: >= 0 for > 0 (a rate of 0 counted as growth)."""
    y = np.tile([0.0, 0.5, 1.0, 0.5], 151)[:601]
    t = _grid(601)
    o = judge_outcome("s", 4.0, _traj(t, 0 * t, y), "e")
    assert o.measured == 0.0 and o.expected == "weave grows" and o.passed is False
    assert o.evidence == ("125 peaks of |dtheta/dt| from 1 s: 1 -> 1 rad/s, envelope rate "
                          "+0.0000 /s; completed at 6.00 s")


def test_a_steady_lean_is_not_monotone_growth():
    """theta * dtheta/dt > 0 at every sample: a lean held at 1e-3 rad with dtheta/dt = 0 from
    3 s on has a product of 0, so it is not growing. Planted: theta / dtheta (+inf > 0); >= 0
    (0 counted as growing)."""
    t = _grid(601)
    assert capsize_measure(_traj(t, np.full(t.size, 1e-3), 0 * t)).monotone is False


def test_a_lean_that_does_not_grow_is_no_capsize():
    """The stage's docstring: the capsize rate must be positive. theta = 1 + 0.1 sin(2 pi t /
    0.01) sampled every 0.01 s reads theta = 1 rad rising (dtheta = 0.2 pi/0.01 > 0) at every
    sample: one sign and 'monotone' at the samples, but log|theta| = 0 throughout, rate 0: no
    capsize. Planted: rate >= 0 for rate > 0."""
    t = _grid(601)
    o = judge_outcome("s", 8.0, _traj(t, np.ones(t.size), np.full(t.size, 0.2 * np.pi / 0.01)),
                      "e")
    assert o.expected == "slow capsize" and o.measured == 0.0 and o.passed is False
    assert "keeps one sign and grows monotonically" in o.evidence


def test_slow_is_measured_over_the_runs_own_duration():
    """Slow: rate x (t_end - t0) < 1. On a 0.5 s grid: rate 0.18 /s over 0 to 6 s is 1.08,
    not slow (over 5.5 s it would be 0.99); 0.16 /s is 0.96, slow; 0.15 /s over a run from 2
    to 8 s is 0.9, slow (over t_end + t0 = 10 s it would be 1.5). Planted: the duration from
    the second sample (t_end - t[1]); t_end + t[0]."""
    def verdict(t, rate):
        theta = 1e-3 * np.exp(rate * t)
        o = judge_outcome("s", 8.0, _traj(t, theta, rate * theta), "e")
        assert o.measured == pytest.approx(rate, rel=1e-9)
        return o.passed
    t = 0.5 * np.arange(13)
    assert verdict(t, 0.18) is False and verdict(t, 0.16) is True
    assert verdict(2.0 + t, 0.15) is True


def test_the_benchmarks_upright_pitch_is_minus_pi_over_10_to_the_last_bit(bench):
    """Table 1: the steer axis is tilted by lambda = pi/10, so upright with straight steer the
    frame is pitched by -pi/10, the docstring's value, and it is that float exactly (the start
    of the solve is the answer; a solve from elsewhere stops an ulp away). Planted: the start
    +pi/10; -pi/11."""
    q = upright_state(bench)
    assert q[5] == -np.pi / 10
    assert abs(bench.constraint_residual(q, np.zeros(8))[0]) <= 1e-14


def test_a_weave_run_that_ends_before_the_envelope_window_fails_with_words():
    """A run that falls (or fails) before 1 s, the envelope's start, has no peak of
    |dtheta/dt| to measure. At 4 m/s (below the weave speed 4.29 m/s: a growing weave
    predicted) the verdict is FAIL with a NaN rate, and the evidence says there was nothing to
    measure, as the stage's table shows it, instead of stopping the whole section. Planted
    (found here, fixed): the evidence quoted the first peak, an IndexError on an empty array."""
    t = _grid(80)                                   # 0 to 0.79 s
    o = judge_outcome("s", 4.0, _traj(t, 0.1 * t, np.full(t.size, 0.1), status="fell"), "e")
    assert o.expected == "weave grows"
    assert o.passed is False and np.isnan(o.measured)
    assert o.evidence.startswith("0 peaks of |dtheta/dt| from 1 s: none to measure, ")
    assert o.evidence.endswith("; fell at 0.79 s")


def test_the_capsize_growth_factor_is_over_the_runs_own_duration():
    """The evidence's growth factor is exp(rate x duration), the same duration the slowness
    check uses: a lean growing at 0.15 /s on a run from 2 to 8 s grows by exp(0.9) = 2.46 over
    it (exp(0.15 x 8) = 3.32 would count the two seconds before the run). Planted (found here,
    fixed): the factor over t_end instead of t_end - t0."""
    t = 2.0 + 0.5 * np.arange(13)
    theta = 1e-3 * np.exp(0.15 * t)
    o = judge_outcome("s", 8.0, _traj(t, theta, 0.15 * theta), "e")
    assert f"(x{np.exp(0.9):.2f} over the run)" in o.evidence


def test_each_channel_gives_a_hankel_matrix_of_half_the_samples_plus_one_columns(monkeypatch):
    """The docstring: each channel (n samples once thinned) gives a Hankel matrix of n/2 + 1
    columns, stacked before the SVD. On exact sums of exponentials any window returns the
    exponents, so the shape is what the contract fixes: 40 samples on two channels are two
    20 x 21 blocks, a 40 x 21 matrix whose rows are the channels' windows in order. Planted:
    a window of n/2 + 2 columns (38 x 22)."""
    seen = []
    svd = np.linalg.svd

    def spy(a, *args, **kwargs):
        seen.append(np.array(a))
        return svd(a, *args, **kwargs)

    monkeypatch.setattr(np.linalg, "svd", spy)
    run = _table2_run(_grid(40, step=0.04))
    identify_eigenvalues(run, sample=0.04)
    (a,) = seen
    assert a.shape == (40, 21)
    theta = run.q[:, THETA] / np.abs(run.q[:, THETA]).max()
    assert np.array_equal(a[0], theta[:21]) and np.array_equal(a[19], theta[19:40])
