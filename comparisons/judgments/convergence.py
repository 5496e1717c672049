"""Convergence of a fixed-step engine to the reference, and how far in time a comparison means
anything.

A fixed-step engine run at step h differs from the exact motion by C h^p (p = 2 for Exudyn's
generalized-alpha and trapezoidal schemes). Run at several steps and compared with the
reference integrated at tight tolerance, the errors fall on a line of slope p in log-log
axes. A difference that does *not* fall with h is not the integrator's: the two sides solve
different equations (e.g. Exudyn's true rolling-disc front contact against the thesis's
fork-axis contact), and it is reported as a model difference, not as a failure.

    study = convergence_study(load_model("thesis-disc"),
                              lambda h: load_engine("exudyn", disc, build="tree", step=h),
                              SCENARIOS["stability-psid10"], horizon=0.5)
    print(study.describe())

The horizon. The bicycle is unstable: a small difference in the state grows like e^(sigma t)
(sigma ~ 2/s for stability-psid10, more when the steer runs away), so any two runs, however
accurate, part company eventually, and past that time their difference says nothing about
either. `meaningful_horizon` measures it with the reference alone: two reference runs that
differ only by a perturbation far below anything an engine comparison resolves (1e-9 rad/s
on theta_dot(0), 100x the reference's rtol of 1e-11) are compared on the common output grid;
the horizon is the last grid time before they separate by more than 1e-6 (rad or m) in
theta, gamma, xc or yc. Up to there the reference itself is reproducible to 1e-6 against
perturbations at its own error level, so an engine difference above that is the engine's;
beyond it, the reference's own errors, amplified 1e3-fold and more, could be anything. When
the runs never separate that much, the horizon is the end of the shorter run (a fall ends a
run; the event row, off the grid, is not compared).

Within that horizon a difference is the engine's, but not necessarily still its *asymptotic*
h^2 error: an engine's local errors are amplified by the same instability. Measured on
stability-psid10 (reference horizon 2.86 s), Exudyn's tree error keeps its ratio of 4 per
halving only up to ~1 s; at 1.5-2 s the ratios are 2-3.9 and the runs at h >= 2.5e-3 fail
(Newton) at ~1.85 s. `convergence_study` at a given horizon is the check of that.

Accelerations are never compared here (Exudyn's stored accelerations are not used anywhere;
the adapter's ddq are finite differences): only q on the scenario's output grid.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from reference_model import COORDINATES, Model
from reference_model.scenarios import Scenario, run_forward
from reference_model.solvers import Trajectory

__all__ = ["COMPARED", "DEFAULT_STEPS", "ConvergenceStudy", "Horizon", "convergence_study",
           "error_vs_time", "meaningful_horizon", "perturbed_scenario", "reference_run",
           "reference_horizon", "fit_order"]

COMPARED = ("theta", "gamma", "xc", "yc")   # the coordinates the thesis plots and the issue names
# Steps that halve and span 8x. The 4e-3 does not divide the 0.01 s output grid (the
# adapter requires that), so the sequence starts at 5e-3 and covers the same range.
DEFAULT_STEPS = (5e-3, 2.5e-3, 1.25e-3, 6.25e-4)
REFERENCE_RTOL = 1e-11      # DOP853 with projection: the reference is exact to ~1e-9 here
REFERENCE_ATOL = 1e-12
# verdict thresholds
ORDER_BAND = (1.5, 2.5)     # a second-order scheme measured over 8x in h: 2 +- 0.5
NO_SHRINK_ORDER = 0.5       # order < 0.5 over >= 8x in h: error(h_max)/error(h_min) < 8^0.5 = 2.8
MIN_SPAN = 8.0              # steps must span 8x for either verdict (three halvings)
CONVERGED_BELOW = 1e-3      # rad or m at the smallest step: 0.06 deg / 1 mm, below anything the
                            # thesis's figures resolve and 70x below the contact models'
                            # difference on stability-psid0 at 0.5 s (7e-2)
REFERENCE_FLOOR = 1e-8      # errors this small are the reference's own (rtol 1e-11, amplified):
                            # no order can be read from them
HORIZON_THRESHOLD = 1e-6    # rad or m: the twin reference runs' separation that ends the horizon
HORIZON_PERTURBATION = 1e-9  # rad/s on theta_dot(0): 100x the reference's rtol


def _index(coords: Sequence[str]) -> np.ndarray:
    unknown = [c for c in coords if c not in COORDINATES]
    if unknown:
        raise ValueError(f"unknown coordinate(s) {unknown}; choose from {COORDINATES}")
    return np.array([COORDINATES.index(c) for c in coords])


def _grid_keys(t: np.ndarray, t0: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(grid index, row) of the rows of t that lie on the grid t0 + dt k (to 1e-9 dt)."""
    k = np.rint((t - t0) / dt)
    on = np.abs(t - (t0 + dt * k)) <= 1e-9 * dt
    return k[on].astype(np.int64), np.flatnonzero(on)


def _common(ref: Trajectory, other: Trajectory, horizon: float | None = None):
    """Rows of ref and other at the output-grid times both reached (event rows off the grid
    excluded), up to ``horizon``: (t, ref rows, other rows)."""
    if ref.t.size < 2:
        raise ValueError("the reference trajectory needs at least 2 samples to define its grid")
    t0, dt = float(ref.t[0]), float(ref.t[1] - ref.t[0])
    ka, ra = _grid_keys(ref.t, t0, dt)
    kb, rb = _grid_keys(other.t, t0, dt)
    common, ia, ib = np.intersect1d(ka, kb, assume_unique=True, return_indices=True)
    t = t0 + dt * common
    keep = np.ones(t.size, dtype=bool) if horizon is None else t <= horizon + 1e-9 * dt
    if not np.any(keep):
        raise ValueError("the two trajectories share no output-grid time up to the horizon")
    return t[keep], ra[ia[keep]], rb[ib[keep]]


# -- errors against time ----------------------------------------------------------------------

def error_vs_time(ref: Trajectory, other: Trajectory, coords: Sequence[str] = COMPARED,
                  horizon: float | None = None) -> dict[str, np.ndarray]:
    """|other - ref| for each coordinate on the common output grid (up to ``horizon``), for
    plotting: {'t': times, coord: errors (rad or m), ..., 'max': the largest of them}."""
    idx = _index(coords)
    t, ra, rb = _common(ref, other, horizon)
    diff = np.abs(other.q[rb][:, idx] - ref.q[ra][:, idx])
    out = {"t": t}
    out.update({c: diff[:, j] for j, c in enumerate(coords)})
    out["max"] = diff.max(axis=1)
    return out


# -- the horizon ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Horizon:
    """How far a comparison of two runs means anything, and why."""

    t: float                 # s: the last common grid time within the horizon
    limited_by: str          # 'separation' (the runs parted) or 'end' (a run ended first)
    threshold: float         # rad or m
    separation_at_t: float   # the runs' largest difference in the compared coordinates at t
    end_times: tuple[float, float]
    reason: str

    def describe(self) -> str:
        return f"horizon {self.t:.2f} s: {self.reason}"


def meaningful_horizon(ref: Trajectory, other: Trajectory, threshold: float = HORIZON_THRESHOLD,
                       coords: Sequence[str] = COMPARED, what: str = "the two runs") -> Horizon:
    """The last common output-grid time before ``ref`` and ``other`` differ by more than
    ``threshold`` in any of ``coords``; the end of the shorter run if they never do.

    Pass the reference and a twin run that differs only by a tiny perturbation (see
    `reference_horizon`): beyond the time they part, no engine comparison means anything.
    ``what`` names the pair in the reason."""
    if not threshold > 0:
        raise ValueError(f"threshold must be positive; got {threshold!r}")
    err = error_vs_time(ref, other, coords)
    t, sep = err["t"], err["max"]
    ends = (float(ref.t_end), float(other.t_end))
    over = np.flatnonzero(sep > threshold)
    if over.size:
        k = int(over[0])
        if k == 0:
            return Horizon(float(t[0]), "separation", threshold, float(sep[0]), ends,
                           f"{what} already differ by {sep[0]:.1e} > {threshold:.0e} at the start")
        return Horizon(float(t[k - 1]), "separation", threshold, float(sep[k - 1]), ends,
                       f"{what} separate by more than {threshold:.0e} in {', '.join(coords)} "
                       f"at t = {t[k]:.2f} s ({sep[k]:.1e}); the comparison stops at the grid "
                       f"time before")
    return Horizon(float(t[-1]), "end", threshold, float(sep[-1]), ends,
                   f"{what} stay within {threshold:.0e} (max {sep.max():.1e}) up to the end of the "
                   f"shorter run ({min(ends):.3f} s; the last common grid time {t[-1]:.2f} s)")


def perturbed_scenario(scenario: Scenario, delta: float = HORIZON_PERTURBATION) -> Scenario:
    """The same forward scenario with theta_dot(0) raised by ``delta`` rad/s."""
    if scenario.kind != "forward":
        raise ValueError(f"scenario {scenario.name!r} is not a forward scenario")
    d = list(scenario.dq_ind0)
    d[0] += float(delta)
    return dataclasses.replace(scenario, name=f"{scenario.name}+dtheta{delta:g}", dq_ind0=tuple(d))


def reference_run(model: Model, scenario: Scenario, rtol: float = REFERENCE_RTOL,
                  atol: float = REFERENCE_ATOL, t_end: float | None = None) -> Trajectory:
    """The reference at tight tolerance: DOP853 with projection onto the constraints after
    every step (exact accelerations, no Baumgarte), optionally only up to ``t_end`` (the grid
    is cut there; the torque input is built from the full scenario as always)."""
    sc = scenario
    if t_end is not None:
        start, step, n = scenario.grid
        n_cut = min(n, int(np.floor((float(t_end) - start) / step + 1e-9)) + 1)
        if n_cut < 2:
            raise ValueError(f"t_end = {t_end!r} leaves fewer than 2 grid samples")
        sc = dataclasses.replace(scenario, grid=(start, step, n_cut))
    return run_forward(model, sc, constraints="projection", rtol=rtol, atol=atol)


def reference_horizon(model: Model, scenario: Scenario, delta: float = HORIZON_PERTURBATION,
                      threshold: float = HORIZON_THRESHOLD, rtol: float = REFERENCE_RTOL,
                      reference: Trajectory | None = None) -> Horizon:
    """`meaningful_horizon` of the reference and its twin with theta_dot(0) + ``delta``."""
    ref = reference if reference is not None else reference_run(model, scenario, rtol)
    twin = reference_run(model, perturbed_scenario(scenario, delta), rtol)
    return meaningful_horizon(ref, twin, threshold,
                              what=f"two reference runs (rtol {rtol:.0e}) {delta:.0e} rad/s apart "
                                   "in theta_dot(0)")


# -- the convergence study ---------------------------------------------------------------------

def fit_order(steps, errors) -> tuple[float, float]:
    """Least-squares line log(error) = order log(h) + intercept: (order, intercept)."""
    h, e = np.asarray(steps, dtype=float), np.asarray(errors, dtype=float)
    if h.size < 2 or np.any(e <= 0) or not np.all(np.isfinite(e)):
        return float("nan"), float("nan")
    order, intercept = np.polyfit(np.log(h), np.log(e), 1)
    return float(order), float(intercept)


@dataclass(frozen=True)
class ConvergenceStudy:
    """Errors of an engine run at several fixed steps against one tight-tolerance reference.

    ``errors[i]``: max over ``coordinates`` (theta, gamma, xc, yc by default) and the common grid
    times up to ``horizon`` of |q_engine - q_ref| at ``steps[i]`` (rad or m); ``errors_all``
    the same over all eight coordinates. ``order`` and ``intercept``: the least-squares line
    log e = order log h + intercept through ``errors``.
    """

    scenario: str
    engine: str               # e.g. "exudyn tree (disc contact), GeneralizedAlpha"
    reference: str            # e.g. "reference thesis-disc, DOP853 rtol 1e-11, projection"
    coordinates: tuple[str, ...]  # the compared coordinates (``errors``)
    steps: tuple[float, ...]
    errors: tuple[float, ...]
    errors_all: tuple[float, ...]
    worst: tuple[str, ...]     # the compared coordinate with the largest error, per step
    order: float
    intercept: float
    order_all: float
    horizon: float             # s: the last grid time compared (the same for every step)
    horizon_reason: str
    statuses: tuple[str, ...]  # the engine runs' status
    verdict: str               # 'converges' | 'model difference' | 'inconclusive'
    verdict_reason: str

    @property
    def ratios(self) -> tuple[float, ...]:
        """error(h_i) / error(h_i+1): 4 per halving for a second-order scheme."""
        return tuple(a / b for a, b in zip(self.errors[:-1], self.errors[1:]))

    @property
    def difference(self) -> float:
        """The error at the smallest step: the size of a model difference, when there is one."""
        return self.errors[int(np.argmin(self.steps))]

    def describe(self) -> str:
        errs = ", ".join(f"{h:g}: {e:.2e}" for h, e in zip(self.steps, self.errors))
        return (f"{self.engine} vs {self.reference}, {self.scenario} up to {self.horizon:.2f} s: "
                f"max error in {'/'.join(self.coordinates)} by step {{{errs}}}, fitted order "
                f"{self.order:.2f} -> {self.verdict} ({self.verdict_reason})")


def _verdict(steps, errors, order) -> tuple[str, str]:
    h = np.asarray(steps, dtype=float)
    e = np.asarray(errors, dtype=float)
    span = float(h.max() / h.min())
    e_min = float(e[np.argmin(h)])
    if h.size < 3 or span < MIN_SPAN * (1 - 1e-9):
        return "inconclusive", (f"{h.size} steps spanning {span:.3g}x; need >= 3 steps "
                                f"spanning >= {MIN_SPAN:g}x")
    if not np.isfinite(order):
        return "inconclusive", "an error is zero or not finite: no order can be fitted"
    if e_min < REFERENCE_FLOOR:
        return "inconclusive", (f"error at the smallest step {e_min:.1e} is below "
                                f"{REFERENCE_FLOOR:.0e}, the reference's own accuracy")
    if ORDER_BAND[0] <= order <= ORDER_BAND[1]:
        if e_min < CONVERGED_BELOW:
            return "converges", (f"order {order:.2f} in [{ORDER_BAND[0]}, {ORDER_BAND[1]}] and "
                                 f"error {e_min:.1e} < {CONVERGED_BELOW:.0e} at h = {h.min():g}")
        return "inconclusive", (f"order {order:.2f} but the error at h = {h.min():g} is still "
                                f"{e_min:.1e} >= {CONVERGED_BELOW:.0e}")
    if order < NO_SHRINK_ORDER:
        ratio = float(e[np.argmax(h)] / e_min)
        return "model difference", (f"the error does not shrink with h (order {order:.2f}, "
                                    f"error(h_max)/error(h_min) = {ratio:.3g} over {span:g}x in h): "
                                    f"a difference of {e_min:.2e} between the two models, not "
                                    "the integrator's error")
    return "inconclusive", f"order {order:.2f} is neither ~2 nor ~0"


def _engine_label(traj: Trajectory) -> str:
    """The engine of a run as its settings describe it: name, build and contact when it says,
    and its solver."""
    s = traj.settings
    name = str(s.get("engine", s.get("integrator", "engine")))
    if "build" in s:
        name += f" {s['build']}"
    if "contact" in s:
        name += f" ({s['contact']} contact)"
    if "solver_type" in s:
        name += f", {s['solver_type']}" + (f" rho_inf {s['spectral_radius']:g}"
                                           if "spectral_radius" in s else "")
    return name


def convergence_study(model_for_reference: Model, engine_factory: Callable[[float], object],
                      scenario: Scenario, steps: Sequence[float] = DEFAULT_STEPS,
                      horizon: float | None = None, reference_rtol: float = REFERENCE_RTOL, *,
                      reference: Trajectory | None = None,
                      coords: Sequence[str] = COMPARED,
                      runs: Sequence[Trajectory] | None = None) -> ConvergenceStudy:
    """Run ``engine_factory(h).simulate(scenario, t_end=horizon)`` for each step h and compare
    q with the reference (``model_for_reference``, projection, DOP853 at ``reference_rtol``),
    run once, on the common output grid up to ``horizon``.

    ``horizon=None`` uses `reference_horizon` (one more reference run, perturbed). Runs that
    end earlier (a fall) are compared up to the earliest end of all, so every step is judged
    over the same times. ``reference``: a reference trajectory already computed (its settings
    are then what they are; ``reference_rtol`` is ignored). ``runs``: the engine's runs at
    ``steps`` already made (each up to ``horizon``, e.g. for a study of the same runs against
    another reference); ``engine_factory`` is then not called."""
    steps = tuple(float(h) for h in steps)
    if len(steps) < 2 or any(not h > 0 for h in steps):
        raise ValueError(f"steps must be >= 2 positive time steps; got {steps!r}")
    if horizon is None:
        if reference is None:
            reference = reference_run(model_for_reference, scenario, reference_rtol)
        hz = reference_horizon(model_for_reference, scenario, rtol=reference_rtol,
                               reference=reference)
        horizon, reason = hz.t, hz.reason
    else:
        horizon = float(horizon)
        reason = "given"
        if reference is None:
            reference = reference_run(model_for_reference, scenario, reference_rtol, t_end=horizon)
    if runs is None:
        runs = [engine_factory(h).simulate(scenario, t_end=horizon) for h in steps]
    elif len(runs) != len(steps):
        raise ValueError(f"{len(runs)} runs given for {len(steps)} steps")
    # judge every step over the same times: up to the earliest grid time all runs reached
    last = min(float(_common(reference, tr, horizon)[0][-1]) for tr in runs)
    if last < horizon - 1e-9:
        reason += f"; cut to {last:.2f} s, the last grid time every run reached"
    idx, idx_all = _index(coords), np.arange(len(COORDINATES))
    errors, errors_all, worst = [], [], []
    for tr in runs:
        _, ra, rb = _common(reference, tr, last)
        d = np.abs(tr.q[rb] - reference.q[ra])
        errors.append(float(d[:, idx].max()))
        errors_all.append(float(d[:, idx_all].max()))
        worst.append(coords[int(np.argmax(d[:, idx].max(axis=0)))])
    order, intercept = fit_order(steps, errors)
    verdict, why = _verdict(steps, errors, order)
    rs = reference.settings
    ref_label = (f"reference {model_for_reference.name} ({model_for_reference.contact} contact), "
                 f"{rs.get('integrator', '?')} rtol {rs.get('rtol', float('nan')):.0e}, "
                 f"{rs.get('constraints', '?')}")
    return ConvergenceStudy(
        scenario=scenario.name, engine=_engine_label(runs[0]), reference=ref_label,
        coordinates=tuple(coords), steps=steps,
        errors=tuple(errors), errors_all=tuple(errors_all), worst=tuple(worst), order=order,
        intercept=intercept, order_all=fit_order(steps, errors_all)[0], horizon=last,
        horizon_reason=reason, statuses=tuple(tr.status for tr in runs), verdict=verdict,
        verdict_reason=why)
