"""A forward scenario on Drake's own wheel-ground contact, as a `Trajectory`.

What is Drake's and what is ours in a run:

* Drake: the discrete MultibodyPlant of `engines.drake.contact_plant` (the run's URDF with the
  rear height ``zc`` free, gravity, the wheels' cylinders on the half-space, its contact model
  and solver) and its time stepping at the fixed ``time_step`` (``Simulator.AdvanceTo`` one
  step at a time).
* Ours: the start, the scenario's projected initial state (`initial_state`, the same for every
  engine; zc = 0, so both wheels touch the ground without penetration); the rider torques,
  single-sided as in the thesis, and the drag -cv |vG3| vG3 at the frame's CoM, as externally
  applied spatial forces set before every step from that step's state (held over the step);
  the output on the scenario's grid (the steps land on its samples: the step must divide its
  interval); ddq, Drake's generalized acceleration (v_next - v) / h of the step that leaves each
  sample; the constraint residuals ``C``, evaluated by the reference model on Drake's states;
  the diagnostics (below); the fall (|theta| >= fall_limit after a step ends the run; the
  event is interpolated linearly between the two steps around it) and failures (Drake raises,
  or the state becomes non-finite: the run ends at the last good sample, status 'failed').

``Trajectory.diagnostics`` (each (N,) on the output grid), from the knife-edge disc of each
wheel (the model's wheel; the cylinder's caps are ``wheel_half_width`` either side of it):
``slip_speed_rear``/``_front`` (m/s: the horizontal speed of the wheel's material point at the
disc's lowest point, rG - R n/|n| with n = e_z - (e_z . a) a, a the axle), ``penetration_rear``/
``_front`` (m, that point's depth below the ground, positive into it) and
``normal_force_rear``/``_front`` (N: the ground's vertical force on the wheel from Drake's
contact results, zero once the wheel has lifted off).
"""

from __future__ import annotations

import math
import time

import numpy as np

from importlib.metadata import version

from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce

from reference_model.scenarios import Scenario, initial_state, torque_input
from reference_model.solvers import Trajectory

from ..base import EngineUsageError
from ..stepping import forward_grid, steps_per_sample
from .contact_plant import RunPlant, build_run_plant
from .plant import BODY_LINKS

__all__ = ["simulate"]

THETA = 3                # index of theta in q
REFERENCE_ONLY = ("rtol", "atol", "constraints", "baumgarte")
_UP = np.array([0.0, 0.0, 1.0])
_ZERO = [0.0, 0.0, 0.0]


class _Loads:
    """The rider torques and the drag as Drake's externally applied spatial forces."""

    def __init__(self, rp: RunPlant, params):
        plant = rp.plant
        self.rp = rp
        self.bodies = {b: plant.GetBodyByName(link) for b, link in BODY_LINKS.items()}
        self.com3 = np.array([params.x3, 0.0, params.z3])
        self.cv = float(params.cv)
        self.port = plant.get_applied_spatial_force_input_port()
        # steer torque on the fork, pedal torque on the rear wheel, anti-roll torque and drag
        # (at the CoM) on the frame; their values are set by `apply`
        self.forces = []
        for b, at in ((4, np.zeros(3)), (2, np.zeros(3)), (3, self.com3)):
            f = ExternallyAppliedSpatialForce()
            f.body_index = self.bodies[b].index()
            f.p_BoBq_B = at
            self.forces.append(f)

    def apply(self, T) -> None:
        """Set the loads from the context's current state (plain float arithmetic on
        3-vectors: this runs every step, and a numpy call on one costs ~1-70 us)."""
        plant, ctx, bodies, forces = self.rp.plant, self.rp.context, self.bodies, self.forces
        R4 = plant.EvalBodyPoseInWorld(ctx, bodies[4]).rotation().matrix().tolist()
        R2 = plant.EvalBodyPoseInWorld(ctx, bodies[2]).rotation().matrix().tolist()
        R3 = plant.EvalBodyPoseInWorld(ctx, bodies[3]).rotation().matrix().tolist()
        T0, T1, T2 = (float(x) for x in T)
        V3 = plant.EvalBodySpatialVelocityInWorld(ctx, bodies[3])
        wx, wy, wz = V3.rotational().tolist()
        vx, vy, vz = V3.translational().tolist()
        cx, cz = self.com3[0], self.com3[2]
        px, py, pz = (R3[0][0] * cx + R3[0][2] * cz, R3[1][0] * cx + R3[1][2] * cz,
                      R3[2][0] * cx + R3[2][2] * cz)                  # CoM from the origin
        vx, vy, vz = vx + wy * pz - wz * py, vy + wz * px - wx * pz, vz + wx * py - wy * px
        k = -self.cv * math.sqrt(vx * vx + vy * vy + vz * vz)
        forces[0].F_Bq_W = SpatialForce([T0 * R4[0][2], T0 * R4[1][2], T0 * R4[2][2]], _ZERO)
        forces[1].F_Bq_W = SpatialForce([T1 * R2[0][1], T1 * R2[1][1], T1 * R2[2][1]], _ZERO)
        forces[2].F_Bq_W = SpatialForce([T2 * R3[0][0], T2 * R3[1][0], T2 * R3[2][0]],
                                        [k * vx, k * vy, k * vz])
        self.port.FixValue(ctx, forces)


def _disc_point(plant, ctx, body, R) -> tuple[float, float]:
    """(slip speed m/s, penetration m) of a wheel's knife-edge disc at its lowest point."""
    X = plant.EvalBodyPoseInWorld(ctx, body)
    Rm = X.rotation().matrix()
    a = Rm[:, 1]
    n = _UP - a[2] * a
    p = X.translation() - R * n / math.sqrt(n @ n)
    V = plant.EvalBodySpatialVelocityInWorld(ctx, body)
    v = V.translational() + np.cross(V.rotational(), p - X.translation())
    return math.hypot(v[0], v[1]), -float(p[2])


def _normal_forces(rp: RunPlant) -> tuple[float, float]:
    """(rear, front) vertical force of the ground on each wheel (N), from the contact results."""
    res = rp.plant.get_contact_results_output_port().Eval(rp.context)
    index = {rp.wheels[2].index(): 0, rp.wheels[5].index(): 1}
    out = [0.0, 0.0]
    for i in range(res.num_point_pair_contacts()):
        c = res.point_pair_contact_info(i)
        for body, sign in ((c.bodyB_index(), 1.0), (c.bodyA_index(), -1.0)):
            if body in index:
                out[index[body]] += sign * float(c.contact_force()[2])
    if res.num_hydroelastic_contacts():
        inspector = rp.plant.get_geometry_query_input_port().Eval(rp.context).inspector()
    for i in range(res.num_hydroelastic_contacts()):
        c = res.hydroelastic_contact_info(i)
        surface = c.contact_surface()
        for gid in (surface.id_M(), surface.id_N()):
            body = rp.plant.GetBodyFromFrameId(inspector.GetFrameId(gid))
            if body is not None and body.index() in index:    # the ground pushes up
                out[index[body.index()]] += abs(float(c.F_Ac_W().translational()[2]))
    return out[0], out[1]


def simulate(engine, scenario: Scenario, **options) -> Trajectory:
    """Forward run of ``scenario`` from its projected initial state, on Drake's contact.

    Options: ``fall_limit`` (rad, default the scenario's), ``t_end`` (s, stop early),
    ``progress`` (called with the time reached at every output sample), and any of the
    engine's settings (time_step, approximation, ...) for this run. The reference-only options
    rtol, atol, constraints, baumgarte are accepted and ignored (listed in
    ``settings['ignored_options']``). A bad option is an `EngineUsageError`, raised before
    anything runs."""
    wall0 = time.perf_counter()
    fall_limit = options.pop("fall_limit", scenario.fall_limit)
    t_end = options.pop("t_end", None)
    progress = options.pop("progress", None)
    ignored = sorted(k for k in REFERENCE_ONLY if k in options)
    for k in ignored:
        options.pop(k)
    settings = engine.settings.replace(**options) if options else engine.settings
    grid, fall_limit = forward_grid(scenario, fall_limit, t_end, "Drake")
    model = engine.model
    h = settings.time_step
    per = steps_per_sample(h, float(grid[1] - grid[0]), float(grid[-1] - grid[0]), "Drake",
                           "time_step")

    rp = build_run_plant(model.params, settings)
    plant, ctx, mp = rp.plant, rp.context, rp.mapping
    # the lean's place in Drake's q (the run's coordinates have zc after yc: mp.names)
    i_theta = mp.q_index[mp.names.index("theta")]
    init = initial_state(model, scenario)
    torque = torque_input(model, scenario)
    torque_at = torque if callable(torque) else (lambda t, T=np.asarray(torque, float): T)
    plant.SetPositions(ctx, mp.q_to_drake(np.insert(init.q, 2, 0.0)))
    plant.SetVelocities(ctx, mp.v_to_drake(np.insert(init.dq, 2, 0.0)))
    sim = rp.simulator
    sim.get_mutable_context().SetTime(float(grid[0]))
    sim.Initialize()
    loads = _Loads(rp, model.params)
    R = {2: float(model.params.R_rear), 5: float(model.params.R_front)}
    acc_port = plant.get_generalized_acceleration_output_port()
    rows: list[tuple] = []

    def state():
        return (mp.q_from_drake(plant.GetPositions(ctx)), mp.v_from_drake(plant.GetVelocities(ctx)))

    def sample(t, T):
        x, v = state()
        loads.apply(T)
        ddq = mp.v_from_drake(acc_port.Eval(ctx))
        diag = (_disc_point(plant, ctx, rp.wheels[2], R[2])
                + _disc_point(plant, ctx, rp.wheels[5], R[5]) + _normal_forces(rp))
        rows.append((t, np.delete(x, 2), np.delete(v, 2), np.delete(ddq, 2),
                     np.asarray(T, float).reshape(3), diag))

    status, message = "completed", "reached the end of the grid"
    n_steps = per * (grid.size - 1)
    t0 = float(grid[0])
    sample(t0, torque_at(t0))
    solve0 = time.perf_counter()
    k = 0
    if abs(init.q[THETA]) >= fall_limit:
        status, message, n_steps = "fell", (f"|theta| = {abs(init.q[THETA]):.3f} rad >= fall "
                                            "limit at the start"), 0
    while k < n_steps:
        t_k = t0 + k * h
        T = torque_at(t_k)
        prev = (plant.GetPositions(ctx).copy(), plant.GetVelocities(ctx).copy())
        try:
            loads.apply(T)
            sim.AdvanceTo(t0 + (k + 1) * h)
        except RuntimeError as exc:
            status = "failed"
            message = (f"Drake stopped between t = {t_k:.6f} and {t_k + h:.6f} s: "
                       + " ".join(str(exc).split())[:200])
            break
        k += 1
        x = plant.GetPositions(ctx)
        if not (np.isfinite(x).all() and np.isfinite(plant.GetVelocities(ctx)).all()):
            status = "failed"
            message = f"Drake's state became non-finite after t = {rows[-1][0]:.6f} s"
            break
        theta = abs(x[i_theta])
        if theta >= fall_limit:
            th0 = abs(prev[0][i_theta])
            s = min(max((fall_limit - th0) / (theta - th0), 0.0), 1.0) if theta > th0 else 1.0
            plant.SetPositions(ctx, prev[0] + s * (x - prev[0]))
            plant.SetVelocities(ctx, prev[1] + s * (plant.GetVelocities(ctx) - prev[1]))
            t_event = t_k + s * h
            if t_event > rows[-1][0]:
                sample(t_event, torque_at(t_event))
            status = "fell"
            message = f"|theta| reached the fall limit {fall_limit:.4f} rad at t = {t_event:.6f} s"
            break
        if k % per == 0:
            t = float(grid[k // per])
            sample(t, torque_at(t))
            if progress is not None:
                progress(t)
    solve_seconds = time.perf_counter() - solve0

    t_out = np.array([r[0] for r in rows])
    q, dq, ddq, T_out = (np.array([r[i] for r in rows]) for i in (1, 2, 3, 4))
    diag = np.array([r[5] for r in rows], dtype=float).reshape(-1, 6)
    return Trajectory(
        t=t_out, q=q, dq=dq, ddq=ddq, C=model.constraint_residual(q, dq).reshape(-1, 5), T=T_out,
        status=status, message=message, t_end=float(t_out[-1]),
        settings={
            "engine": "drake", "drake_version": version("drake"), "contact": model.contact,
            **settings.as_dict(),
            "wheels": (f"cylinders of the wheel radii ({model.params.R_rear:g} m rear, "
                       f"{model.params.R_front:g} m front), half-width "
                       f"{settings.wheel_half_width:g} m, axis = the axle; ground: the half-space "
                       "z <= 0"),
            "rear_height_joint": ("zc, a prismatic z joint after yc (free: the rear wheel rests "
                                  "on its contact)"),
            "loads": "rider torques and drag as applied spatial forces, set before each step",
            "fall_limit": fall_limit, "grid": f"scenario grid (every {per} steps)",
            "ddq": "Drake's generalized acceleration (v_next - v) / h of the step after each sample",
            "C": "reference model's constraint_residual on the Drake states",
            "diagnostics": ("slip speed and penetration of each wheel's knife-edge disc at its "
                            "lowest point (the model's contact point); normal force per wheel"),
            "initial_correction": init.describe(), "beta_correction": init.beta_correction,
            "ignored_options": ignored,
        },
        timing={"wall_seconds": time.perf_counter() - wall0, "solve_seconds": solve_seconds,
                "steps": k},
        diagnostics={"slip_speed_rear": diag[:, 0], "penetration_rear": diag[:, 1],
                     "slip_speed_front": diag[:, 2], "penetration_front": diag[:, 3],
                     "normal_force_rear": diag[:, 4], "normal_force_front": diag[:, 5]},
    )
