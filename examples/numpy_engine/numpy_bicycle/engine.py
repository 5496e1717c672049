"""The bicycle in plain numpy, from the contract in docs/engines.md: a third party's engine.

Newton-Euler on joint axes, no symbolic algebra and no numerical differentiation:

* each coordinate moves the bodies after it in the chain along (xc, yc) or about (the others)
  a global axis through a point on it: phi about e_z and theta about Rz(phi) e_x, both through
  the rear contact C; psi and beta about the lean frame's y through the rear hub G2; gamma
  about the frame's z through the steering-axis point A; eps about the fork's y through the
  front hub G5;
* a material point P of body b therefore has the velocity Jacobian columns axis_k x (P - o_k)
  (revolute) or axis_k (prismatic) and the angular-velocity columns axis_k, for the
  coordinates k on b's chain;
* the velocity-product ("bias") accelerations at ddq = 0 follow by differentiating those
  columns once: an axis fixed in frame f turns with f's angular velocity, d axis/dt = w_f x
  axis, and d/dt (axis x (P - o)) = d axis/dt x (P - o) + axis x (v_P - v_o);
* M = sum_b m_b Jv^T Jv + Jw^T I_b,global Jw, Qv = -sum_b m_b Jv^T a_bias + Jw^T (I alpha_bias
  + w x I w), the gravity, drag and rider-torque forces from the same Jacobians;
* the constraint rows [rD_z, vC_x, vC_y, vD_x, vD_y] straight from their definitions, D from
  their linearity in dq (column k = the rows at dq = e_k), dD dq by differentiating them once
  more in time at ddq = 0;
* ``simulate``: the scenario's initial state and torques from the harness, Baumgarte
  stabilization, DOP853 (scipy) with dense output on the grid, the statuses of the contract.

Options: ``bug`` plants a derivation error, for showing that the harness localizes it:
``"gyroscopic"`` drops the gyroscopic torques w x I w from Qv, ``"I3xz-sign"`` flips the sign
of the frame's product of inertia. `BuggyNumpyEngine` is the first one as its own class.

Self-contained on purpose (numpy and `engines.base` only, no relative imports) so that it also
loads as ``path/to/engine.py:NumpyEngine``.
"""

from __future__ import annotations

import numpy as np

from engines.base import Engine, EngineError, EngineSpecError

N_Q, N_C = 8, 5
XC, YC, PHI, THETA, PSI, BETA, GAMMA, EPS = range(N_Q)
E_X, E_Y, E_Z = np.eye(3)
BUGS = (None, "gyroscopic", "I3xz-sign")
# the coordinates on each body's chain, from the ground out
CHAIN = {2: (XC, YC, PHI, THETA, PSI), 3: (XC, YC, PHI, THETA, BETA),
         4: (XC, YC, PHI, THETA, BETA, GAMMA), 5: (XC, YC, PHI, THETA, BETA, GAMMA, EPS)}


def cross(a, b):
    """a x b for two 3-vectors (np.cross's generality costs ~10x for single vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class _State:
    """Kinematics of one state: rotations, points, axes, velocities and bias accelerations."""

    def __init__(self, e: "NumpyEngine", q, dq):
        p = e.p
        self.q, self.dq = q, dq
        self._jac = {}
        Ryaw = rot_z(q[PHI])
        Alean = Ryaw @ rot_x(q[THETA])
        A = {2: Alean @ rot_y(q[PSI]), 3: Alean @ rot_y(q[BETA])}
        A[4] = A[3] @ rot_z(q[GAMMA])
        A[5] = A[4] @ rot_y(q[EPS])
        self.A = A
        rC = np.array([q[XC], q[YC], 0.0])
        rG2 = rC + Alean @ np.array([0.0, 0.0, p.R_rear])
        rA = rG2 + A[3] @ np.array([p.xa, 0.0, p.za])
        rG5 = rA + A[4] @ np.array([p.x5, 0.0, p.z5])
        self.com = {2: rG2, 3: rG2 + A[3] @ np.array([p.x3, 0.0, p.z3]),
                    4: rA + A[4] @ np.array([p.dx4, 0.0, p.dz4]), 5: rG5}
        self.rC, self.rG5 = rC, rG5
        # joint axes (global) and a point on each axis; the frame each axis is fixed in
        self.axis = {XC: E_X, YC: E_Y, PHI: E_Z, THETA: Ryaw @ E_X, PSI: Alean @ E_Y,
                     BETA: Alean @ E_Y, GAMMA: A[3] @ E_Z, EPS: A[4] @ E_Y}
        self.origin = {PHI: rC, THETA: rC, PSI: rG2, BETA: rG2, GAMMA: rA, EPS: rG5}
        # angular velocities of the frames the axes are fixed in
        w_yaw = E_Z * dq[PHI]
        w_lean = w_yaw + self.axis[THETA] * dq[THETA]
        self.w = {2: w_lean + self.axis[PSI] * dq[PSI], 3: w_lean + self.axis[BETA] * dq[BETA]}
        self.w[4] = self.w[3] + self.axis[GAMMA] * dq[GAMMA]
        self.w[5] = self.w[4] + self.axis[EPS] * dq[EPS]
        carrier = {PHI: np.zeros(3), THETA: w_yaw, PSI: w_lean, BETA: w_lean,
                   GAMMA: self.w[3], EPS: self.w[4]}
        self.daxis = {k: cross(carrier[k], self.axis[k]) for k in carrier}
        self.daxis[XC] = self.daxis[YC] = np.zeros(3)
        # velocities of the axis points (rC moves with xc, yc only)
        v_rC = np.array([dq[XC], dq[YC], 0.0])
        self.v_origin = {PHI: v_rC, THETA: v_rC}
        self.v_origin[PSI] = self.v_origin[BETA] = self.velocity(2, rG2)
        self.v_origin[GAMMA] = self.velocity(3, rA)
        self.v_origin[EPS] = self.velocity(4, rG5)
        self.v_rC = v_rC

    # -- a material point P of body b -------------------------------------------------------
    def jacobians(self, b: int, P):
        """(Jv (3x8) of b's material point at P, Jw (3x8) of b); cached per state."""
        key = (b, P.tobytes())
        if key in self._jac:
            return self._jac[key]
        Jv, Jw = np.zeros((3, N_Q)), np.zeros((3, N_Q))
        for k in CHAIN[b]:
            if k in (XC, YC):
                Jv[:, k] = self.axis[k]
            else:
                Jv[:, k] = cross(self.axis[k], P - self.origin[k])
                Jw[:, k] = self.axis[k]
        self._jac[key] = Jv, Jw
        return Jv, Jw

    def velocity(self, b: int, P):
        return self.jacobians(b, P)[0] @ self.dq

    def bias(self, b: int, P):
        """(a_bias, alpha_bias): d/dt (Jv dq), d/dt (Jw dq) at ddq = 0, P material in b."""
        vP = self.velocity(b, P)
        a, al = np.zeros(3), np.zeros(3)
        for k in CHAIN[b]:
            if k in (XC, YC):
                continue
            d = self.dq[k]
            a += (cross(self.daxis[k], P - self.origin[k])
                  + cross(self.axis[k], vP - self.v_origin[k])) * d
            al += self.daxis[k] * d
        return a, al


class NumpyEngine(Engine):
    """The bicycle by Newton-Euler on joint axes in plain numpy."""

    name = "numpy-bicycle"
    capabilities = frozenset({"mass_matrix", "inverse_dynamics", "gravity", "generalized_forces",
                              "constraint_jacobian", "constraint_bias", "forward_acceleration",
                              "simulate"})
    contacts = ("thesis", "disc")

    def __init__(self, model, bug: str | None = None):
        super().__init__(model)
        if bug not in BUGS:
            raise EngineSpecError(f"option bug={bug!r} is not one of "
                                  f"{', '.join(repr(b) for b in BUGS)}")
        self.bug = bug
        self.p = model.params
        self.disc = model.contact == "disc"
        p = self.p
        I3xz = -p.I3xz if bug == "I3xz-sign" else p.I3xz
        self.mass = {2: p.m2, 3: p.m3, 4: p.m4, 5: p.m5}
        self.inertia = {2: np.diag([p.I2xx, p.I2yy, p.I2zz]),
                        3: np.array([[p.I3xx, 0, I3xz], [0, p.I3yy, 0], [I3xz, 0, p.I3zz]]),
                        4: np.array([[p.I4xx, 0, p.I4xz], [0, p.I4yy, 0], [p.I4xz, 0, p.I4zz]]),
                        5: np.diag([p.I5xx, p.I5yy, p.I5zz])}

    # -- batches: one state (8,) or N states (N, 8) ---------------------------------------
    @staticmethod
    def _each(fn, *arrays):
        first = np.asarray(arrays[0], dtype=float)
        if first.ndim == 1:
            return fn(*(np.asarray(a, dtype=float) for a in arrays))
        rows = [np.broadcast_to(np.asarray(a, dtype=float), (first.shape[0], np.shape(a)[-1]))
                for a in arrays]
        return np.array([fn(*r) for r in zip(*rows)])

    # -- dynamics -------------------------------------------------------------------------
    def _global_inertia(self, s: _State, b: int):
        return s.A[b] @ self.inertia[b] @ s.A[b].T

    def _M(self, q, s: _State | None = None):
        s = s or _State(self, q, np.zeros(N_Q))
        M = np.zeros((N_Q, N_Q))
        for b in (2, 3, 4, 5):
            Jv, Jw = s.jacobians(b, s.com[b])
            M += self.mass[b] * Jv.T @ Jv + Jw.T @ self._global_inertia(s, b) @ Jw
        return M

    def _Qv(self, s: _State):
        Q = np.zeros(N_Q)
        for b in (2, 3, 4, 5):
            Jv, Jw = s.jacobians(b, s.com[b])
            a, al = s.bias(b, s.com[b])
            Ig = self._global_inertia(s, b)
            torque = Ig @ al
            if self.bug != "gyroscopic":
                torque = torque + cross(s.w[b], Ig @ s.w[b])
            Q -= self.mass[b] * Jv.T @ a + Jw.T @ torque
        return Q

    def _Qgrav(self, s: _State):
        Q = np.zeros(N_Q)
        for b in (2, 3, 4, 5):
            Jv, _ = s.jacobians(b, s.com[b])
            Q += Jv.T @ np.array([0.0, 0.0, -self.mass[b] * self.p.g])
        return Q

    def _applied(self, s: _State, T):
        """Drag at the frame's CoM and the three single-sided rider torques."""
        Jv3, Jw3 = s.jacobians(3, s.com[3])
        v3 = Jv3 @ s.dq
        Q = -self.p.cv * np.sqrt(v3 @ v3) * (Jv3.T @ v3)
        Jw4, Jw2 = s.jacobians(4, s.com[4])[1], s.jacobians(2, s.com[2])[1]
        Q += Jw4.T @ (s.A[4] @ E_Z) * T[0]     # Mdir: steer, on the fork about its z
        Q += Jw2.T @ (s.A[2] @ E_Y) * T[1]     # Mped: pedal, on the rear wheel about its y
        Q += Jw3.T @ (s.A[3] @ E_X) * T[2]     # Mvue: anti-roll, on the frame about its x
        return Q

    def mass_matrix(self, q):
        return self._each(self._M, q)

    def gravity(self, q):
        return self._each(lambda q: self._Qgrav(_State(self, q, np.zeros(N_Q))), q)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        def one(q, dq, T):
            s = _State(self, q, dq)
            return self._Qv(s) + self._Qgrav(s) + self._applied(s, T)
        return self._each(one, q, dq, torques)

    def inverse_dynamics(self, q, dq, ddq):
        def one(q, dq, ddq):
            s = _State(self, q, dq)
            return self._M(q, s) @ ddq - self._Qv(s) - self._Qgrav(s)
        return self._each(one, q, dq, ddq)

    # -- rolling contact --------------------------------------------------------------------
    def _front_direction(self, s: _State):
        """u with rD = rG5 - R_front u: the fork's z axis (thesis) or, for the disc, the unit
        vector from the lowest rim point to the hub, n/|n| with n = e_z - (e_z . a) a and a
        the wheel's axle (the fork's y axis)."""
        if not self.disc:
            return s.A[4] @ E_Z
        a = s.A[4] @ E_Y
        n = E_Z - a[2] * a
        return n / np.sqrt(n @ n)

    def _front_rate(self, s: _State, w4):
        """du/dt for the fork's angular velocity w4 (linear in w4; w4 may be (3,) or (8, 3))."""
        if not self.disc:
            return np.cross(w4, s.A[4] @ E_Z)
        a = s.A[4] @ E_Y
        n = E_Z - a[2] * a
        m = np.sqrt(n @ n)
        da = np.cross(w4, a)
        dn = -(da[..., 2:3] * a + a[2] * da)
        dm = (dn @ n)[..., None] / m
        return (dn - (n / m) * dm) / m

    def _front_bias(self, s: _State):
        """d2u/dt2 at ddq = 0 (the fork's bias angular acceleration alpha4 enters)."""
        _, al4 = s.bias(4, s.com[4])
        w4 = s.w[4]
        if not self.disc:
            u = s.A[4] @ E_Z
            du = cross(w4, u)
            return cross(al4, u) + cross(w4, du)
        a = s.A[4] @ E_Y
        da = cross(w4, a)
        dda = cross(al4, a) + cross(w4, da)
        n = E_Z - a[2] * a
        dn = -(da[2] * a + a[2] * da)
        ddn = -(dda[2] * a + 2.0 * da[2] * da + a[2] * dda)
        m = np.sqrt(n @ n)
        dm = (n @ dn) / m
        ddm = (dn @ dn + n @ ddn - dm * dm) / m
        u = n / m
        du = (dn - u * dm) / m
        return (ddn - 2.0 * du * dm - u * ddm) / m

    def _D(self, q, s: _State | None = None):
        """Rows [d rD_z/dt, vC_x, vC_y, vD_x, vD_y] are linear in dq: D from the Jacobians
        (which do not depend on dq: any state at q will do)."""
        s = s or _State(self, q, np.zeros(N_Q))
        R = self.p.R_front
        rD = s.rG5 - R * self._front_direction(s)
        JvG5, _ = s.jacobians(5, s.rG5)
        _, Jw4 = s.jacobians(4, s.com[4])
        JvC, _ = s.jacobians(2, s.rC)           # rear wheel's material point at C
        JvD, _ = s.jacobians(5, rD)             # front wheel's material point at D
        du = self._front_rate(s, Jw4.T)         # (8, 3): du/dt at dq = e_k
        return np.vstack([JvG5[2] - R * du[:, 2], JvC[0], JvC[1], JvD[0], JvD[1]])

    def _bias(self, s: _State):
        """dD dq: the rows' time derivative at ddq = 0: the material points' bias accelerations
        plus the contact points' own motion through the wheels (rC with xc, yc; rD with u)."""
        R = self.p.R_front
        u = self._front_direction(s)
        du = self._front_rate(s, s.w[4])
        rD = s.rG5 - R * u
        vG5 = s.velocity(5, s.rG5)
        aG2, al2 = s.bias(2, s.com[2])
        aG5, al5 = s.bias(5, s.rG5)
        bC = aG2 + cross(al2, s.rC - s.com[2]) + cross(s.w[2], s.v_rC - s.velocity(2, s.com[2]))
        bD = aG5 + cross(al5, rD - s.rG5) + cross(s.w[5], (vG5 - R * du) - vG5)
        return np.array([aG5[2] - R * self._front_bias(s)[2], bC[0], bC[1], bD[0], bD[1]])

    def constraint_jacobian(self, q):
        return self._each(self._D, q)

    def constraint_bias(self, q, dq):
        return self._each(lambda q, dq: self._bias(_State(self, q, dq)), q, dq)

    def _accelerations(self, q, dq, T, a1=0.0, a2=0.0):
        """ddq from [M D^T; D 0] [ddq; lambda] = [F; -dD dq - 2 a1 D dq - a2^2 C] (Baumgarte
        with a1 = a2 = 0 is the exact constrained motion); and the residuals C."""
        s = _State(self, q, dq)
        F = self._Qv(s) + self._Qgrav(s) + self._applied(s, T)
        D, bias = self._D(q, s), self._bias(s)
        Ddq = D @ dq
        C = np.concatenate([[(s.rG5 - self.p.R_front * self._front_direction(s))[2]], Ddq[1:]])
        K = np.zeros((N_Q + N_C, N_Q + N_C))
        K[:N_Q, :N_Q], K[:N_Q, N_Q:], K[N_Q:, :N_Q] = self._M(q, s), D.T, D
        ddq = np.linalg.solve(K, np.concatenate([F, -bias - 2.0 * a1 * Ddq - a2 * a2 * C]))[:N_Q]
        if not np.all(np.isfinite(ddq)):
            raise FloatingPointError("non-finite accelerations")
        return ddq, C

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._each(lambda q, dq, T: self._accelerations(q, dq, T)[0], q, dq, torques)

    # -- a forward run ------------------------------------------------------------------------
    def simulate(self, scenario, *, t_end=None, fall_limit=1.4, rtol=1e-10, atol=1e-12):
        """A forward scenario with Baumgarte stabilization (the scenario's a1, a2), DOP853 with
        dense output on the scenario's grid; stops at |theta| = fall_limit ('fell') or when the
        integrator or the linear solve fails ('failed', with the trajectory so far)."""
        from scipy.integrate import DOP853
        from scipy.optimize import brentq

        from reference_model.scenarios import initial_state, torque_input
        from reference_model.solvers import Trajectory

        if scenario.kind != "forward":
            raise EngineError(f"{scenario.name!r} is not a forward scenario")
        if scenario.constraints != "baumgarte":
            raise EngineError(f"this engine integrates with Baumgarte stabilization only; scenario "
                              f"{scenario.name!r} asks for {scenario.constraints!r}")
        a1, a2 = (float(a) for a in scenario.baumgarte)
        init = initial_state(self.model, scenario)
        given = torque_input(self.model, scenario)
        torque = given if callable(given) else (lambda t, T=np.asarray(given, float): T)
        grid = scenario.t if t_end is None else scenario.t[scenario.t <= t_end + 1e-12]

        def rhs(t, y):
            return np.concatenate([y[N_Q:], self._accelerations(y[:N_Q], y[N_Q:], torque(t), a1, a2)[0]])

        y0 = np.concatenate([init.q, init.dq])
        # Baumgarte's decay rate 2 a1 + a2^2 bounds the explicit step (stability region ~3/rate)
        rate = 2 * a1 + a2 * a2
        solver = DOP853(rhs, grid[0], y0, grid[-1], rtol=rtol, atol=atol,
                        max_step=3.0 / rate if rate > 0 else np.inf)
        ts, ys = [grid[0]], [y0]
        status, message, i = "completed", "reached the end of the grid", 1
        while status == "completed" and solver.status == "running":
            try:
                solver.step()
            except (np.linalg.LinAlgError, FloatingPointError) as exc:
                status, message = "failed", f"right-hand side failed after t = {solver.t:.6f} s: {exc}"
                break
            if solver.status == "failed":
                status, message = "failed", f"integrator failed at t = {solver.t:.6f} s"
                break
            sol, t_stop = solver.dense_output(), solver.t
            if abs(solver.y[THETA]) >= fall_limit:
                sign = np.sign(solver.y[THETA])
                t_stop = brentq(lambda t: sign * sol(t)[THETA] - fall_limit, solver.t_old, solver.t)
                status, message = "fell", f"|theta| reached {fall_limit} rad at t = {t_stop:.6f} s"
            while i < grid.size and grid[i] <= t_stop:
                ts.append(grid[i])
                ys.append(sol(grid[i]))
                i += 1
            if status == "fell" and ts[-1] < t_stop:
                ts.append(t_stop)
                ys.append(sol(t_stop))
        t, Y = np.array(ts), np.array(ys)
        T = np.array([torque(tk) for tk in t]).reshape(-1, 3)
        out = []
        for k, (y, Tk) in enumerate(zip(Y, T)):     # ddq and C at the samples; cut where they fail
            try:
                out.append(self._accelerations(y[:N_Q], y[N_Q:], Tk, a1, a2))
            except (np.linalg.LinAlgError, FloatingPointError) as exc:
                status, message = "failed", f"accelerations failed at t = {t[k]:.6f} s: {exc}"
                t, Y, T = t[:k], Y[:k], T[:k]
                break
        return Trajectory(t=t, q=Y[:, :N_Q], dq=Y[:, N_Q:],
                          ddq=np.array([o[0] for o in out]).reshape(-1, N_Q),
                          C=np.array([o[1] for o in out]).reshape(-1, N_C), T=T, status=status,
                          message=message, t_end=float(t[-1]) if t.size else float(grid[0]),
                          settings={"integrator": "DOP853", "rtol": rtol, "atol": atol,
                                    "constraints": "baumgarte", "baumgarte": [a1, a2],
                                    "fall_limit": fall_limit})


class BuggyNumpyEngine(NumpyEngine):
    """The same engine with a planted derivation bug: Qv without the gyroscopic torques."""

    name = "numpy-bicycle-buggy"

    def __init__(self, model, bug: str | None = "gyroscopic"):
        super().__init__(model, bug=bug)
