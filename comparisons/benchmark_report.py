"""The benchmark bicycle (Meijaard et al. 2007) in the engines and in nonlinear runs: the report
section of issue 6's engine part.

    from comparisons.benchmark_report import benchmark_section
    section = benchmark_section(Path("reports/latest"), quick=False, progress=print)

Three parts, all on ``load_model("benchmark")`` (true disc front contact, cv = 0):

(a) **Terms.** Pinocchio and Exudyn's kinematic tree against the reference at deterministic
    random states (`comparisons.terms`, tolerances from `tolerances.toml`) and M at the upright
    configuration (theta = gamma = 0, beta = -pi/10 solved from the contact).

(b) **The IFToMM "uncontrolled bicycle" manoeuvres** (scenarios ``benchmark-v4``,
    ``benchmark-v4.6``, ``benchmark-v8``: 4, 4.6 and 8 m/s with roll rates 0.05, 0.5 and 0.05
    rad/s, no torques; 5 s with output every 0.01 s as in Exudyn's implementation of the IFToMM
    problem, ``Examples/bicycleIftommBenchmark.py``: tEnd = 5, sensors every 0.01 s, outputs roll
    angle and rate, forward speed, potential, kinetic and mechanical energy, steer angle and
    rate; an older revision of that file ran 20 s). Each on the reference (DOP853, rtol 1e-11,
    projection) and on Exudyn (tree and redundant builds, h = 1e-3):

    * the error against time up to the meaningful horizon (`convergence.reference_horizon`),
      reported; on ``benchmark-v4.6`` (full run only) the tree's convergence order judges it;
    * the constraint residual of every run (tolerance ``constraint_residual``);
    * the IFToMM energy drift 100 (Emax - Emin) / |E0| % over the 0.01 s output samples
      (`comparisons.energy`), judged against IFToMM's acceptance of 1e-3 % (the criterion
      printed by Exudyn's implementation, "must be < 1e-3");
    * the physics, judged against the published critical speeds (weave 4.29238 m/s, capsize
      6.02426 m/s): below the weave speed the weave grows, between the two it decays, above
      the capsize speed the bicycle capsizes slowly. How each is measured:
      - *weave grows / decays*: the peaks of |d theta/dt| from t = 1 s on (the castor mode,
        -12 /s and faster, is gone by then) and the slope of log(peak) against t by least squares:
        the envelope rate, > 0 grows, < 0 decays;
      - *slow capsize*: from t = 3 s on (the weave, decaying at -2.69 /s, is down by e^-8)
        theta keeps one sign and |theta| grows monotonically (theta * d theta/dt > 0 at every
        sample), at a rate sigma (slope of log|theta|) that is positive and slow,
        sigma * 5 s < 1 (less than a factor e over the whole run), and the run does not fall.

(c) **Nonlinear against linear.** The four non-trivial eigenvalues are identified from the
    nonlinear runs by the matrix-pencil method (theta and gamma on a 0.04 s grid, model order
    4: the linearized roll/steer system has exactly four modes) and compared with
    `reference_model.linearize.eigenvalues` at the run's speed: the weave at every speed, the
    capsize at 8 m/s (where it dominates; at 4 and 4.6 m/s it decays under a larger weave and is
    poorly determined). The runs are the IFToMM manoeuvres and the same manoeuvres with roll
    rates of 1e-3 and 1e-2 rad/s. Tolerance: relative deviation <= 2 a^2 + 1e-8 with a the
    largest |theta| or |gamma| of the run (rad). Why: the nonlinear terms left out by the
    linearization are the cubic remainders of the sines and cosines of roll and steer and
    products of three small quantities, so relative to the linear terms they are of order a^2
    with an O(1) coefficient (sin a = a (1 - a^2/6), a pendulum's frequency shifts by a^2/16);
    2 bounds the sum of several (measured: 0.75 to 1.1); 1e-8 is the floor of the fit (reference
    rtol 1e-11, amplified by the pencil's conditioning, its 4th singular value 1e-3 to 1e-2 of
    the 1st). And the deviation must *be* the nonlinearity: between the 1e-3 and 1e-2 rad/s
    runs it must scale as a^order with order in [1.8, 2.2] (a model difference would not vanish
    with the amplitude). Exudyn's fits on the IFToMM runs are compared with the reference's fits
    on the same runs (the nonlinearity cancels): tolerance 1e-4 relative, the relative error of
    a second-order scheme in a mode's frequency and damping, O((omega h)^2) = (8.5e-3)^2 = 7e-5
    for the weave at 8 m/s and h = 1e-3.

Plus the eigenvalues-against-speed figure (`comparisons.eigenvalues.eigenvalue_figure`).
Every comparison is a dict (quantity, scenario, model, engines, max_error, tolerance, passed,
localized_to, note) as in `engine_report`; outcome checks carry ``measured`` and ``expected``.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from engines import load_engine
from reference_model import COORDINATES, Model, load_model
from reference_model.scenarios import SCENARIOS, Scenario
from reference_model.solvers import THETA, Trajectory, solve_beta

from .convergence import (DEFAULT_STEPS, Horizon, convergence_study, error_vs_time,
                          reference_horizon, reference_run)
from .energy import energy_drift
from .engine_report import Section, _md, _savefig
from .published import MEIJAARD_CAPSIZE_SPEED, MEIJAARD_WEAVE_SPEED
from .terms import States, compare_terms, random_states
from .tolerances import load_tolerances

__all__ = [
    "MODEL", "MANOEUVRES", "PUBLISHED_WEAVE_SPEED", "PUBLISHED_CAPSIZE_SPEED",
    "IFTOMM_DRIFT_PERCENT", "CapsizeMeasure", "Envelope", "ManoeuvreRuns", "ModeFit", "Outcome",
    "benchmark_section", "capsize_measure", "expected_outcome", "identify_eigenvalues",
    "judge_outcome", "mode_fits", "nonlinear_tolerance", "roll_rate_envelope", "run_manoeuvres",
    "speed_of", "upright_state", "with_roll_rate",
]

MODEL = "benchmark"
MANOEUVRES = ("benchmark-v4", "benchmark-v4.6", "benchmark-v8")
EXUDYN_STEP = 1e-3                 # s: divides the IFToMM output interval 0.01 s
BUILDS = ("tree", "redundant")
QUICK_BUILDS = ("tree",)
# Meijaard et al. (2007), section 7 / Table 2: the linearized benchmark is self-stable between
PUBLISHED_WEAVE_SPEED = MEIJAARD_WEAVE_SPEED       # m/s (comparisons/published.py)
PUBLISHED_CAPSIZE_SPEED = MEIJAARD_CAPSIZE_SPEED   # m/s
IFTOMM_DRIFT_PERCENT = 1e-3        # %: IFToMM acceptance (the report reads tolerances.toml)
ENVELOPE_FROM = 1.0                # s: castor mode (<= -12 /s) down by e^-12
CAPSIZE_FROM = 3.0                 # s: weave at 8 m/s (-2.69 /s) down by e^-8
SMALL_ROLL_RATES = (1e-3, 1e-2)    # rad/s: small-amplitude twins of every manoeuvre
NONLINEAR_COEFFICIENT = 2.0        # tolerance K a^2 (module docstring)
FIT_FLOOR = 1e-8                   # relative: the fit's own accuracy
ORDER_BAND = (1.8, 2.2)            # the deviation's order in the amplitude
PENCIL_ORDER = 4                   # the roll/steer linearization's four modes
PENCIL_SAMPLE = 0.04               # s: grid of the fit (every 4th IFToMM output sample)
CONVERGENCE_SCENARIO = "benchmark-v4.6"
CONVERGENCE_HORIZON = 2.0          # s: keeps the four-step study near 1 s of wall time
EIGENVALUE_SPEEDS = (0.0, 10.0, 0.01)   # m/s: start, stop, step of the figure


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
        return Outcome(scenario, engine, expected, env.rate, ok,
                       f"{env.peaks.size} peaks of |dtheta/dt| from {env.t_from:g} s: "
                       f"{env.peaks[0]:.3g} -> {env.peaks[-1]:.3g} rad/s, envelope rate "
                       f"{env.rate:+.4f} /s; {traj.status} at {traj.t_end:.2f} s")
    cm = capsize_measure(traj)
    slow = cm.rate * (traj.t_end - traj.t[0]) < 1.0
    ok = bool(cm.monotone and cm.rate > 0 and slow and cm.status == "completed")
    return Outcome(scenario, engine, expected, cm.rate, ok,
                   f"from {cm.t_from:g} s theta {'keeps one sign and grows monotonically' if cm.monotone else 'is NOT monotone'}"
                   f", rate of log|theta| {cm.rate:+.4f} /s (x{np.exp(cm.rate * traj.t_end):.2f} "
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
    BLAS on a loaded 2-core machine). Sorted: complex with +imag first, then by decreasing
    real part."""
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


# -- the runs ----------------------------------------------------------------------------------

@dataclass
class ManoeuvreRuns:
    """One manoeuvre on the reference and on the Exudyn builds."""

    scenario: Scenario
    speed: float
    reference: Trajectory
    horizon: Horizon
    exudyn: dict[str, Trajectory] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)


def run_manoeuvres(model: Model, names: Sequence[str] = MANOEUVRES,
                   builds: Sequence[str] = BUILDS, step: float = EXUDYN_STEP,
                   progress: Callable[[str], None] = lambda s: None) -> list[ManoeuvreRuns]:
    """Each manoeuvre on the reference (DOP853 rtol 1e-11, projection) with its horizon (one
    twin run), and on each Exudyn build at ``step``."""
    out = []
    for name in names:
        sc = SCENARIOS[name]
        progress(f"  benchmark {name}: reference, twin, Exudyn {', '.join(builds)} ...")
        t0 = time.perf_counter()
        ref = reference_run(model, sc)
        hor = reference_horizon(model, sc, reference=ref)
        runs = ManoeuvreRuns(sc, speed_of(model, sc), ref, hor,
                             seconds={"reference + twin": time.perf_counter() - t0})
        for build in builds:
            t0 = time.perf_counter()
            runs.exudyn[build] = load_engine("exudyn", model, build=build, step=step).simulate(sc)
            runs.seconds[f"exudyn {build}"] = time.perf_counter() - t0
        out.append(runs)
    return out


# -- the section -------------------------------------------------------------------------------

def _terms_part(sec: Section, model: Model, quick: bool, progress) -> None:
    n_pin, n_exu = (50, 20) if quick else (200, 100)
    progress("  benchmark terms: Pinocchio and Exudyn tree against the reference ...")
    ref = load_engine("reference", model)
    engines = {"pinocchio": load_engine("pinocchio", model),
               "exudyn-tree": load_engine("exudyn", model, build="tree")}
    q_up = upright_state(model)
    upright = States(q_up[None, :], np.zeros((1, 8)), np.zeros((1, 8)), np.zeros((1, 3)))
    sec.lines += ["### Terms", "",
                  f"Deterministic random states (large lean, steer near ±π/2, rates up to 20 "
                  f"rad/s; {n_pin} for Pinocchio, {n_exu} for Exudyn's tree) and M at the upright "
                  f"configuration (beta = {q_up[5]:+.15f} rad, -π/10 = {-np.pi / 10:+.15f}).", "",
                  "| engine | states | quantity | max error | tolerance | verdict | worst entry |",
                  "|---|---|---|---|---|---|---|"]
    for label, eng in engines.items():
        n = n_pin if label == "pinocchio" else n_exu
        for states, where, quantities in ((random_states(n, seed=7), f"random-states-{n}", None),
                                          (upright, "upright", ("mass_matrix",))):
            for r in compare_terms(ref, eng, states, quantities):
                sec.lines.append(f"| {label} | {where} | {r.quantity} | {r.max_error:.1e} | "
                                 f"{r.tolerance:.0e} | {'pass' if r.passed else 'FAIL'} | "
                                 f"{_md(r.worst_entry)} |")
                sec.comparisons.append({
                    "quantity": r.quantity, "scenario": where, "model": model.name,
                    "engines": ["reference", label], "max_error": r.max_error,
                    "tolerance": r.tolerance, "passed": r.passed, "localized_to": r.worst_entry})
    sec.lines.append("")


def _manoeuvre_part(sec: Section, out: Path, model: Model, runs: list[ManoeuvreRuns]) -> None:
    import matplotlib.pyplot as plt

    tols = load_tolerances()
    c_tol = tols["constraint_residual"].tolerance
    drift_tol = tols["iftomm_energy_drift"].tolerance
    sec.lines += [
        "### IFToMM uncontrolled bicycle: reference against Exudyn", "",
        "5 s, output every 0.01 s (IFToMM). Reference: DOP853 rtol 1e-11, projection. Exudyn: "
        f"h = {EXUDYN_STEP:g}, generalized-alpha (spectral radius 0.9). Errors in all eight "
        "coordinates up to the horizon where two reference runs 1e-9 rad/s apart in "
        "theta_dot(0) separate by 1e-6; reported, not judged (the convergence check below "
        "judges them). Energy drift 100 (Emax - Emin)/|E0| over the 0.01 s output, judged "
        f"against IFToMM's acceptance {drift_tol:g} % (stricter than the generic "
        "`tolerances.toml` [energy_drift], which bounds any second-order run at h = 1e-3); "
        f"constraint residual against [constraint_residual] {c_tol:g}.", "",
        "| scenario | v [m/s] | engine | status | horizon [s] | max error up to horizon | first > 1e-6 | max abs C | drift [% of E0] |",
        "|---|---|---|---|---|---|---|---|---|"]
    fig_r, axes_r = plt.subplots(len(runs), 1, figsize=(7.5, 2.4 * len(runs)), sharex=True,
                                 squeeze=False)
    fig_e, axes_e = plt.subplots(len(runs), 1, figsize=(7.5, 2.4 * len(runs)), sharex=True,
                                 squeeze=False)
    for k, mr in enumerate(runs):
        name, ref = mr.scenario.name, mr.reference
        engines = {"reference": ref, **{f"exudyn-{b}": tr for b, tr in mr.exudyn.items()}}
        ax = axes_r[k, 0]
        for label, tr in engines.items():
            style = {"reference": dict(color="k", lw=1.6), "exudyn-tree": dict(color="tab:orange", ls="--", lw=1.1),
                     "exudyn-redundant": dict(color="tab:blue", ls=":", lw=1.1)}[label]
            ax.plot(tr.t, tr.q[:, THETA], label=label, **style)
            drift = energy_drift(model, tr)
            Cmax = float(np.abs(tr.C).max())
            if label == "reference":
                worst, first = "-", "-"
            else:
                err = error_vs_time(ref, tr, coords=COORDINATES, horizon=mr.horizon.t)
                worst = f"{err['max'].max():.2e}"
                over = np.flatnonzero(err["max"] > 1e-6)
                first = "-"
                if over.size:
                    i = int(over[0])
                    first = f"{max(COORDINATES, key=lambda c: err[c][i])} at {err['t'][i]:.2f} s"
                sec.comparisons.append({
                    "quantity": "trajectory (benchmark)", "scenario": name, "model": model.name,
                    "engines": ["reference", label], "max_error": float(err["max"].max()),
                    "tolerance": None, "passed": None, "horizon": mr.horizon.t,
                    "horizon_reason": mr.horizon.reason, "localized_to": first,
                    "note": "reported, not judged: integrator error at h = 1e-3 (see the "
                            "convergence check)"})
                color = {"exudyn-tree": "tab:orange", "exudyn-redundant": "tab:blue"}[label]
                axes_e[k, 0].semilogy(err["t"], np.maximum(err["theta"], 1e-16), "-", color=color,
                                      lw=0.9, label=f"{label}: theta")
                axes_e[k, 0].semilogy(err["t"], np.maximum(err["max"], 1e-16), ":", color=color,
                                      lw=1.1, label=f"{label}: max over q")
            sec.lines.append(f"| {name} | {mr.speed:g} | {label} | {tr.status} | {mr.horizon.t:.2f} | "
                             f"{worst} | {first} | {Cmax:.1e} | {drift['drift_percent']:.2e} |")
            sec.comparisons.append({
                "quantity": "constraint_residual", "scenario": name, "model": model.name,
                "engines": [label], "max_error": Cmax, "tolerance": c_tol,
                "passed": bool(Cmax <= c_tol), "localized_to": "max |C| over the run"})
            sec.comparisons.append({
                "quantity": "energy drift percent (IFToMM)", "scenario": name,
                "model": model.name, "engines": [label], "max_error": drift["drift_percent"],
                "tolerance": drift_tol,
                "passed": bool(drift["drift_percent"] <= drift_tol),
                "localized_to": f"Emax at {drift['t_Emax']:.2f} s, Emin at {drift['t_Emin']:.2f} s",
                "note": (f"100 (Emax - Emin)/|E0| over the 0.01 s output, E0 = {drift['E0']:.3f} J "
                         f"(ground as zero of V), E_end - E0 = {drift['E_end_minus_E0']:+.2e} J")})
        ax.set_ylabel("theta [rad]")
        ax.set_title(f"{name}: v = {mr.speed:g} m/s, roll rate {mr.scenario.dq_ind0[0]:g} rad/s "
                     f"({expected_outcome(mr.speed)})", fontsize=9)
        ax.grid(True, lw=0.3)
        if k == 0:
            ax.legend(fontsize=7)
    axes_r[-1, 0].set_xlabel("t [s]")
    _savefig(fig_r, out, "benchmark_roll.png", sec)
    for k, mr in enumerate(runs):
        ax = axes_e[k, 0]
        ax.axhline(1e-6, color="grey", lw=0.8)
        ax.set_ylim(bottom=1e-12)
        ax.set_ylabel("|exudyn - ref|\n[rad, m]")
        ax.set_title(f"{mr.scenario.name}: Exudyn (h = {EXUDYN_STEP:g}) against the reference up "
                     f"to the horizon ({mr.horizon.t:.2f} s)", fontsize=9)
        ax.grid(True, lw=0.3)
        if k == 0:
            ax.legend(fontsize=7, ncol=2)
    axes_e[-1, 0].set_xlabel("t [s]")
    _savefig(fig_e, out, "benchmark_error.png", sec)
    sec.lines += ["", "Initial states (projected once, used by every engine): " + "; ".join(
        f"{mr.scenario.name}: {_md(mr.reference.settings['initial_correction'])}" for mr in runs), ""]


def _outcome_part(sec: Section, model: Model, runs: list[ManoeuvreRuns]) -> list[Outcome]:
    sec.lines += [
        "### Physics: weave and capsize", "",
        f"Expected from the published critical speeds (weave {PUBLISHED_WEAVE_SPEED} m/s, capsize "
        f"{PUBLISHED_CAPSIZE_SPEED} m/s). Weave: slope of log of the peaks of |dtheta/dt| from "
        f"{ENVELOPE_FROM:g} s on (> 0 grows, < 0 decays). Capsize: from {CAPSIZE_FROM:g} s on "
        "theta keeps one sign and |theta| grows monotonically, at a rate sigma with sigma * 5 s < 1 "
        "(slow), no fall. The linear weave real part / capsize eigenvalue is given beside.", "",
        "| scenario | engine | expected | measured rate [1/s] | linear [1/s] | verdict | how |",
        "|---|---|---|---|---|---|---|"]
    from reference_model.linearize import eigenvalues

    outcomes = []
    for mr in runs:
        lin = eigenvalues(model, mr.speed)
        for label, tr in {"reference": mr.reference,
                          **{f"exudyn-{b}": t for b, t in mr.exudyn.items()}}.items():
            o = judge_outcome(mr.scenario.name, mr.speed, tr, label)
            outcomes.append(o)
            linear = lin[2].real if o.expected == "slow capsize" else lin[0].real
            sec.lines.append(f"| {o.scenario} | {label} | {o.expected} | {o.measured:+.4f} | "
                             f"{linear:+.4f} | {'pass' if o.passed else 'FAIL'} | {_md(o.evidence)} |")
            sec.comparisons.append({
                "quantity": f"outcome: {o.expected}", "scenario": o.scenario, "model": model.name,
                "engines": [label], "max_error": None, "tolerance": None, "passed": o.passed,
                "measured": o.measured, "expected": o.expected, "linear": float(linear),
                "localized_to": "-", "note": o.evidence})
    sec.lines.append("")
    return outcomes


def _nonlinear_part(sec: Section, out: Path, model: Model, runs: list[ManoeuvreRuns],
                    progress) -> None:
    import matplotlib.pyplot as plt

    progress("  benchmark nonlinear vs linear: small-amplitude runs and eigenvalue fits ...")
    sec.lines += [
        "### Nonlinear against linear", "",
        "Eigenvalues identified from the nonlinear runs (matrix pencil on theta and gamma, 0.04 s "
        "grid, order 4) against the linearization at the run's speed. Tolerance on the relative deviation: "
        f"{NONLINEAR_COEFFICIENT:g} a² + {FIT_FLOOR:.0e}, a = max |theta|, |gamma| of the run "
        "(the terms the linearization drops are O(a²) relative; the floor is the fit's "
        "accuracy). Between the two small amplitudes the deviation must scale as a^order with "
        f"order in [{ORDER_BAND[0]}, {ORDER_BAND[1]}]: it is the nonlinearity, not a model "
        "difference.", "",
        "| scenario | engine | mode | a [rad] | fitted [1/s] | linear [1/s] | rel. deviation | tolerance | verdict |",
        "|---|---|---|---|---|---|---|---|---|"]
    fits: list[ModeFit] = []
    by_speed: dict[str, list[ModeFit]] = {}
    exudyn_rows = []
    for mr in runs:
        group = []
        for rate in SMALL_ROLL_RATES:
            sc = with_roll_rate(mr.scenario, rate)
            group += mode_fits(model, sc, reference_run(model, sc))
        group += mode_fits(model, mr.scenario, mr.reference)
        by_speed[mr.scenario.name] = group
        fits += group
        ref_weave = next(f for f in group if f.mode == "weave" and f.scenario == mr.scenario.name)
        for build, tr in mr.exudyn.items():
            f = mode_fits(model, mr.scenario, tr, engine=f"exudyn-{build}", modes=("weave",))[0]
            exudyn_rows.append((f, ref_weave, abs(f.fitted - ref_weave.fitted) / abs(ref_weave.fitted)))
    for f in fits:
        ok = f.deviation <= f.tolerance
        sec.comparisons.append({
            "quantity": f"{f.mode} eigenvalue, nonlinear fit vs linear", "scenario": f.scenario,
            "model": model.name, "engines": ["reference (nonlinear)", "linearize"],
            "max_error": f.deviation, "tolerance": f.tolerance, "passed": bool(ok),
            "localized_to": f"a = {f.amplitude:.2e} rad",
            "note": f"fitted {f.fitted:.10f} /s, linear {f.linear:.10f} /s"})
        sec.lines.append(f"| {f.scenario} | {f.engine} | {f.mode} | {f.amplitude:.2e} | "
                         f"{_cx(f.fitted)} | {_cx(f.linear)} | {f.deviation:.2e} | "
                         f"{f.tolerance:.1e} | {'pass' if ok else 'FAIL'} |")
    fit_tol = load_tolerances()["benchmark_weave_fit"].tolerance
    sec.lines += ["", "Exudyn's weave fits on the IFToMM runs against the reference's fit on the "
                  f"same run (the nonlinearity cancels); tolerance {fit_tol:.0e} "
                  "relative, the O((omega h)^2) error of the integrator at h = 1e-3:", "",
                  "| scenario | engine | fitted [1/s] | reference fit [1/s] | rel. difference | verdict |",
                  "|---|---|---|---|---|---|"]
    for f, r, dev in exudyn_rows:
        ok = dev <= fit_tol
        sec.lines.append(f"| {f.scenario} | {f.engine} | {_cx(f.fitted)} | {_cx(r.fitted)} | "
                         f"{dev:.1e} | {'pass' if ok else 'FAIL'} |")
        sec.comparisons.append({
            "quantity": "weave eigenvalue fit, exudyn vs reference (same run)",
            "scenario": f.scenario, "model": model.name,
            "engines": ["reference", f.engine], "max_error": dev,
            "tolerance": fit_tol, "passed": bool(ok),
            "localized_to": f"fitted {_cx(f.fitted)} vs {_cx(r.fitted)} /s",
            "note": "same amplitude, so the nonlinearity cancels; (omega h)^2 integrator error"})
    sec.lines += ["", "| speed | mode | deviation at roll rate 1e-3 / 1e-2 | order in a | verdict |",
                  "|---|---|---|---|---|"]
    fig, ax = plt.subplots(figsize=(6, 4))
    for name, group in by_speed.items():
        for mode in ("weave", "capsize"):
            g = [f for f in group if f.mode == mode]
            if not g:
                continue
            small = [f for f in g if f.roll_rate in SMALL_ROLL_RATES]
            a = np.array([f.amplitude for f in small])
            d = np.array([f.deviation for f in small])
            order = float(np.log(d[1] / d[0]) / np.log(a[1] / a[0]))
            ok = ORDER_BAND[0] <= order <= ORDER_BAND[1]
            sec.lines.append(f"| {g[0].speed:g} m/s | {mode} | {d[0]:.2e} / {d[1]:.2e} | "
                             f"{order:.3f} | {'pass' if ok else 'FAIL'} |")
            sec.comparisons.append({
                "quantity": f"{mode} eigenvalue deviation: order in the amplitude",
                "scenario": name, "model": model.name, "engines": ["reference (nonlinear)", "linearize"],
                "max_error": abs(order - 2.0), "tolerance": ORDER_BAND[1] - 2.0,
                "passed": bool(ok), "order": order, "localized_to": "-",
                "note": f"a = {a[0]:.2e}, {a[1]:.2e} rad; deviation {d[0]:.2e}, {d[1]:.2e}"})
            ax.loglog([f.amplitude for f in g], [f.deviation for f in g], "o-",
                      label=f"{g[0].speed:g} m/s {mode}: order {order:.2f}")
    aa = np.logspace(-4.5, -0.7, 20)
    ax.loglog(aa, NONLINEAR_COEFFICIENT * aa**2 + FIT_FLOOR, "k--", lw=0.8,
              label=f"tolerance {NONLINEAR_COEFFICIENT:g} a² + {FIT_FLOOR:.0e}")
    ax.set_xlabel("amplitude a = max |theta|, |gamma| [rad]")
    ax.set_ylabel("|fitted - linear| / |linear|")
    ax.set_title("eigenvalues from nonlinear runs against the linearization")
    ax.legend(fontsize=7)
    _savefig(fig, out, "benchmark_nonlinear.png", sec)
    sec.lines.append("")


def _convergence_part(sec: Section, model: Model, progress) -> None:
    progress(f"  benchmark convergence: exudyn tree on {CONVERGENCE_SCENARIO} ...")
    sc = SCENARIOS[CONVERGENCE_SCENARIO]
    study = convergence_study(model, lambda h: load_engine("exudyn", model, build="tree", step=h),
                              sc, steps=DEFAULT_STEPS, horizon=CONVERGENCE_HORIZON)
    ok = study.verdict == "converges"
    sec.lines += ["### Exudyn convergence on the benchmark", "", study.describe(), ""]
    sec.comparisons.append({
        "quantity": "convergence order", "scenario": sc.name, "model": model.name,
        "engines": ["reference", "exudyn-tree"], "max_error": study.difference, "tolerance": None,
        "order": study.order, "steps": list(study.steps), "errors": list(study.errors),
        "verdict": study.verdict, "expected": "converges", "passed": ok,
        "localized_to": f"worst coordinate {study.worst[-1]}", "reason": study.verdict_reason})


def _eigenvalue_part(sec: Section, out: Path, model: Model) -> None:
    """Linear eigenvalues and critical speeds against Meijaard et al. (2007) Table 2, and the
    eigenvalues-against-speed figure."""
    from reference_model.linearize import capsize_speed, eigenvalues, weave_speed
    from .eigenvalues import eigenvalue_figure
    from .published import (MEIJAARD_CAPSIZE_SPEED, MEIJAARD_TABLE2, MEIJAARD_WEAVE_SPEED,
                            table2_eigenvalues)
    from .tolerances import load_tolerances
    tols = load_tolerances()
    err, worst = 0.0, "-"
    for v in MEIJAARD_TABLE2:
        e = float(np.abs(eigenvalues(model, float(v)) - table2_eigenvalues(v)).max())
        if e > err:
            err, worst = e, f"v = {v} m/s"
    tol = tols["benchmark_eigenvalues"]
    sec.comparisons.append({
        "quantity": "eigenvalues vs Meijaard 2007 Table 2", "scenario": "benchmark upright, v = 0..10",
        "model": MODEL, "engines": ["reference", "published"], "max_error": err,
        "tolerance": tol.tolerance, "passed": bool(err <= tol.tolerance), "localized_to": worst,
        "note": "exact linearization (complex step), 4 eigenvalues at 11 speeds"})
    speeds = {"weave speed": (weave_speed(model), MEIJAARD_WEAVE_SPEED),
              "capsize speed": (capsize_speed(model), MEIJAARD_CAPSIZE_SPEED)}
    tol_s = tols["benchmark_speeds"]
    for name, (ours, theirs) in speeds.items():
        e = abs(ours - theirs)
        sec.comparisons.append({
            "quantity": f"{name} vs Meijaard 2007", "scenario": "benchmark upright", "model": MODEL,
            "engines": ["reference", "published"], "max_error": e, "tolerance": tol_s.tolerance,
            "passed": bool(e <= tol_s.tolerance), "localized_to": f"{ours:.14f} m/s"})
    sec.lines += ["", "Linearized about upright straight running (roll and steer; exact "
                  "derivatives), against the published Table 2:", "",
                  "| quantity | ours | published | error | tolerance |", "|---|---|---|---|---|",
                  f"| eigenvalues, v = 0..10 m/s | - | Table 2 | {err:.1e} (worst at {worst}) | {tol.tolerance:.0e} |"]
    sec.lines += [f"| {name} [m/s] | {ours:.14f} | {theirs:.14f} | {abs(ours - theirs):.1e} | "
                  f"{tol_s.tolerance:.0e} |" for name, (ours, theirs) in speeds.items()]
    start, stop, step = EIGENVALUE_SPEEDS
    grid = start + step * np.arange(int(round((stop - start) / step)) + 1)
    eigenvalue_figure(model, grid, out / "figures" / "benchmark_eigenvalues.png")
    sec.figures.append("benchmark_eigenvalues.png")


def benchmark_section(out: Path, quick: bool, progress: Callable[[str], None], *,
                      runs: list[ManoeuvreRuns] | None = None) -> Section:
    """The benchmark bicycle's section of the report (module docstring): terms, the IFToMM
    manoeuvres on the reference and Exudyn, physics, nonlinear against linear, and the
    eigenvalue figure. ``quick``: Exudyn's tree build only, fewer random states, no
    convergence study. ``runs``: manoeuvres already run (`run_manoeuvres`), used as given."""
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    sec = Section("Benchmark bicycle (Meijaard et al. 2007): engines, IFToMM uncontrolled "
                  "bicycle, nonlinear against linear")
    model = load_model(MODEL)
    _terms_part(sec, model, quick, progress)
    if runs is None:
        runs = run_manoeuvres(model, MANOEUVRES, QUICK_BUILDS if quick else BUILDS, EXUDYN_STEP,
                              progress)
    _manoeuvre_part(sec, out, model, runs)
    _outcome_part(sec, model, runs)
    _nonlinear_part(sec, out, model, runs, progress)
    if not quick:
        _convergence_part(sec, model, progress)

    progress("  benchmark eigenvalues against speed and Table 2 ...")
    _eigenvalue_part(sec, out, model)
    return sec
