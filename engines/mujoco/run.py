"""A forward scenario on MuJoCo with its own wheel-ground contact, as a `Trajectory`.

What is MuJoCo's and what is ours in a run:

* MuJoCo: the tree (the MJCF of `reference_model.export_mjcf` with the rear contact's height
  ``zc`` free, so the ground carries the rear wheel through its contact as it does the front
  one), gravity, the contact of each wheel (a thin cylinder of the wheel's radius) with the
  plane z = 0 — soft, frictional, with the settings of `MjcfSettings` — and the time stepping
  at the fixed ``timestep`` with its integrator.
* Ours: the start, the scenario's projected initial state (`initial_state`, the same for every
  engine; zc = 0, so both wheels touch the ground without penetration); the rider torques,
  single-sided as in the thesis, and the drag -cv |vG3| vG3 at the frame's CoM, as body wrenches
  (``xfrc_applied``) set before every step from that step's kinematics (``mj_step1``, then the
  loads, then ``mj_step2``; with RK4 they are held over the step's stages); the output on the
  scenario's grid (the steps land on its samples: the timestep must divide its interval); ddq,
  MuJoCo's own qacc at each sample's state (an ``mj_forward`` there, which does not change the
  run); the constraint residuals ``C``, evaluated by the reference model on MuJoCo's states;
  the contact diagnostics (below); the fall (|theta| >= fall_limit after a step ends the run;
  the event is interpolated linearly between the two steps around it, at most one timestep
  wide) and failures (MuJoCo resets a simulation whose accelerations or state become invalid
  and counts a warning: the run ends at the last sample before, status 'failed').

``Trajectory.diagnostics`` (each (N,) on the output grid), from the knife-edge disc of each wheel
(the model's wheel; the cylinder's caps are ``wheel_half_width`` either side of it):

* ``slip_speed_rear``, ``slip_speed_front`` (m/s): the horizontal speed of the wheel's material
  point at the disc's lowest point, rG - R n/|n| with n = e_z - (e_z . a) a, a the axle; zero
  for ideal rolling.
* ``penetration_rear``, ``penetration_front`` (m): how far that lowest point is below the
  ground (positive into the ground); zero for ideal rolling. The rear one is -zc.
* ``normal_force_rear``, ``normal_force_front`` (N): the ground's normal force on each wheel,
  summed over its contacts (``mj_contactForce``); zero when the wheel has lifted off (MuJoCo's
  contact is unilateral, the thesis's rolling constraint is not).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import time

import numpy as np

from reference_model.export_mjcf import MjcfSettings
from reference_model.scenarios import Scenario, initial_state, torque_input
from reference_model.solvers import Trajectory

from ..base import EngineUsageError
from ..stepping import forward_grid, steps_per_sample
from .options import tuple_option

import mujoco

# the run's chain: xc, yc, zc, phi, theta, psi, beta, gamma, eps
Q_OF_QPOS = np.array([0, 1, 3, 4, 5, 6, 7, 8])
ZC, THETA_QPOS = 2, 4
N_QPOS = 9
# options of the reference's simulate that have no meaning here; accepted and recorded
REFERENCE_ONLY = ("rtol", "atol", "constraints", "baumgarte")
# the warnings after which MuJoCo has reset the state (its data are no longer the run's)
RESET_WARNINGS = ("mjWARN_BADQACC", "mjWARN_BADQPOS", "mjWARN_BADQVEL")


class _Bicycle:
    """Indices and per-step arithmetic on one MjModel/MjData pair of the run's chain."""

    def __init__(self, m, params):
        body = lambda name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
        self.rear, self.frame = body("rear_wheel"), body("frame")
        self.fork, self.front = body("fork"), body("front_wheel")
        self.root = int(m.body_rootid[self.rear])
        self.R = {self.rear: float(params.R_rear), self.front: float(params.R_front)}
        self.cv = float(params.cv)

    def velocity(self, d, b, p):
        """(v, w): velocity of body b's material point p and b's angular velocity (world)."""
        w = d.cvel[b, :3]
        r = p - d.subtree_com[self.root]
        return d.cvel[b, 3:] + np.cross(w, r), w

    def loads(self, d, T) -> None:
        """Rider torques about body axes (steer z of the fork, pedal y of the rear wheel,
        anti-roll x of the frame, each on its body alone) and the drag at the frame's CoM, as
        world-frame wrenches on the bodies' CoMs, from d's current kinematics. Plain float
        arithmetic: this runs every step, and a numpy call on a 3-vector costs ~1-10 us."""
        T0, T1, T2 = T
        xm, x, fr = d.xmat, d.xfrc_applied, self.frame
        a = xm[self.fork].tolist()
        x[self.fork, 3:] = (T0 * a[2], T0 * a[5], T0 * a[8])
        a = xm[self.rear].tolist()
        x[self.rear, 3:] = (T1 * a[1], T1 * a[4], T1 * a[7])
        a = xm[fr].tolist()
        if not self.cv:
            x[fr, 3:] = (T2 * a[0], T2 * a[3], T2 * a[6])
            return
        wx, wy, wz, vx, vy, vz = d.cvel[fr].tolist()          # at the root subtree's CoM
        px, py, pz = (d.xipos[fr] - d.subtree_com[self.root]).tolist()
        vx, vy, vz = vx + wy * pz - wz * py, vy + wz * px - wx * pz, vz + wx * py - wy * px
        k = -self.cv * math.sqrt(vx * vx + vy * vy + vz * vz)
        x[fr] = (k * vx, k * vy, k * vz, T2 * a[0], T2 * a[3], T2 * a[6])

    def contact(self, d, b) -> tuple[float, float]:
        """(slip speed m/s, penetration m) of wheel b's disc at its lowest point."""
        a = d.xmat[b, 1::3]                         # axle: the body's y axis, world
        n = np.array([0.0, 0.0, 1.0]) - a[2] * a
        u = n / math.sqrt(float(n @ n))
        p = d.xpos[b] - self.R[b] * u
        v, _ = self.velocity(d, b, p)
        return math.hypot(v[0], v[1]), -float(p[2])

    def normal_forces(self, m, d) -> tuple[float, float]:
        """(rear, front) normal force of the ground on each wheel (N), summed over its contacts."""
        out = {self.rear: 0.0, self.front: 0.0}
        f = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            g = c.geom2 if m.geom_bodyid[c.geom1] == 0 else c.geom1   # the wheel's geom
            body = int(m.geom_bodyid[g])
            mujoco.mj_contactForce(m, d, i, f)
            out[body] = out.get(body, 0.0) + float(f[0])
        return out[self.rear], out[self.front]


@contextlib.contextmanager
def _mujoco_warnings():
    """MuJoCo's warning texts during the block, collected instead of printed (its default
    handler writes to stdout); the previous handler is restored after."""
    texts: list[str] = []
    before = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda text: texts.append(" ".join(str(text).split())))
    try:
        yield texts
    finally:
        mujoco.set_mju_user_warning(before)


def _torque_steps(torque, t_steps) -> np.ndarray:
    """torque(t) at every step (n, 3): one vectorised call where the function takes arrays
    (a spline does), else one call per step."""
    try:
        out = np.asarray(torque(t_steps), dtype=float)
        if out.shape == (t_steps.size, 3):
            return out
    except (TypeError, ValueError):
        pass
    return np.array([np.asarray(torque(t), dtype=float).reshape(3) for t in t_steps])


def simulate(engine, scenario: Scenario, **options) -> Trajectory:
    """Forward run of ``scenario`` from its projected initial state, on MuJoCo's contact.

    Options: ``fall_limit`` (rad, default the scenario's), ``t_end`` (s, stop early),
    ``progress`` (called with the time reached at every output sample), and any field of
    `MjcfSettings` to override the engine's for this run (timestep, solref, ...). The
    reference-only options rtol, atol, constraints, baumgarte are accepted and ignored (listed
    in ``settings['ignored_options']``). A bad option is an `EngineUsageError`, raised before
    anything runs."""
    wall0 = time.perf_counter()
    fall_limit = options.pop("fall_limit", scenario.fall_limit)
    t_end = options.pop("t_end", None)
    progress = options.pop("progress", None)
    ignored = {k: options.pop(k) for k in REFERENCE_ONLY if k in options}
    unknown = [k for k in options if k not in MjcfSettings.field_names()]
    if unknown:
        raise EngineUsageError(f"MuJoCo simulate got unknown option(s) {', '.join(unknown)}; it "
                               f"takes fall_limit, t_end, progress and "
                               f"{', '.join(MjcfSettings.field_names())}")
    if options:
        for k in ("solref", "solimp"):
            if k in options:
                options[k] = tuple_option(k, options[k])
        try:
            settings = dataclasses.replace(engine.settings, **options)
        except (TypeError, ValueError) as exc:
            raise EngineUsageError(f"MuJoCo option: {exc}") from None
        _, m = engine.run_model(settings)
    else:
        settings = engine.settings
        _, m = engine.run_model()
    grid, fall_limit = forward_grid(scenario, fall_limit, t_end, "MuJoCo")
    model = engine.model
    h = settings.timestep
    per = steps_per_sample(h, float(grid[1] - grid[0]), float(grid[-1] - grid[0]), "MuJoCo",
                           "timestep")

    init = initial_state(model, scenario)
    torque = torque_input(model, scenario)
    n_steps = per * (grid.size - 1)
    t_steps = grid[0] + h * np.arange(n_steps + 1)
    if callable(torque):
        T_steps = _torque_steps(torque, t_steps)
    else:
        T_steps = np.broadcast_to(np.asarray(torque, dtype=float).reshape(3), (n_steps + 1, 3))

    T_list = T_steps.tolist()
    d = mujoco.MjData(m)
    bike = _Bicycle(m, model.params)
    d.qpos[Q_OF_QPOS], d.qvel[Q_OF_QPOS] = init.q, init.dq
    d.time = float(grid[0])
    rk4 = settings.integrator == "RK4"
    warn = [int(getattr(mujoco.mjtWarning, w)) for w in RESET_WARNINGS]

    def reset() -> str:
        """The reset warnings MuJoCo has counted so far, by name ('' if none)."""
        return ", ".join(w for w, i in zip(RESET_WARNINGS, warn) if d.warning[i].number)

    rows_q, rows_dq, rows_ddq, rows_diag, rows_t, rows_T = [], [], [], [], [], []

    def sample(t, T):
        """Record the current state: an mj_forward with the loads gives qacc and kinematics."""
        mujoco.mj_forward(m, d)
        bike.loads(d, T)
        mujoco.mj_forward(m, d)
        rows_t.append(t)
        rows_T.append(np.array(T, dtype=float))
        rows_q.append(d.qpos.copy())
        rows_dq.append(d.qvel.copy())
        rows_ddq.append(d.qacc.copy())
        rows_diag.append(bike.contact(d, bike.rear) + bike.contact(d, bike.front)
                         + bike.normal_forces(m, d))

    with _mujoco_warnings() as mj_warnings:
        status, message = "completed", "reached the end of the grid"
        sample(float(grid[0]), T_steps[0])
        solve0 = time.perf_counter()
        prev_q, prev_v = d.qpos.copy(), d.qvel.copy()
        k = 0
        if abs(d.qpos[THETA_QPOS]) >= fall_limit:
            status = "fell"
            message = f"|theta| = {abs(d.qpos[THETA_QPOS]):.3f} rad >= fall limit at the start"
            n_steps = 0
        while k < n_steps:
            prev_q[:], prev_v[:] = d.qpos, d.qvel
            mujoco.mj_step1(m, d)
            bike.loads(d, T_list[k])
            if rk4:
                mujoco.mj_step(m, d)
            else:
                mujoco.mj_step2(m, d)
            k += 1
            theta = d.qpos[THETA_QPOS]
            at_sample = k % per == 0
            if (at_sample or abs(theta) >= fall_limit) and reset():
                # (checked at samples and at a fall only: a reset zeroes the state, so it cannot
                # fake a fall, and the run is cut at the last sample before it either way)
                status = "failed"
                message = (f"MuJoCo reset the simulation ({reset()}) between t = {rows_t[-1]:.6f} and "
                           f"{t_steps[k]:.6f} s; the run ends at the last sample before"
                           + (f" (MuJoCo: {mj_warnings[0]})" if mj_warnings else ""))
                break
            if abs(theta) >= fall_limit:
                th0 = abs(prev_q[THETA_QPOS])
                s = (fall_limit - th0) / (abs(theta) - th0) if abs(theta) > th0 else 1.0
                s = min(max(s, 0.0), 1.0)
                t_event = t_steps[k - 1] + s * h
                d.qpos[:] = prev_q + s * (d.qpos - prev_q)
                d.qvel[:] = prev_v + s * (d.qvel - prev_v)
                T_event = T_steps[k - 1] + s * (T_steps[k] - T_steps[k - 1])
                if t_event > rows_t[-1]:
                    sample(float(t_event), T_event)
                status = "fell"
                message = (f"|theta| reached the fall limit {fall_limit:.4f} rad at "
                           f"t = {t_event:.6f} s")
                break
            if at_sample:
                sample(float(grid[k // per]), T_steps[k])
                if progress is not None:
                    progress(float(grid[k // per]))
    solve_seconds = time.perf_counter() - solve0

    qpos = np.array(rows_q)
    ok = np.all(np.isfinite(qpos), axis=1) & np.all(np.isfinite(np.array(rows_dq)), axis=1) \
        & np.all(np.isfinite(np.array(rows_ddq)), axis=1)
    n = int(np.argmin(ok)) if not ok.all() else len(rows_t)
    if n < len(rows_t):
        status = "failed"
        message = f"MuJoCo's state became non-finite after t = {rows_t[n - 1]:.6f} s"
        n = max(n, 1)
    t_out = np.array(rows_t[:n])
    q = qpos[:n][:, Q_OF_QPOS]
    dq = np.array(rows_dq[:n])[:, Q_OF_QPOS]
    ddq = np.array(rows_ddq[:n])[:, Q_OF_QPOS]
    diag = np.array(rows_diag[:n], dtype=float).reshape(-1, 6)
    C = model.constraint_residual(q, dq).reshape(-1, 5)
    return Trajectory(
        t=t_out, q=q, dq=dq, ddq=ddq, C=C, T=np.array(rows_T[:n]), status=status, message=message,
        t_end=float(t_out[-1]),
        settings={
            "engine": "mujoco", "mujoco_version": mujoco.__version__, "contact": model.contact,
            **settings.as_dict(),
            "wheels": (f"cylinders of the wheel radii ({model.params.R_rear:g} m rear, "
                       f"{model.params.R_front:g} m front), half-width "
                       f"{settings.wheel_half_width:g} m, axis = the axle; ground: the plane z = 0"),
            "friction_coefficients": f"sliding {settings.friction:g}, torsional 0, rolling 0",
            "rear_height_joint": ("zc, a slide along z after yc (free: the rear wheel rests on "
                                  "its contact)"),
            "loads": ("rider torques and drag as xfrc_applied, set each step from mj_step1's "
                      "kinematics" + (" and held over the RK4 stages" if rk4 else "")),
            "fall_limit": fall_limit,
            "grid": f"scenario grid (every {per} steps)",
            "ddq": "MuJoCo's qacc at each sample's state (mj_forward with the loads)",
            "C": "reference model's constraint_residual on the MuJoCo states",
            "diagnostics": ("slip speed and penetration of each wheel's knife-edge disc at its "
                            "lowest point (the model's contact point); normal force per wheel"),
            "initial_correction": init.describe(), "beta_correction": init.beta_correction,
            "ignored_options": sorted(ignored),
        },
        timing={"wall_seconds": time.perf_counter() - wall0, "solve_seconds": solve_seconds,
                "steps": k},
        diagnostics={"slip_speed_rear": diag[:, 0], "penetration_rear": diag[:, 1],
                     "slip_speed_front": diag[:, 2], "penetration_front": diag[:, 3],
                     "normal_force_rear": diag[:, 4], "normal_force_front": diag[:, 5]},
    )
