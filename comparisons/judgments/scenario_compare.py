"""Engine runs of one scenario against the reference's: what the registry says is compared.

* inverse scenarios: rider torques and multipliers along the motion, M at its states;
* forward scenarios: all eight coordinates up to the meaningful horizon (with the coordinate
  that diverges first, and when), the constraint residual of every engine's run (evaluated by
  the reference model, so every engine is measured by the same yardstick), M at the
  reference run's states.

Every comparison is a plain dict (the `comparisons` entries of summary.json): quantity,
scenario, model, engines, max_error, tolerance, passed, localized_to, plus notes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from reference_model import CONSTRAINT_NAMES, COORDINATES, TORQUE_NAMES

from .convergence import HORIZON_THRESHOLD, Horizon, error_vs_time
from engines.runs import Run

from .terms import States, compare_term
from .tolerances import Tolerance

@dataclass(frozen=True)
class TrajectoryError:
    """|engine - reference| for each coordinate on the common grid up to a horizon."""

    t: np.ndarray
    errors: np.ndarray          # (N, 8)
    first: str                  # 'theta at 0.89 s' or '-' if nothing passes the threshold
    worst: float
    worst_coordinate: str


def trajectory_error(ref: Run, other: Run, horizon: float, threshold: float = HORIZON_THRESHOLD
                     ) -> TrajectoryError:
    """Errors of all eight coordinates on the output-grid times both runs reached (event rows
    off the grid excluded), up to ``horizon`` (`convergence.error_vs_time`)."""
    err = error_vs_time(ref, other, coords=COORDINATES, horizon=horizon)
    t, e = err["t"], np.stack([err[c] for c in COORDINATES], axis=1)
    over = np.flatnonzero(e.max(axis=1) > threshold)
    first = "-"
    if over.size:
        k = int(over[0])
        first = f"{COORDINATES[int(np.argmax(e[k]))]} at {t[k]:.2f} s"
    return TrajectoryError(t, e, first, float(e.max()), COORDINATES[int(np.argmax(e.max(axis=0)))])


def constraint_series(model, run: Run) -> np.ndarray:
    """|C| (N, 5) of a run's states, evaluated by the reference model."""
    if run.t.size == 0:
        return np.zeros((0, 5))
    return np.abs(model.constraint_residual(run.q, run.dq))


def compare_inverse(ref: Run, other: Run, tols: dict[str, Tolerance]) -> list[dict]:
    """Torques and multipliers of ``other`` against the reference, sample by sample."""
    out = []
    for quantity, a, b, names in (("torques", ref.T, other.T, TORQUE_NAMES),
                                  ("multipliers", ref.lam, other.lam,
                                   [f"lambda[{c}]" for c in CONSTRAINT_NAMES])):
        tol = tols[quantity]
        diff = np.abs(b - a)
        scale = tol.normalizer(a)
        k, i = np.unravel_index(int(np.argmax(diff)), diff.shape)
        err = float(diff.max()) / scale
        out.append({
            "quantity": quantity, "scenario": ref.scenario, "model": ref.model,
            "engines": [ref.engine, other.engine], "max_error": err, "max_abs_error": float(diff.max()),
            "tolerance": tol.tolerance, "passed": bool(err <= tol.tolerance),
            "localized_to": f"{names[i]} at t = {ref.t[k]:.2f} s",
            "note": f"over {len(ref.t)} samples; error relative to {scale:.3g} ({tol.scale})"})
    return out


def compare_mass_matrix(scenario: str, model, states_q: np.ndarray, engines: dict,
                        tols) -> list[dict]:
    """M of every engine of ``engines`` (label -> engine built from ``model``) that provides it,
    at the given states, against the reference model's."""
    from engines import load_engine
    ref = load_engine("reference", model)
    n = len(states_q)
    states = States(states_q, np.zeros_like(states_q), np.zeros_like(states_q), np.zeros((n, 3)))
    out = []
    for label, eng in engines.items():
        if label == "reference" or not eng.supports("mass_matrix"):
            continue
        r = compare_term("mass_matrix", ref, eng, states, tols["mass_matrix"])
        out.append({"quantity": "mass_matrix", "scenario": scenario, "model": model.name,
                    "engines": ["reference", label], "max_error": r.max_error,
                    "max_abs_error": r.max_abs_error, "tolerance": r.tolerance,
                    "passed": r.passed, "localized_to": f"{r.worst_entry} at state {r.worst_state}",
                    "note": f"at the reference's {n} states of the scenario"})
    return out


def _short(x: float) -> str:
    """1e-06 -> '1e-6' (as the report's text writes thresholds)."""
    return f"{x:.0e}".replace("e-0", "e-").replace("e+0", "e+")


def compare_forward(model, ref: Run, other: Run, horizon: Horizon, tols,
                    judged_by: str | None = "trajectory",
                    reported_because: str = "its convergence order"
                    ) -> tuple[list[dict], TrajectoryError]:
    """Trajectory (8 coordinates, up to the horizon) of ``other`` against the reference.
    ``judged_by``: the tolerance table that judges it, as the engine declares
    (`engines.facts`: ``trajectory_tolerance``): [trajectory] for a run with the reference's own
    integrator and tolerances, [trajectory_conformance] for an engine's own integrator; None to
    report it only, judged elsewhere by what ``reported_because`` names."""
    te = trajectory_error(ref, other, horizon.t)
    same_solver = judged_by == "trajectory"
    tol = tols[judged_by] if judged_by else None
    comp = {
        "quantity": "trajectory", "scenario": ref.scenario, "model": ref.model,
        "engines": [ref.engine, other.engine], "max_error": te.worst,
        "tolerance": tol.tolerance if tol else None,
        "passed": bool(te.worst <= tol.tolerance) if tol else None,
        "localized_to": (f"first past {_short(HORIZON_THRESHOLD)}: {te.first}" if te.first != "-"
                         else f"none past {_short(HORIZON_THRESHOLD)}")
                        + f"; largest: {te.worst_coordinate}",
        "horizon": horizon.t, "horizon_reason": horizon.reason,
        "note": ("same integrator and formulation as the reference: judged" if same_solver else
                 f"its own integrator: judged by [{judged_by}]" if tol else
                 f"reported here, judged by {reported_because}"),
        "why": "" if tol else f"judged by {reported_because}",
    }
    return [comp], te


def compare_constraints(model, run: Run, tols) -> dict:
    """The constraint residual of one engine's run, measured by the reference model."""
    C = constraint_series(model, run)
    tol = tols["constraint_residual"]
    if C.size == 0:
        return {"quantity": "constraint_residual", "scenario": run.scenario, "model": run.model,
                "engines": [run.engine], "max_error": None, "tolerance": tol.tolerance,
                "passed": None, "localized_to": "-", "note": f"no samples ({run.status})"}
    k, i = np.unravel_index(int(np.argmax(C)), C.shape)
    err = float(C.max())
    return {"quantity": "constraint_residual", "scenario": run.scenario, "model": run.model,
            "engines": [run.engine], "max_error": err, "tolerance": tol.tolerance,
            "passed": bool(err <= tol.tolerance),
            "localized_to": f"C[{CONSTRAINT_NAMES[i]}] at t = {run.t[k]:.2f} s",
            "note": f"whole run to {run.t_end:.3f} s ({run.status})"}
