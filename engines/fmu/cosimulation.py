"""A Co-Simulation FMU's run of a scenario: fmpy's master steps the FMU over the scenario's
grid from the reference's projected initial state, the rider torques as inputs; the mapped
states are read at the grid's samples. The master holds an input over a communication step,
so the steps are the grid's divided down to at most `COMMUNICATION_STEP` (a torque history
held over 10 ms steps put the replay scenario 5.6e-4 rad off the reference by 0.29 s). The FMU's own integrator is
the run's (the settings say so); ddq is the grid's central differences of dq (np.gradient:
second order, an approximation, not the FMU's), C the thesis's constraints at its states."""

from __future__ import annotations

import time

import numpy as np

from reference_model.scenarios import Scenario, initial_state, torque_input
from reference_model.solvers import THETA, Trajectory

__all__ = ["COMMUNICATION_STEP", "co_simulate"]

#: the largest communication step (s) the master takes (the inputs are held over it)
COMMUNICATION_STEP = 5e-4


def _inputs(engine, scenario: Scenario, t: np.ndarray) -> np.ndarray:
    torque = torque_input(engine.model, scenario)
    T = np.array([torque(tk) if callable(torque) else torque for tk in t], dtype=float).reshape(-1, 3)
    names = [r.name for r in engine.mapping.torques]
    rows = np.zeros(t.size, dtype=[("time", np.float64)] + [(n, np.float64) for n in names])
    rows["time"] = t
    for k, r in enumerate(engine.mapping.torques):
        rows[r.name] = T[:, k] / r.scale
    return rows


def co_simulate(engine, scenario: Scenario, fall_limit: float | None = None, **_ignored) -> Trajectory:
    """The scenario run by the FMU's Co-Simulation interface (``engine``: an `FmuEngine`)."""
    from fmpy import simulate_fmu
    t = np.asarray(scenario.t, dtype=np.float64)
    init = initial_state(engine.model, scenario)
    refs = engine.mapping.coordinates + engine.mapping.rates
    y0 = np.concatenate([init.q, init.dq])
    start = {r.name: float(v / r.scale) for r, v in zip(refs, y0)}
    names = {vr: n for n, vr in engine._vr.items()}
    start.update({names[vr]: v for vr, v in engine._parameters.items()})
    if engine.mapping.baumgarte is not None:
        a12 = scenario.baumgarte if scenario.constraints == "baumgarte" else (0.0, 0.0)
        start.update(dict(zip(engine.mapping.baumgarte, (float(a) for a in a12))))
    limit = scenario.fall_limit if fall_limit is None else fall_limit
    t0 = time.perf_counter()
    status, message = "completed", "reached the end of the grid"
    sub = max(1, int(np.ceil((t[1] - t[0]) / COMMUNICATION_STEP - 1e-9)))
    fine = np.linspace(t[0], t[-1], (t.size - 1) * sub + 1)
    try:
        res = simulate_fmu(str(engine._path), fmi_type="CoSimulation", start_time=t[0],
                           stop_time=t[-1], output_interval=float(fine[1] - fine[0]),
                           start_values=start, input=_inputs(engine, scenario, fine),
                           output=[r.name for r in refs])
        Y = np.column_stack([np.interp(t, res["time"], res[r.name]) * r.scale for r in refs])
    except Exception as exc:     # fmpy raises on an fmi2Error of fmi2DoStep
        Y = y0[None, :]
        status, message = "failed", f"the FMU's Co-Simulation failed: {str(exc).splitlines()[0][:160]}"
    fell = np.nonzero(np.abs(Y[:, THETA]) >= limit)[0]
    if fell.size:
        Y = Y[:fell[0] + 1]
        status, message = "fell", (f"|theta| reached the fall limit {limit:.4f} rad by "
                                   f"t = {t[fell[0]]:.6f} s (first sample past it)")
    tt = t[:Y.shape[0]]
    q, dq = Y[:, :8], Y[:, 8:]
    ddq = np.gradient(dq, tt, axis=0) if tt.size > 2 else np.zeros_like(dq)
    torque = torque_input(engine.model, scenario)
    T = np.array([torque(tk) if callable(torque) else torque for tk in tt], dtype=float).reshape(-1, 3)
    return Trajectory(
        t=tt, q=q, dq=dq, ddq=ddq, C=engine.model.constraint_residual(q, dq).reshape(-1, 5), T=T,
        status=status, message=message, t_end=float(tt[-1]),
        settings={"integrator": "the FMU's own (Co-Simulation, fmpy's master)",
                  "constraints": scenario.constraints, "fall_limit": limit,
                  "ddq": "central differences of dq on the output grid"},
        timing={"wall_seconds": time.perf_counter() - t0})
