"""Judgments on the benchmark bicycle's nonlinear runs (Meijaard et al. 2007): what the
published critical speeds predict at a speed, how a run is measured against it (weave envelope,
slow capsize), and the eigenvalues identified from a run against the linearization.

How each outcome is measured, and why each tolerance has its size, is written in
`comparisons/stages/benchmark.py`'s docstring (the stage that runs the manoeuvres).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from reference_model import COORDINATES, Model
from reference_model.scenarios import Scenario
from reference_model.solvers import THETA, Trajectory, solve_beta

from .published import MEIJAARD_CAPSIZE_SPEED, MEIJAARD_WEAVE_SPEED

PUBLISHED_WEAVE_SPEED = MEIJAARD_WEAVE_SPEED       # m/s (comparisons/judgments/published.py)
PUBLISHED_CAPSIZE_SPEED = MEIJAARD_CAPSIZE_SPEED   # m/s
ENVELOPE_FROM = 1.0                # s: castor mode (<= -12 /s) down by e^-12
CAPSIZE_FROM = 3.0                 # s: weave at 8 m/s (-2.69 /s) down by e^-8
NONLINEAR_COEFFICIENT = 2.0        # tolerance K a^2 (stages/benchmark.py docstring)
FIT_FLOOR = 1e-8                   # relative: the fit's own accuracy
PENCIL_ORDER = 4                   # the roll/steer linearization's four modes
PENCIL_SAMPLE = 0.04               # s: grid of the fit (every 4th IFToMM output sample)


# -- scenarios and states --------------------------------------------------------------------

def speed_of(model: Model, scenario: Scenario) -> float:
    """Forward speed v = R_rear psi_dot(0) (m/s) of an upright benchmark scenario."""
    return float(model.params.R_rear * scenario.dq_ind0[1])


def with_roll_rate(scenario: Scenario, roll_rate: float) -> Scenario:
    """The same manoeuvre with another initial roll rate (rad/s)."""
    d = (float(roll_rate),) + tuple(scenario.dq_ind0[1:])
    return dataclasses.replace(scenario, name=f"{scenario.name}-roll{roll_rate:g}", dq_ind0=d,
                               tags=tuple(scenario.tags) + ("small-amplitude",))


def upright_state(model: Model) -> np.ndarray:
    """q at upright, straight steer: theta = gamma = 0, beta from [rD]_z = 0 (-pi/10 for the
    benchmark)."""
    q0 = np.zeros(8)
    q0[5] = -np.pi / 10
    return solve_beta(model, q0)[0]


# -- physics: how each outcome is measured ----------------------------------------------------

def expected_outcome(speed: float) -> str:
    """What the linearized benchmark predicts at ``speed`` (published critical speeds)."""
    if speed < PUBLISHED_WEAVE_SPEED:
        return "weave grows"
    if speed < PUBLISHED_CAPSIZE_SPEED:
        return "weave decays"
    return "slow capsize"


@dataclass(frozen=True)
class Envelope:
    """Peaks of |d theta/dt| from ``t_from`` on and the slope of their logarithm (1/s)."""

    t: np.ndarray
    peaks: np.ndarray
    rate: float
    t_from: float


def roll_rate_envelope(traj: Trajectory, t_from: float = ENVELOPE_FROM) -> Envelope:
    """Local maxima of |d theta/dt| (refined by a parabola through the three samples around
    each), then log(peak) = rate t + c by least squares; rate NaN with fewer than 3 peaks."""
    t, y = np.asarray(traj.t), np.abs(np.asarray(traj.dq)[:, THETA])
    k = np.flatnonzero((y[1:-1] >= y[:-2]) & (y[1:-1] > y[2:])) + 1
    k = k[t[k] >= t_from]
    a, b, c = y[k - 1], y[k], y[k + 1]
    curv = a - 2 * b + c
    off = np.where(curv < 0, 0.5 * (a - c) / np.where(curv < 0, curv, -1.0), 0.0)
    tp = t[k] + off * (t[1] - t[0])
    yp = b - 0.25 * (a - c) * off
    rate = float(np.polyfit(tp, np.log(yp), 1)[0]) if k.size >= 3 else float("nan")
    return Envelope(tp, yp, rate, float(t_from))


@dataclass(frozen=True)
class CapsizeMeasure:
    """The lean after ``t_from``: one sign and growing (monotone), at ``rate`` (1/s)."""

    t_from: float
    monotone: bool
    rate: float
    theta_end: float
    status: str


def capsize_measure(traj: Trajectory, t_from: float = CAPSIZE_FROM) -> CapsizeMeasure:
    """theta * d theta/dt > 0 at every sample from ``t_from`` on (no oscillation left, |theta|
    growing), and the slope of log|theta| there (least squares)."""
    t, th, dth = traj.t, traj.q[:, THETA], traj.dq[:, THETA]
    sel = t >= t_from
    monotone = bool(np.all(th[sel] * dth[sel] > 0))
    rate = float(np.polyfit(t[sel], np.log(np.abs(th[sel])), 1)[0]) if sel.sum() >= 3 else float("nan")
    return CapsizeMeasure(float(t_from), monotone, rate, float(th[-1]), traj.status)


@dataclass(frozen=True)
class Outcome:
    """The physics claim on one run: expected, measured, verdict and how it was measured."""

    scenario: str
    engine: str
    expected: str
    measured: float       # envelope rate (weave) or capsize rate, 1/s
    passed: bool
    evidence: str


def judge_outcome(scenario: str, speed: float, traj: Trajectory, engine: str) -> Outcome:
    """Judge the outcome the published critical speeds predict at ``speed`` (see the module
    docstring for each measure)."""
    expected = expected_outcome(speed)
    if expected in ("weave grows", "weave decays"):
        env = roll_rate_envelope(traj)
        grows = env.rate > 0
        ok = bool(np.isfinite(env.rate) and grows == (expected == "weave grows")
                  and traj.status == "completed")
        # a run that ends (falls, fails) before the envelope's window has no peak to quote
        peaks = (f"{env.peaks[0]:.3g} -> {env.peaks[-1]:.3g} rad/s" if env.peaks.size
                 else "none to measure")
        return Outcome(scenario, engine, expected, env.rate, ok,
                       f"{env.peaks.size} peaks of |dtheta/dt| from {env.t_from:g} s: "
                       f"{peaks}, envelope rate "
                       f"{env.rate:+.4f} /s; {traj.status} at {traj.t_end:.2f} s")
    cm = capsize_measure(traj)
    duration = traj.t_end - traj.t[0]
    slow = cm.rate * duration < 1.0
    ok = bool(cm.monotone and cm.rate > 0 and slow and cm.status == "completed")
    return Outcome(scenario, engine, expected, cm.rate, ok,
                   f"from {cm.t_from:g} s theta {'keeps one sign and grows monotonically' if cm.monotone else 'is NOT monotone'}"
                   f", rate of log|theta| {cm.rate:+.4f} /s (x{np.exp(cm.rate * duration):.2f} "
                   f"over the run), theta({traj.t_end:.2f} s) = {cm.theta_end:+.4f} rad; {cm.status}")


# -- nonlinear against linear: eigenvalues identified from a run -------------------------------

def identify_eigenvalues(traj: Trajectory, coords: Sequence[str] = ("theta", "gamma"),
                         order: int = PENCIL_ORDER, sample: float = PENCIL_SAMPLE) -> np.ndarray:
    """The ``order`` exponents (1/s) of the sum of exponentials that best represents the
    ``coords`` of ``traj`` (multichannel matrix pencil). The run's uniform grid is thinned to
    ``sample`` (a multiple of its step); each channel, scaled to unit peak, gives a Hankel
    matrix of n/2 + 1 columns; the matrices are stacked, truncated by SVD to ``order``, and the
    eigenvalues z of the shift pencil give lambda = log(z) / sample. The accuracy depends on
    the time spanned (n/2 samples), not on their number: the deviations from the linear
    eigenvalues on the 0.04 s grid equal those on the 0.01 s grid to a few per cent, and the SVD
    of a 126 x 64 matrix stays cheap (a 502 x 251 one took up to seconds with multi-threaded
    BLAS on a loaded 2-core machine). Sorted by decreasing imaginary part (a complex pair's
    +imag member first, its conjugate last), equal ones by decreasing real part."""
    t = np.asarray(traj.t)
    dt = float(t[1] - t[0])
    if np.abs(np.diff(t) - dt).max() > 1e-9 * dt:
        raise ValueError("identify_eigenvalues needs a uniform grid (the run's event row?)")
    stride = int(round(sample / dt))
    if stride < 1 or abs(stride * dt - sample) > 1e-9 * sample:
        raise ValueError(f"sample {sample:g} s must be a multiple of the run's step {dt:g} s")
    idx = [COORDINATES.index(c) for c in coords]
    q = np.asarray(traj.q)[::stride]
    L = q.shape[0] // 2
    if L <= order:
        raise ValueError(f"{q.shape[0]} samples are too few for {order} modes")
    blocks = []
    for j in idx:
        s = q[:, j] / (np.abs(q[:, j]).max() or 1.0)
        blocks.append(np.lib.stride_tricks.sliding_window_view(s, L + 1))
    _, _, Vt = np.linalg.svd(np.vstack(blocks), full_matrices=False)
    V = Vt[:order].T
    z = np.linalg.eigvals(np.linalg.lstsq(V[:-1], V[1:], rcond=None)[0])
    lam = np.log(z.astype(complex)) / (stride * dt)
    return lam[np.lexsort((-lam.real, -lam.imag))]


def nonlinear_tolerance(amplitude: float) -> float:
    """Relative tolerance of a fitted eigenvalue at amplitude a (rad): K a^2 + floor."""
    return NONLINEAR_COEFFICIENT * amplitude**2 + FIT_FLOOR


@dataclass(frozen=True)
class ModeFit:
    """One mode identified from a nonlinear run against the linearization at its speed."""

    scenario: str
    engine: str
    mode: str               # 'weave' | 'capsize'
    speed: float            # m/s
    roll_rate: float        # rad/s, initial
    amplitude: float        # rad: max |theta|, |gamma| over the run
    fitted: complex         # 1/s
    linear: complex         # 1/s
    deviation: float        # |fitted - linear| / |linear|
    tolerance: float


def _cx(z: complex) -> str:
    return f"{z.real:+.8f}{z.imag:+.8f}i"


def _pick(lam: np.ndarray, mode: str, linear: complex) -> complex:
    if mode == "weave":
        return complex(lam[np.argmax(lam.imag)])
    real = lam[np.abs(lam.imag) <= 1e-12 * np.abs(lam)]
    pool = real if real.size else lam
    return complex(pool[np.argmin(np.abs(pool - linear))])


def mode_fits(model: Model, scenario: Scenario, traj: Trajectory, engine: str = "reference",
              modes: Sequence[str] | None = None) -> list[ModeFit]:
    """Weave (and at speeds above the capsize speed the capsize mode) identified from ``traj``
    against `reference_model.linearize.eigenvalues` at the scenario's speed."""
    from reference_model.linearize import eigenvalues

    v = speed_of(model, scenario)
    lin = eigenvalues(model, v)
    modes = modes or (("weave", "capsize") if v > PUBLISHED_CAPSIZE_SPEED else ("weave",))
    lam = identify_eigenvalues(traj)
    amp = float(np.abs(traj.q[:, [COORDINATES.index("theta"), COORDINATES.index("gamma")]]).max())
    out = []
    for mode in modes:
        ref = complex(lin[0] if mode == "weave" else lin[2])
        fit = _pick(lam, mode, ref)
        out.append(ModeFit(scenario.name, engine, mode, v, float(scenario.dq_ind0[0]), amp, fit,
                           ref, abs(fit - ref) / abs(ref), nonlinear_tolerance(amp)))
    return out
