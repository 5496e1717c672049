"""The benchmark's judgments (comparisons/judgments/benchmark.py) on synthetic runs: what the
published critical speeds predict, the weave envelope and the slow capsize measured on signals
whose growth rates are set by hand, and the eigenvalues identified from a sum of exponentials
whose exponents are Table 2's (Meijaard et al. 2007). No simulation: the stage's real runs
are the slow tests of test_benchmark_engines.py. ~0.1 s."""

import numpy as np
import pytest

from comparisons.judgments.benchmark import (CAPSIZE_FROM, ENVELOPE_FROM, _pick,
                                             capsize_measure, expected_outcome, judge_outcome,
                                             mode_fits, nonlinear_tolerance, roll_rate_envelope,
                                             speed_of, upright_state, with_roll_rate)
from comparisons.judgments.published import (MEIJAARD_CAPSIZE_SPEED, MEIJAARD_TABLE2,
                                             MEIJAARD_WEAVE_SPEED)
from reference_model import load_model
from reference_model.scenarios import SCENARIOS
from reference_model.solvers import Trajectory

THETA = 3


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


def _traj(t, theta, dtheta, status="completed", gamma=None):
    q, dq = np.zeros((t.size, 8)), np.zeros((t.size, 8))
    q[:, THETA], dq[:, THETA] = theta, dtheta
    if gamma is not None:
        q[:, 6] = gamma
    z = np.zeros((t.size, 5))
    return Trajectory(t, q, dq, np.zeros_like(q), z, np.zeros((t.size, 3)), status, "",
                      float(t[-1]))


T6 = np.round(np.arange(0.0, 6.0 + 1e-9, 0.01), 10)


def test_the_published_speeds_divide_the_outcomes():
    w, c = MEIJAARD_WEAVE_SPEED, MEIJAARD_CAPSIZE_SPEED
    assert [expected_outcome(v) for v in (0.0, 4.0, w - 1e-9, w, 5.0, c - 1e-9, c, 8.0)] == [
        "weave grows", "weave grows", "weave grows", "weave decays", "weave decays",
        "weave decays", "slow capsize", "slow capsize"]


def test_speed_roll_rate_and_upright_state_of_the_benchmark(bench):
    sc = SCENARIOS["benchmark-v8"]
    assert speed_of(bench, sc) == pytest.approx(8.0, rel=1e-14)    # R_rear psi_dot, 0.3 x 26.67
    s = with_roll_rate(sc, 1e-3)
    assert s.name == "benchmark-v8-roll0.001" and s.dq_ind0 == (1e-3, *sc.dq_ind0[1:])
    assert s.tags == (*sc.tags, "small-amplitude") and s.grid == sc.grid
    q = upright_state(bench)
    # Table 1's bicycle upright: the frame pitched by the head angle's complement, pi/10
    assert q[5] == pytest.approx(-np.pi / 10, abs=1e-12) and q[THETA] == q[6] == 0.0
    assert abs(bench.constraint_residual(q, np.zeros(8))[0]) < 1e-14    # rD_z = 0


def test_the_envelope_rate_is_the_signals_growth_rate():
    """|d theta/dt| = |e^(s t) sin(w t)|, w = 3 pi (1.5 Hz): its peaks lie one half-period
    apart, each at the same phase, so log(peak) rises by exactly s per second; the parabola
    through three 0.01 s samples finds each peak to ~1e-5 relative (15 peaks from 1 s on:
    at (k + 1/2)/3 s, k = 3..17)."""
    for s in (-0.5, 0.3):
        env = roll_rate_envelope(_traj(T6, 0 * T6, np.exp(s * T6) * np.sin(3 * np.pi * T6)))
        assert env.rate == pytest.approx(s, abs=1e-4)
        assert env.peaks.size == 15 and env.t_from == ENVELOPE_FROM == 1.0
        assert env.t[0] >= 1.0 and env.t[0] == pytest.approx(3.5 / 3, abs=2e-2)
    # from 5.5 s: the peaks at 5.5 s itself (from, inclusive) and 5.83 s; two are too few
    few = roll_rate_envelope(_traj(T6, 0 * T6, np.sin(3 * np.pi * T6)), t_from=5.5)
    assert few.t.tolist() == pytest.approx([5.5, 17.5 / 3], abs=1e-5) and np.isnan(few.rate)


def test_the_capsize_is_measured_monotone_and_at_its_rate():
    theta = 1e-3 * np.exp(0.15 * T6)
    cm = capsize_measure(_traj(T6, theta, 0.15 * theta))
    assert cm.monotone is True and cm.t_from == CAPSIZE_FROM == 3.0
    assert cm.rate == pytest.approx(0.15, rel=1e-9)      # a least-squares line through a line
    assert cm.theta_end == theta[-1] and cm.status == "completed"
    wobbly = theta * (1 + 0.5 * np.sin(20 * T6))
    assert capsize_measure(_traj(T6, wobbly, np.gradient(wobbly, T6))).monotone is False
    # an oscillation before 3 s does not count
    early = np.where(T6 < 2.9, -theta, theta)
    assert capsize_measure(_traj(T6, early, np.where(T6 < 2.9, -1, 1) * 0.15 * theta)).monotone


def test_judge_outcome_on_each_prediction():
    grow = np.exp(0.3 * T6) * np.sin(3 * np.pi * T6)
    decay = np.exp(-0.5 * T6) * np.sin(3 * np.pi * T6)
    o = judge_outcome("s", 4.0, _traj(T6, 0 * T6, grow), "reference")
    assert (o.scenario, o.engine, o.expected, o.passed) == ("s", "reference", "weave grows", True)
    assert o.measured == pytest.approx(0.3, abs=1e-4)
    assert o.evidence.startswith("15 peaks of |dtheta/dt| from 1 s: ")
    assert "envelope rate +0.3000 /s; completed at 6.00 s" in o.evidence
    assert judge_outcome("s", 4.0, _traj(T6, 0 * T6, decay), "e").passed is False
    assert judge_outcome("s", 5.0, _traj(T6, 0 * T6, decay), "e").passed is True
    assert judge_outcome("s", 5.0, _traj(T6, 0 * T6, grow), "e").passed is False
    assert judge_outcome("s", 5.0, _traj(T6, 0 * T6, decay, status="fell"), "e").passed is False
    # the capsize at 8 m/s: growing monotonically and slowly (rate x duration < 1)
    slow = 1e-3 * np.exp(0.15 * T6)            # 0.15 x 6 s = 0.9
    o = judge_outcome("s", 8.0, _traj(T6, slow, 0.15 * slow), "e")
    assert (o.expected, o.passed) == ("slow capsize", True)
    assert o.measured == pytest.approx(0.15, rel=1e-9)
    assert "keeps one sign and grows monotonically" in o.evidence and o.evidence.endswith(
        "; completed")
    fast = 1e-3 * np.exp(0.2 * T6)             # 0.2 x 6 s = 1.2: not slow
    assert judge_outcome("s", 8.0, _traj(T6, fast, 0.2 * fast), "e").passed is False
    decaying = 1e-3 * np.exp(-0.2 * T6)        # one sign but shrinking: not monotone growth
    o = judge_outcome("s", 8.0, _traj(T6, decaying, -0.2 * decaying), "e")
    assert o.passed is False and "is NOT monotone" in o.evidence
    assert judge_outcome("s", 8.0, _traj(T6, slow, 0.15 * slow, status="fell"), "e").passed \
        is False


def test_the_nonlinear_tolerance_and_the_mode_picked():
    assert nonlinear_tolerance(1e-2) == pytest.approx(2e-4 + 1e-8, rel=1e-15)
    lam = np.array([-2 + 8j, -2 - 8j, 0.14, -20.0])
    assert _pick(lam, "weave", -2 + 8j) == -2 + 8j
    assert _pick(lam, "capsize", 0.1) == 0.14 and _pick(lam, "capsize", -19) == -20.0
    pairs = np.array([-2 + 8j, -2 - 8j, 0.1 + 1j, 0.1 - 1j])     # no real one: any nearest
    assert _pick(pairs, "capsize", 0.1 - 0.9j) == 0.1 - 1j


def test_mode_fits_find_table2s_modes_in_a_sum_of_its_exponentials(bench):
    """At 8 m/s (above the capsize speed) theta and gamma made of Table 2's four modes
    (weave -2.69 +- 8.46i, capsize +0.143, castor -20.3 /s): the pencil gives them back, so
    the weave and the capsize fitted equal the linearization's at 8 m/s to the pencil's
    accuracy on exact exponentials (~1e-9 relative, 1e-7 allowed) and the linearization's
    own match to Table 2 (1e-10 /s, test_benchmark.py)."""
    re, im, cap, cas = MEIJAARD_TABLE2[8]
    t = np.round(np.arange(0.0, 5.0 + 1e-9, 0.01), 10)
    theta = 1e-3 * (np.exp(re * t) * np.cos(im * t) + 0.5 * np.exp(cap * t)
                    + 0.3 * np.exp(cas * t))
    gamma = 1e-3 * (0.7 * np.exp(re * t) * np.sin(im * t) - 0.2 * np.exp(cap * t)
                    + 0.4 * np.exp(cas * t))
    sc = with_roll_rate(SCENARIOS["benchmark-v8"], 2e-3)
    fits = mode_fits(bench, sc, _traj(t, theta, 0 * t, gamma=gamma), engine="e")
    assert [f.mode for f in fits] == ["weave", "capsize"]
    weave, capsize = fits
    assert weave.linear == pytest.approx(complex(re, im), abs=1e-10)
    assert capsize.linear == pytest.approx(cap, abs=1e-10)
    for f in fits:
        assert (f.scenario, f.engine, f.speed, f.roll_rate) == (sc.name, "e", 8.0, 2e-3)
        assert f.deviation < 1e-7 and f.deviation == abs(f.fitted - f.linear) / abs(f.linear)
        assert f.amplitude == np.abs(np.stack([theta, gamma])).max()
        assert f.tolerance == nonlinear_tolerance(f.amplitude)
    # below the capsize speed only the weave is fitted
    sc = SCENARIOS["benchmark-v4.6"]
    assert [f.mode for f in mode_fits(bench, sc, _traj(t, theta, 0 * t, gamma=gamma))] == \
        ["weave"]


def test_the_evidence_says_what_was_measured():
    """The evidence strings with their numbers, from the synthetic signals: the first and last
    of 15 peaks of e^(s t) |sin(w t)| (s = 0.3, w = 3 pi): d/dt = 0 at t_k + d, d = atan(s/w)/w
    after t_k = 7/6 and 35/6 s, where the value is e^(s (t_k + d)) cos(atan(s/w)); and a capsize
    growing by e^(0.15 x 6) = x2.46 over the run."""
    s_, w = 0.3, 3 * np.pi
    d, c = np.arctan(s_ / w) / w, np.cos(np.arctan(s_ / w))
    first, last = (np.exp(s_ * (tk + d)) * c for tk in (7 / 6, 35 / 6))
    grow = np.exp(s_ * T6) * np.sin(w * T6)
    o = judge_outcome("s", 4.0, _traj(T6, 0 * T6, grow), "e")
    assert o.evidence == (f"15 peaks of |dtheta/dt| from 1 s: {first:.3g} -> {last:.3g} rad/s, "
                          "envelope rate +0.3000 /s; completed at 6.00 s")
    slow = 1e-3 * np.exp(0.15 * T6)
    o = judge_outcome("cap", 8.0, _traj(T6, slow, 0.15 * slow), "eng")
    assert (o.scenario, o.engine) == ("cap", "eng")
    assert o.evidence == ("from 3 s theta keeps one sign and grows monotonically, rate of "
                          f"log|theta| +0.1500 /s (x{np.exp(0.9):.2f} over the run), "
                          f"theta(6.00 s) = +{slow[-1]:.4f} rad; completed")
    wob = slow * (1 + 0.5 * np.sin(20 * T6))
    o = judge_outcome("cap", 8.0, _traj(T6, wob, np.gradient(wob, T6)), "eng")
    assert o.evidence.startswith("from 3 s theta is NOT monotone, ")
    # a run ending 0.01 s after 3 s has two samples there: too few for a rate
    t = T6[T6 <= 3.01 + 1e-9]
    assert np.isnan(capsize_measure(_traj(t, 1e-3 * np.exp(0.15 * t), 0.15e-3 * np.exp(
        0.15 * t))).rate)
    t3 = T6[T6 <= 3.02 + 1e-9]                      # three samples: a rate
    assert capsize_measure(_traj(t3, 1e-3 * np.exp(0.15 * t3), 0.15e-3 * np.exp(0.15 * t3))
                           ).rate == pytest.approx(0.15, rel=1e-6)
