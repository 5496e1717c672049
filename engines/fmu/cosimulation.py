"""A Co-Simulation FMU's run of a scenario: fmpy's master steps the FMU over the scenario's
grid from the reference's projected initial state, the rider torques as inputs; the mapped
states are read at the grid's samples. The master holds an input over a communication step,
so the steps are the grid's divided down to at most `COMMUNICATION_STEP` (a torque history
held over 10 ms steps put the replay scenario 5.6e-4 rad off the reference by 0.29 s). The FMU's own integrator is
the run's (the settings say so); ddq is the grid's central differences of dq (np.gradient:
second order inside, first order at the ends; an approximation, not the FMU's), C the
thesis's constraints at its states.

The master stops after the communication step on which |theta| reaches the fall limit (the
fall is the first grid sample past it, as the message says), so a failure of the FMU after
a fall cannot turn the fall into a failure; a step that fails keeps the samples recorded
before it. ``t_end`` cuts the grid; the constraint handling is the scenario's or
``constraints``: 'baumgarte', else the FMU's Baumgarte parameters set to 0 (a Co-Simulation
FMU cannot project its state: 'projection' runs as 'none', and the settings say so); an option
its own integrator cannot honour (rtol, atol) is refused in one line."""

from __future__ import annotations

import time

import numpy as np

from reference_model.scenarios import Scenario, initial_state, torque_input
from reference_model.solvers import THETA, Trajectory, checked_fall_limit

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


def co_simulate(engine, scenario: Scenario, fall_limit: float | None = None,
                t_end: float | None = None, constraints: str | None = None,
                progress=None, **options) -> Trajectory:
    """The scenario run by the FMU's Co-Simulation interface (``engine``: an `FmuEngine`);
    ``progress`` is accepted and not called (the master reports nothing on the way)."""
    from fmpy import simulate_fmu
    if options:
        raise TypeError(f"the fmu engine's Co-Simulation run takes no {', '.join(sorted(options))}"
                        " (the FMU integrates with its own method and step); fix: leave it out, "
                        "or use the Model-Exchange interface (interface=me)")
    constraints = constraints or scenario.constraints
    if constraints not in ("baumgarte", "none", "projection"):
        raise ValueError(f"constraints={constraints!r}: fix: 'baumgarte', 'none' or 'projection'")
    t = np.asarray(scenario.t, dtype=np.float64)
    if t_end is not None:
        t = t[t <= float(t_end) + 1e-12]
        if t.size < 2:
            raise ValueError(f"t_end={t_end!r} leaves fewer than two samples of the scenario's "
                             f"grid (from {scenario.t[0]:g} s); fix: a later t_end")
    init = initial_state(engine.model, scenario)
    refs = engine.mapping.coordinates + engine.mapping.rates
    y0 = np.concatenate([init.q, init.dq])
    start = {r.name: float(v / r.scale) for r, v in zip(refs, y0)}
    names = {vr: n for n, vr in engine._vr.items()}
    start.update({names[vr]: v for vr, v in engine._parameters.items()})
    if engine.mapping.baumgarte is not None:
        a12 = scenario.baumgarte if constraints == "baumgarte" else (0.0, 0.0)
        start.update(dict(zip(engine.mapping.baumgarte, (float(a) for a in a12))))
    limit = checked_fall_limit(scenario.fall_limit if fall_limit is None else fall_limit)
    t0 = time.perf_counter()
    status, message = "completed", "reached the end of the grid"
    sub = max(1, int(np.ceil((t[1] - t[0]) / COMMUNICATION_STEP - 1e-9)))
    fine = np.linspace(t[0], t[-1], (t.size - 1) * sub + 1)
    theta = refs[THETA]
    seen: dict = {}

    def on_step(now, recorder) -> bool:
        """Keep the recorder (its samples survive a failing step); stop at the first grid
        sample past the fall limit."""
        seen["recorder"] = recorder
        at_sample = round((now - fine[0]) / (fine[1] - fine[0])) % sub == 0
        if not (recorder.rows and at_sample):
            return True
        k = seen.setdefault("theta_col", [c[0] for c in recorder.cols].index(theta.name))
        return abs(recorder.rows[-1][k] * theta.scale) < limit

    try:
        res = simulate_fmu(str(engine._path), fmi_type="CoSimulation", start_time=t[0],
                           stop_time=t[-1], output_interval=float(fine[1] - fine[0]),
                           start_values=start, input=_inputs(engine, scenario, fine),
                           output=[r.name for r in refs], step_finished=on_step)
    except Exception as exc:     # fmpy raises on an fmi2Error of fmi2DoStep
        res = seen["recorder"].result() if "recorder" in seen else None
        status, message = "failed", f"the FMU's Co-Simulation failed: {str(exc).splitlines()[0][:160]}"
    if res is None or len(res) == 0:
        Y = y0[None, :]
    else:            # the grid's samples the run reached (it stops early on a fall or failure)
        t = t[: max(1, int(np.searchsorted(t, res["time"][-1] + 1e-12)))]
        Y = np.column_stack([np.interp(t, res["time"], res[r.name]) * r.scale for r in refs])
    fell = np.nonzero(np.abs(Y[:, THETA]) >= limit)[0]
    if fell.size:
        Y = Y[:fell[0] + 1]
        status, message = "fell", (f"|theta| reached the fall limit {limit:.4f} rad by "
                                   f"t = {t[fell[0]]:.6f} s (first sample past it)")
    tt = t[:Y.shape[0]]
    q, dq = Y[:, :8], Y[:, 8:]
    ddq = np.gradient(dq, tt, axis=0) if tt.size >= 2 else np.zeros_like(dq)
    torque = torque_input(engine.model, scenario)
    T = np.array([torque(tk) if callable(torque) else torque for tk in tt], dtype=float).reshape(-1, 3)
    return Trajectory(
        t=tt, q=q, dq=dq, ddq=ddq, C=engine.model.constraint_residual(q, dq).reshape(-1, 5), T=T,
        status=status, message=message, t_end=float(tt[-1]),
        settings={"integrator": "the FMU's own (Co-Simulation, fmpy's master)",
                  "constraints": (constraints if constraints != "projection" else
                                  "none (the scenario's projection: a Co-Simulation FMU cannot "
                                  "project its state)"), "fall_limit": limit,
                  "ddq": "central differences of dq on the output grid"},
        timing={"wall_seconds": time.perf_counter() - t0})
