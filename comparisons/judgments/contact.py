"""Contact fidelity of a soft-contact engine (MuJoCo) against the ideal-rolling reference.

The reference rolls both wheels without slip and without penetration (the constraints hold
exactly). A soft-contact simulator cannot: its wheels slip a little and sink a little, and
its trajectory drifts from the reference by the effect of both. Three measures say by how much
and whether it goes away as the contact is made stiffer or the step smaller:

* `contact_fidelity`: the slip speed of each wheel's contact point in the ground plane (m/s)
  and its penetration into the ground (m, positive into it), max and RMS over the run (up to a
  horizon), from the engine's per-sample ``Trajectory.diagnostics``; and the trajectory error
  to the reference against time (`convergence.error_vs_time`, on the common output grid);
* `refinement_study`: the error at one fixed time (inside the meaningful horizon, where a
  difference is the engine's, not the reference's own amplified round-off) against a refined
  parameter (the time step, the contact's solref time constant), with the observed order
  fitted by `convergence.fit_order`. A positive order over a wide span says the engine
  approaches ideal rolling, and how fast; an error that does not shrink says the refined
  parameter is not what limits it.

No engine is imported here: the functions read trajectories.

    fid = contact_fidelity(ref, mujoco_run, horizon=2.86)
    study = refinement_study(ref, [(tc, run_tc) for tc, run_tc in ...], "solref time constant",
                             at_time=0.3)
    print(fid.describe(), study.describe())
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from reference_model import COORDINATES
from reference_model.solvers import Trajectory

from .convergence import MIN_SPAN, NO_SHRINK_ORDER, REFERENCE_FLOOR, error_vs_time, fit_order
from .rows import Comparison

__all__ = ["PENETRATION_KEYS", "SLIP_KEYS", "ContactFidelity", "Refinement", "contact_fidelity",
           "declared_difference_rows", "error_at", "lift_off_time", "local_orders",
           "refinement_study"]

WHEELS = ("rear", "front")
SLIP_KEYS = tuple(f"slip_speed_{w}" for w in WHEELS)          # m/s
PENETRATION_KEYS = tuple(f"penetration_{w}" for w in WHEELS)  # m, positive into the ground


def _window(run: Trajectory, horizon: float | None) -> np.ndarray:
    """Rows of ``run`` up to ``horizon`` (all rows when None)."""
    if horizon is None:
        return np.ones(run.t.size, dtype=bool)
    dt = float(run.t[1] - run.t[0]) if run.t.size > 1 else 1.0
    return run.t <= float(horizon) + 1e-9 * dt


def _diagnostic(run: Trajectory, key: str) -> np.ndarray:
    diag = getattr(run, "diagnostics", None) or {}
    if key not in diag:
        raise ValueError(f"the run's Trajectory.diagnostics has no {key!r} (it has "
                         f"{', '.join(sorted(diag)) or 'nothing'}); a soft-contact engine must "
                         "record slip_speed_rear/front and penetration_rear/front per sample")
    a = np.asarray(diag[key], dtype=float)
    if a.shape != run.t.shape:
        raise ValueError(f"Trajectory.diagnostics[{key!r}] has shape {a.shape}; it must have one "
                         f"value per sample, {run.t.shape}")
    return a


@dataclass(frozen=True)
class ContactFidelity:
    """How far a soft-contact run is from ideal rolling, up to ``horizon``.

    Slip speeds in m/s (the contact point's speed in the ground plane; 0 for ideal rolling),
    penetrations in m (positive into the ground; 0 for ideal rolling), each the max and the RMS
    over both wheels' samples; ``error``: `error_vs_time` of the run against the reference
    (rad or m, all eight coordinates and their 'max')."""

    horizon: float                 # s: the last time included
    slip_max: float
    slip_rms: float
    slip_worst: str                # 'rear at 0.42 s'
    penetration_max: float
    penetration_rms: float
    penetration_worst: str
    error: dict                    # error_vs_time(ref, run, COORDINATES, horizon)
    error_max: float               # max of error['max']
    error_end: float               # error['max'] at the last common time

    def describe(self) -> str:
        return (f"up to {self.horizon:.2f} s: slip max {self.slip_max:.2e} m/s ({self.slip_worst}), "
                f"RMS {self.slip_rms:.2e} m/s; penetration max {self.penetration_max:.2e} m "
                f"({self.penetration_worst}), RMS {self.penetration_rms:.2e} m; trajectory error "
                f"max {self.error_max:.2e} (rad or m)")


def _max_rms(run: Trajectory, keys: Sequence[str], rows: np.ndarray) -> tuple[float, float, str]:
    vals = np.stack([_diagnostic(run, k)[rows] for k in keys])      # (wheels, n)
    if not np.all(np.isfinite(vals)):
        raise ValueError(f"non-finite values in Trajectory.diagnostics {', '.join(keys)}")
    w, k = np.unravel_index(int(np.argmax(vals)), vals.shape)
    where = f"{keys[w].rsplit('_', 1)[-1]} at {run.t[rows][k]:.2f} s"
    return float(vals.max()), float(np.sqrt(np.mean(vals ** 2))), where


def contact_fidelity(ref: Trajectory, run: Trajectory, horizon: float | None = None,
                     coords: Sequence[str] = COORDINATES) -> ContactFidelity:
    """Slip, penetration and trajectory error of ``run`` against ``ref`` up to ``horizon``
    (default: the end of the shorter run). ValueError when ``run`` lacks the diagnostics."""
    rows = _window(run, horizon)
    if not np.any(rows):
        raise ValueError(f"the run has no sample up to the horizon {horizon!r} s")
    slip = _max_rms(run, SLIP_KEYS, rows)
    pen = _max_rms(run, PENETRATION_KEYS, rows)
    err = error_vs_time(ref, run, coords, horizon)
    return ContactFidelity(
        horizon=float(err["t"][-1]), slip_max=slip[0], slip_rms=slip[1], slip_worst=slip[2],
        penetration_max=pen[0], penetration_rms=pen[1], penetration_worst=pen[2], error=err,
        error_max=float(err["max"].max()), error_end=float(err["max"][-1]))


def error_at(ref: Trajectory, run: Trajectory, at_time: float,
             coords: Sequence[str] = COORDINATES) -> float:
    """max over ``coords`` of |run - ref| at the output-grid time ``at_time``; ValueError when
    either run does not reach it (the comparison needs both at that very time)."""
    err = error_vs_time(ref, run, coords, at_time)
    dt = float(ref.t[1] - ref.t[0])
    if abs(float(err["t"][-1]) - float(at_time)) > 1e-9 * dt:
        raise ValueError(f"the runs share no output-grid sample at t = {at_time:g} s (the last "
                         f"common one is {err['t'][-1]:g} s; ends: reference {ref.t_end:g} s, "
                         f"engine {run.t_end:g} s)")
    return float(err["max"][-1])


def local_orders(values, errors) -> tuple[float, ...]:
    """log(e_i / e_i+1) / log(v_i / v_i+1) between neighbours: the order each refinement shows."""
    v, e = np.asarray(values, dtype=float), np.asarray(errors, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.log(e[:-1] / e[1:]) / np.log(v[:-1] / v[1:])
    return tuple(float(x) for x in out)


@dataclass(frozen=True)
class Refinement:
    """The error at ``at_time`` (max over the compared coordinates, rad or m) of runs that
    differ only in ``parameter``, and the order fitted to log error against log value."""

    parameter: str                 # e.g. 'solref time constant [s]'
    held: str                      # what the runs share, e.g. 'timestep = time constant / 2'
    at_time: float                 # s
    values: tuple[float, ...]
    errors: tuple[float, ...]
    slip_rms: tuple[float, ...]    # m/s, up to at_time
    penetration_max: tuple[float, ...]   # m, up to at_time
    order: float
    intercept: float
    verdict: str                   # 'approaches ideal rolling' | 'does not approach' | 'inconclusive'
    verdict_reason: str

    @property
    def orders(self) -> tuple[float, ...]:
        return local_orders(self.values, self.errors)

    @property
    def span(self) -> float:
        return float(max(self.values) / min(self.values))

    def describe(self) -> str:
        errs = ", ".join(f"{v:g}: {e:.2e}" for v, e in zip(self.values, self.errors))
        return (f"error at {self.at_time:g} s by {self.parameter} ({self.held}) {{{errs}}}: "
                f"fitted order {self.order:.2f} -> {self.verdict} ({self.verdict_reason})")


def _refinement_verdict(values, errors, order) -> tuple[str, str]:
    v, e = np.asarray(values, dtype=float), np.asarray(errors, dtype=float)
    span = float(v.max() / v.min())
    if v.size < 3 or span < MIN_SPAN * (1 - 1e-9):
        return "inconclusive", (f"{v.size} values spanning {span:.3g}x; need >= 3 spanning "
                                f">= {MIN_SPAN:g}x")
    if not np.isfinite(order):
        return "inconclusive", "an error is zero or not finite: no order can be fitted"
    e_min = float(e[np.argmin(v)])
    if e_min < REFERENCE_FLOOR:
        return "inconclusive", (f"error at the finest value {e_min:.1e} is below "
                                f"{REFERENCE_FLOOR:.0e}, the reference's own accuracy")
    if order < NO_SHRINK_ORDER:
        ratio = float(e[np.argmax(v)] / e_min)
        return "does not approach", (f"order {order:.2f} < {NO_SHRINK_ORDER}: error(coarsest) / "
                                     f"error(finest) = {ratio:.3g} over {span:g}x")
    return "approaches ideal rolling", (f"the error shrinks at order {order:.2f} over {span:g}x "
                                        f"(to {e_min:.1e} at {v.min():g})")


def refinement_study(ref: Trajectory, runs: Sequence[tuple[float, Trajectory]], parameter: str,
                     at_time: float, held: str = "", coords: Sequence[str] = COORDINATES
                     ) -> Refinement:
    """The error of each run at ``at_time`` against ``ref`` and the fitted order.

    ``runs``: (value of the refined parameter, the engine's run at it), any order. Each run
    must reach ``at_time`` (ValueError naming the value otherwise); runs with diagnostics also
    give their slip RMS and maximum penetration up to ``at_time`` (NaN without)."""
    if len(runs) < 2:
        raise ValueError(f"a refinement study needs at least 2 runs; got {len(runs)}")
    pairs = sorted(runs, key=lambda p: -float(p[0]))     # coarsest first
    values, errors, slips, pens = [], [], [], []
    for value, run in pairs:
        if not float(value) > 0:
            raise ValueError(f"{parameter} = {value!r}: refined values must be positive")
        try:
            errors.append(error_at(ref, run, at_time, coords))
        except ValueError as exc:
            raise ValueError(f"{parameter} = {value:g}: {exc}") from None
        values.append(float(value))
        if getattr(run, "diagnostics", None):
            fid_rows = _window(run, at_time)
            slips.append(_max_rms(run, SLIP_KEYS, fid_rows)[1])
            pens.append(_max_rms(run, PENETRATION_KEYS, fid_rows)[0])
        else:
            slips.append(float("nan"))
            pens.append(float("nan"))
    order, intercept = fit_order(values, errors)
    verdict, why = _refinement_verdict(values, errors, order)
    return Refinement(parameter, held, float(at_time), tuple(values), tuple(errors),
                      tuple(slips), tuple(pens), order, intercept, verdict, why)


def lift_off_time(run: Trajectory) -> float | None:
    """The first sample time after the start at which a wheel carries no load (the engine's
    recorded normal force ``normal_force_rear``/``normal_force_front`` is zero or less), or
    None (no lift-off, or the engine records no normal forces)."""
    d = getattr(run, "diagnostics", None) or {}
    if "normal_force_rear" not in d or "normal_force_front" not in d:
        return None
    unloaded = np.minimum(np.asarray(d["normal_force_rear"], dtype=float),
                          np.asarray(d["normal_force_front"], dtype=float)) <= 0.0
    unloaded[0] = False
    k = np.flatnonzero(unloaded)
    return float(run.t[k[0]]) if k.size else None


def declared_difference_rows(ref, run, horizon, difference: str, constraint_max: float | None,
                             constraint_where: str) -> list[dict]:
    """The comparisons of a forward run whose engine declares a model difference of its runs
    (``difference``, e.g. a soft contact) against the reference's ideal rolling: measured and
    reported, never judged by the ideal-rolling tolerances.

    ``ref``, ``run``: `engines.runs.Run` of the reference and the engine; ``horizon``: the
    scenario's meaningful horizon (`convergence.Horizon`); ``constraint_max``: the largest
    |C| of the run as the reference measures it (m or m/s), None without samples. Rows: the
    trajectory error up to the horizon, the constraint residual, and, where the engine records
    them, the contact's slip, penetration and the first lift-off (`contact_fidelity`,
    `lift_off_time`)."""
    note = f"reported, not judged: a declared model difference ({difference})"
    base = {"scenario": run.scenario, "model": run.model, "tolerance": None, "passed": None,
            "declared_difference": difference, "note": note,
            "why": "declared model difference"}
    rows = [Comparison.of(dict(base, quantity="constraint_residual", engines=[run.engine],
                 max_error=constraint_max, localized_to=constraint_where))]
    traj = run.trajectory
    if not run.t.size or ref.trajectory is None or traj is None:
        return rows
    lift = lift_off_time(traj)
    upto = min(float(horizon.t), run.t_end, ref.t_end)
    err = error_vs_time(ref.trajectory, traj, COORDINATES, upto)
    worst = np.stack([err[c] for c in COORDINATES], axis=1).max(axis=0)
    rows.append(Comparison.of(dict(base, quantity="trajectory", engines=[ref.engine, run.engine],
                     max_error=float(err["max"].max()), horizon=float(horizon.t),
                     horizon_reason=horizon.reason, lift_off_s=lift,
                     localized_to=f"largest: {COORDINATES[int(np.argmax(worst))]}, up to the "
                                  f"meaningful horizon {horizon.t:.2f} s"
                                  + (f"; a wheel lifts off at {lift:.2f} s" if lift is not None
                                     else ""))))
    diag = getattr(traj, "diagnostics", None) or {}
    if all(k in diag for k in SLIP_KEYS + PENETRATION_KEYS):
        fid = contact_fidelity(ref.trajectory, traj, horizon=upto)
        rows.append(Comparison.of(dict(base, quantity="contact fidelity (slip, penetration, trajectory)",
                         engines=[ref.engine, run.engine], max_error=fid.error_max,
                         horizon=fid.horizon, slip_max=fid.slip_max, slip_rms=fid.slip_rms,
                         penetration_max=fid.penetration_max,
                         penetration_rms=fid.penetration_rms, lift_off_s=lift,
                         localized_to=f"slip max {fid.slip_max:.1e} m/s ({fid.slip_worst}), "
                                      f"penetration max {fid.penetration_max:.1e} m up to "
                                      f"{fid.horizon:.2f} s"
                                      + (f"; lift-off at {lift:.2f} s" if lift is not None
                                         else "; no lift-off"))))
    return rows
