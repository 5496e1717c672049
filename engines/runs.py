"""One scenario on one engine, as plain arrays: the unit every comparison works on.

`Run` is what the harness keeps of an engine's run (picklable, so runs can be farmed out to
worker processes); `run_scenario` makes one from any engine with the `simulate` or
`run_inverse` capability. A run that cannot be made (the engine lacks the dynamics, or raises)
is a `Run` too, with status 'not run' or 'failed' and the reason as its message: a failure is a
result, never a crash of the harness.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .base import CapabilityError
from .guard import describe


@dataclass
class Run:
    """One scenario on one engine setup: arrays only (picklable)."""

    engine: str
    scenario: str
    model: str
    kind: str                       # inverse | forward
    status: str                     # completed | fell | failed | not run
    message: str
    seconds: float
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    q: np.ndarray = field(default_factory=lambda: np.zeros((0, 8)))
    dq: np.ndarray = field(default_factory=lambda: np.zeros((0, 8)))
    T: np.ndarray | None = None     # inverse: (N, 3) rider torques [Mdir, Mped, Mvue], N m
    lam: np.ndarray | None = None   # inverse: (N, 5) multipliers
    trajectory: object = None       # forward: the engine's Trajectory
    ddq: np.ndarray | None = None   # inverse: (N, 8) accelerations of the motion

    @property
    def t_end(self) -> float:
        return float(self.t[-1]) if self.t.size else 0.0


_WHAT = {"inverse": "constrained inverse dynamics (run_inverse: the rider's torques and the "
                   "contact forces of a prescribed motion)",
         "forward": "forward dynamics (simulate)"}


def run_scenario(label: str, engine, model, scenario, kinds=("inverse", "forward")) -> Run:
    """``scenario`` on ``engine`` (built from ``model``) as a `Run` labelled ``label``. Inverse
    scenarios go through the engine's ``run_inverse`` (the reference model's own
    `reference_model.scenarios.run_inverse` when ``engine`` is None), forward ones through its
    ``simulate``."""
    t0 = time.perf_counter()
    if scenario.kind not in kinds:
        return Run(label, scenario.name, model.name, scenario.kind, "not run",
                   f"{label} has no {_WHAT[scenario.kind]}", 0.0)
    try:
        if scenario.kind == "inverse":
            if engine is None:
                from reference_model.scenarios import run_inverse
                res = run_inverse(model, scenario)
            else:
                res = engine.run_inverse(scenario)
            m = res.motion
            bad = int(np.count_nonzero(res.status))
            how = "solved at every sample" if bad == 0 else f"{bad} samples failed"
            if m.info.get("beta_correction"):     # a geometry whose start needed it
                how += f"; {m.info['initial_correction']}"
            return Run(label, scenario.name, model.name, "inverse",
                       "completed" if bad == 0 else "failed", how,
                       time.perf_counter() - t0, m.t, m.q, m.dq, res.T, res.lam,
                       ddq=getattr(res, "ddq", None))
        traj = engine.simulate(scenario)
    except CapabilityError as exc:   # declared by the engine for this model: not a failure
        return Run(label, scenario.name, model.name, scenario.kind, "not run",
                   f"declared model difference: {' '.join(str(exc).split())}",
                   time.perf_counter() - t0)
    except Exception as exc:   # an engine failure is a result, reported with its message
        return Run(label, scenario.name, model.name, scenario.kind, "failed", describe(exc),
                   time.perf_counter() - t0)
    return Run(label, scenario.name, model.name, "forward", traj.status, traj.message,
               time.perf_counter() - t0, traj.t, traj.q, traj.dq, trajectory=traj)
