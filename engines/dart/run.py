"""A forward scenario on DART with its own wheel-ground contact, as a `Trajectory`.

What is DART's and what is ours in a run:

* DART: the tree (the URDF export with the rear contact's height ``zc`` free, `world`), gravity,
  the contacts of each wheel's thin cylinder with the ground box found by the chosen collision
  detector, their rigid, frictional (Coulomb, DART's friction pyramid of two tangent
  directions), unilateral impulses from the boxed LCP of each step, and the time stepping
  (``World.step``: semi-implicit Euler at the fixed ``timestep``).
* Ours: the start, the scenario's projected initial state (`initial_state`, the same for every
  engine; zc = 0); the rider torques (single-sided, as in the thesis) and the drag at the
  frame's CoM as external forces set before every step from that step's state; the output on
  the scenario's grid (the step must divide its interval); ddq, the velocity change of the step
  that ends at each sample over the step (the contact impulses included); C, the reference
  model's residuals on DART's states; the diagnostics below; the fall (|theta| >= fall_limit
  after a step ends the run with that step's state as the last row) and failures (a
  non-finite state ends the run at the last good sample, status 'failed').

``Trajectory.diagnostics`` (each (N,) on the output grid), from each wheel's knife-edge disc:
``slip_speed_rear/front`` (m/s, the horizontal speed of the wheel's material point at the
disc's lowest point), ``penetration_rear/front`` (m, that point's depth below the ground) and
``normal_force_rear/front`` (N, the ground's vertical force on the wheel over the last step;
zero once a wheel has lifted off).
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from reference_model.scenarios import Scenario, initial_state, torque_input
from reference_model.solvers import Trajectory

from ..base import EngineUsageError
from ..stepping import forward_grid, steps_per_sample
from .options import RunSettings
from .world import build_world

import dartpy as dart

__all__ = ["simulate"]

THETA = 3
#: the columns of a sample's diagnostics row (rear wheel, front wheel, normal forces)
DIAGNOSTICS = ("slip_speed_rear", "penetration_rear", "slip_speed_front", "penetration_front",
               "normal_force_rear", "normal_force_front")
#: options of the reference's simulate that have no meaning here; accepted and recorded
REFERENCE_ONLY = ("rtol", "atol", "constraints", "baumgarte")


def _settings_of(engine, options: dict) -> RunSettings:
    unknown = [k for k in options if k not in RunSettings.field_names()]
    if unknown:
        raise EngineUsageError(f"DART simulate got unknown option(s) {', '.join(unknown)}; it "
                               f"takes fall_limit, t_end, progress and "
                               f"{', '.join(RunSettings.field_names())}")
    if not options:
        return engine.settings
    return RunSettings.checked(**{**dataclasses.asdict(engine.settings), **options})


def simulate(engine, scenario: Scenario, **options) -> Trajectory:
    """Forward run of ``scenario`` from its projected initial state, on DART's contact.

    Options: ``fall_limit`` (rad), ``t_end`` (s, stop early), ``progress`` (called with the time
    reached at every output sample), and any field of `RunSettings` for this run. A bad option
    is an `EngineUsageError`, raised before anything runs."""
    wall0 = time.perf_counter()
    fall_limit = options.pop("fall_limit", scenario.fall_limit)
    t_end = options.pop("t_end", None)
    progress = options.pop("progress", None)
    ignored = {k: options.pop(k) for k in REFERENCE_ONLY if k in options}
    s = _settings_of(engine, options)
    grid, fall_limit = forward_grid(scenario, fall_limit, t_end, "DART")
    model = engine.model
    h = s.timestep
    per = steps_per_sample(h, float(grid[1] - grid[0]), float(grid[-1] - grid[0]), "DART",
                           "timestep")
    n_steps = per * (grid.size - 1)
    torque = torque_input(model, scenario)
    t_steps = grid[0] + h * np.arange(n_steps + 1)
    T_steps = (np.array([np.asarray(torque(t), dtype=float).reshape(3) for t in t_steps])
               if callable(torque) else
               np.broadcast_to(np.asarray(torque, dtype=float).reshape(3), (n_steps + 1, 3)))

    rw = build_world(model.params, s)
    init = initial_state(model, scenario)
    rw.bike.setPositions(rw.map.to_dart(np.insert(init.q, 2, 0.0)))
    rw.bike.setVelocities(rw.map.to_dart(np.insert(init.dq, 2, 0.0)))
    rw.world.setTime(float(grid[0]))
    rows = {"t": [], "q": [], "dq": [], "ddq": [], "T": [], "diag": []}

    def sample(t, T, ddq):
        rows["t"].append(t)
        rows["T"].append(np.array(T, dtype=float))
        rows["q"].append(np.delete(rw.map.from_dart(rw.bike.getPositions()), 2))
        rows["dq"].append(np.delete(rw.map.from_dart(rw.bike.getVelocities()), 2))
        rows["ddq"].append(np.delete(ddq, 2))
        rows["diag"].append(rw.wheel_contact("rear_wheel") + rw.wheel_contact("front_wheel")
                            + rw.normal_forces())

    status, message = "completed", "reached the end of the grid"
    rw.loads(T_steps[0])
    sample(float(grid[0]), T_steps[0], np.zeros(9))
    solve0 = time.perf_counter()
    k = 0
    if abs(init.q[THETA]) >= fall_limit:
        status, n_steps = "fell", 0
        message = f"|theta| = {abs(init.q[THETA]):.3f} rad >= fall limit at the start"
    bike, step, i_theta = rw.bike, rw.world.step, int(rw.map.dof[4])
    T_list = np.asarray(T_steps).tolist()
    while k < n_steps:
        v0 = bike.getVelocities()
        rw.loads(T_list[k])
        step()
        k += 1
        theta = bike.getPosition(i_theta)
        at_sample = k % per == 0
        if not math.isfinite(theta) or ((at_sample or abs(theta) >= fall_limit)
                                        and not np.isfinite(bike.getVelocities()).all()):
            status = "failed"
            message = (f"DART's state became non-finite between t = {t_steps[k - 1]:.6f} and "
                       f"{t_steps[k]:.6f} s; the run ends at the last sample before")
            break
        if abs(theta) >= fall_limit:
            sample(float(t_steps[k]), T_steps[k], rw.map.from_dart(bike.getVelocities() - v0) / h)
            status = "fell"
            message = f"|theta| reached the fall limit {fall_limit:.4f} rad at t = {t_steps[k]:.6f} s"
            break
        if at_sample:
            sample(float(grid[k // per]), T_steps[k],
                   rw.map.from_dart(bike.getVelocities() - v0) / h)
            if progress is not None:
                progress(float(grid[k // per]))
    solve_seconds = time.perf_counter() - solve0

    q, dq = np.array(rows["q"]), np.array(rows["dq"])
    diag = np.array(rows["diag"], dtype=float).reshape(-1, len(DIAGNOSTICS))
    return Trajectory(
        t=np.array(rows["t"]), q=q, dq=dq, ddq=np.array(rows["ddq"]),
        C=model.constraint_residual(q, dq).reshape(-1, 5), T=np.array(rows["T"]),
        status=status, message=message, t_end=float(rows["t"][-1]),
        settings={
            "engine": "dart", "dart_version": dart.__version__, "contact": model.contact,
            **s.as_dict(),
            "wheels": (f"cylinders of the wheel radii ({model.params.R_rear:g} m rear, "
                       f"{model.params.R_front:g} m front), half-width {s.wheel_half_width:g} m, "
                       "axis = the axle; ground: a welded box, top face z = 0"),
            "friction_coefficients": (f"Coulomb {s.friction:g} (wheels and ground), DART's "
                                      "friction pyramid"),
            "integrator": "DART's World.step: semi-implicit Euler, impulses from a boxed LCP",
            "rear_height_joint": ("zc, a prismatic z joint after yc (free: the rear wheel rests "
                                  "on its contact)"),
            "loads": "rider torques and drag as external forces, set before each step",
            "fall_limit": fall_limit,
            "grid": f"scenario grid (every {per} steps)",
            "ddq": "the velocity change of the step ending at each sample, over the step",
            "C": "reference model's constraint_residual on the DART states",
            "diagnostics": ("slip speed and penetration of each wheel's knife-edge disc at its "
                            "lowest point; the ground's vertical force per wheel"),
            "initial_correction": init.describe(), "beta_correction": init.beta_correction,
            "ignored_options": sorted(ignored),
        },
        timing={"wall_seconds": time.perf_counter() - wall0, "solve_seconds": solve_seconds,
                "steps": k},
        diagnostics=dict(zip(DIAGNOSTICS, diag.T)),
    )
