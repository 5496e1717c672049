"""Every scenario on every engine that can run it, the thesis's way.

An *engine setup* is an engine with its options, labelled as the report names it:

| label        | engine     | runs                                                                |
|--------------|------------|---------------------------------------------------------------------|
| reference    | reference  | inverse (13x13 inverse dynamics) and forward (DOP853, the scenario's |
|              |            | constraint handling: Baumgarte a1 = a2 = 10 as the thesis)          |
| pinocchio    | pinocchio  | the same solvers on Pinocchio's M, RNEA and contact kinematics       |
| exudyn-tree  | exudyn     | forward only: kinematic tree, generalized-alpha, h = 1e-3 s, the     |
|              |            | model's own front contact (user constraints for the thesis contact) |

Each run returns plain arrays (`Run`), so runs can be farmed out to worker processes: the
report's numbers do not depend on the order or the process they ran in.
"""

from __future__ import annotations

import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

EXUDYN_STEP = 1e-3


@dataclass(frozen=True)
class EngineSetup:
    """An engine and its options under the label the report uses."""

    label: str
    engine: str
    options: tuple[tuple[str, object], ...] = ()
    kinds: tuple[str, ...] = ("inverse", "forward")
    settings: str = ""

    def build(self, model):
        from engines import load_engine
        return load_engine(self.engine, model, **dict(self.options))


SETUPS: dict[str, EngineSetup] = {s.label: s for s in (
    EngineSetup("reference", "reference",
                settings="inverse: inverse kinematics DOP853 rtol 1e-12 + 13x13 LU; forward: "
                         "DOP853 rtol 1e-10, atol 1e-12, the scenario's constraint handling "
                         "(Baumgarte a1 = a2 = 10)"),
    EngineSetup("pinocchio", "pinocchio",
                settings="the reference's solvers on Pinocchio's crba, rnea and frame kinematics "
                         "(same integrator and tolerances)"),
    EngineSetup("exudyn-tree", "exudyn", (("build", "tree"), ("step", EXUDYN_STEP)),
                kinds=("forward",),
                settings=f"ObjectKinematicTree, generalized-alpha (spectral radius 0.9, index 3), "
                         f"h = {EXUDYN_STEP:g} s, Newton tolerance 1e-10; no inverse dynamics"),
)}
ENGINE_SETUPS = {"reference": ("reference",), "pinocchio": ("pinocchio",),
                 "exudyn": ("exudyn-tree",)}


def setups_for(engines) -> list[EngineSetup]:
    """The setups of the selected engine names, reference first."""
    labels = [lab for e in engines for lab in ENGINE_SETUPS.get(e, ())]
    return [SETUPS[lab] for lab in labels]


@dataclass
class Run:
    """One scenario on one engine setup: arrays only (picklable)."""

    engine: str
    scenario: str
    model: str
    kind: str
    status: str                     # completed | fell | failed | not run
    message: str
    seconds: float
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    q: np.ndarray = field(default_factory=lambda: np.zeros((0, 8)))
    dq: np.ndarray = field(default_factory=lambda: np.zeros((0, 8)))
    T: np.ndarray | None = None     # inverse: (N, 3) rider torques
    lam: np.ndarray | None = None   # inverse: (N, 5) multipliers
    trajectory: object = None       # forward: the engine's Trajectory

    @property
    def t_end(self) -> float:
        return float(self.t[-1]) if self.t.size else 0.0


def run_one(label: str, scenario: str) -> Run:
    """Run ``scenario`` on the setup ``label`` (a top-level function: worker processes call it)."""
    from reference_model import load_model
    from reference_model.scenarios import get_scenario

    sc = get_scenario(scenario)
    setup = SETUPS[label]
    model = load_model(sc.model)
    t0 = time.perf_counter()
    if sc.kind not in setup.kinds:
        return Run(label, scenario, model.name, sc.kind, "not run",
                   f"{label} has no {sc.kind} dynamics", 0.0)
    engine = setup.build(model)
    try:
        if sc.kind == "inverse":
            if label == "reference":
                from reference_model.scenarios import run_inverse
                res = run_inverse(model, sc)
            else:
                res = engine.run_inverse(sc)
            m = res.motion
            bad = int(np.count_nonzero(res.status))
            return Run(label, scenario, model.name, "inverse",
                       "completed" if bad == 0 else "failed",
                       "solved at every sample" if bad == 0 else f"{bad} samples failed",
                       time.perf_counter() - t0, m.t, m.q, m.dq, res.T, res.lam)
        traj = engine.simulate(sc)
    except Exception as exc:   # an engine failure is a result, reported with its message
        return Run(label, scenario, model.name, sc.kind, "failed",
                   f"{type(exc).__name__}: {' '.join(str(exc).split())}", time.perf_counter() - t0)
    return Run(label, scenario, model.name, "forward", traj.status, traj.message,
               time.perf_counter() - t0, traj.t, traj.q, traj.dq, trajectory=traj)


def run_all(labels, scenarios, progress: Callable[[str], None], workers: int | None = None,
            done: dict | None = None) -> dict[tuple[str, str], Run]:
    """Every (setup, scenario) pair not already in ``done``, in worker processes (``workers``
    defaults to the number of CPUs, at most 4); keyed by (label, scenario)."""
    from reference_model.scenarios import get_scenario
    runs = dict(done or {})
    for sc in scenarios:   # what a setup cannot run is recorded, not farmed out
        for lab in labels:
            if (lab, sc) not in runs and get_scenario(sc).kind not in SETUPS[lab].kinds:
                runs[(lab, sc)] = Run(lab, sc, get_scenario(sc).model, get_scenario(sc).kind,
                                      "not run", f"{lab} has no {get_scenario(sc).kind} dynamics", 0.0)
    jobs = [(lab, sc) for sc in scenarios for lab in labels if (lab, sc) not in runs]
    if not jobs:
        return runs
    workers = workers or min(4, os.cpu_count() or 1)
    if workers <= 1 or len(jobs) == 1:
        for k, (lab, sc) in enumerate(jobs, 1):
            runs[(lab, sc)] = run_one(lab, sc)
            progress(f"  [{k}/{len(jobs)}] {sc} on {lab}: {runs[(lab, sc)].status}")
        return runs
    # longest first keeps the two cores busy to the end
    order = sorted(jobs, key=lambda j: (-_cost(*j), j))
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(run_one, lab, sc): (lab, sc) for lab, sc in order}
        for k, fut in enumerate(futures, 1):
            lab, sc = futures[fut]
            runs[(lab, sc)] = fut.result()
            r = runs[(lab, sc)]
            progress(f"  [{k}/{len(jobs)}] {sc} on {lab}: {r.status} ({r.seconds:.1f} s)")
    return runs


def _cost(label: str, scenario: str) -> float:
    """A rough run time for scheduling (s), measured on the 2-core machine."""
    per_second = {"reference": 0.1, "pinocchio": 2.5, "exudyn-tree": 1.2}.get(label, 1.0)
    length = 6.3 if scenario in ("replay", "check-forward") else 1.2
    if scenario in ("check", "zigzag"):
        return 0.1
    return per_second * length
