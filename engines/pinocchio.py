"""The thesis bicycle rebuilt in Pinocchio: CRBA, RNEA, and rolling constraints from its
kinematics alone.

The tree maps one-to-one onto the thesis's coordinates (asserted at build time):

    universe -> PX (xc) -> PY (yc) -> RZ (phi) -> RX (theta) -+-> RY (psi)   rear wheel, at [0, 0, R_rear]
                                                             +-> RY (beta)  frame, at [0, 0, R_rear]
                                                                  -> RZ (gamma) fork, at [xa, 0, za]
                                                                       -> RY (eps) front wheel, at [x5, 0, z5]

Each body's inertia goes in at its CoM in body axes; the yawed and leaned links are massless.
Everything is built from the `reference_model.Model`'s parameters.

What comes from Pinocchio and what from here:

* M from ``crba`` (upper triangle, symmetrised); ``rnea(q, v, a) = M a - Qv - Qgrav``;
  gravity from ``computeGeneralizedGravity`` (= -Qgrav).
* Rolling constraints: Pinocchio has no rolling contact, so D is assembled from joint
  Jacobians (``LOCAL_WORLD_ALIGNED``) shifted to the current contact points: the rear contact
  rC on the rear wheel, the front contact rD on the front wheel (the thesis's fork-axis point
  or the disc's lowest point, per the model's contact variant); the holonomic row is the
  vertical velocity of the fork's material point at rD (for the thesis contact rD is fixed in
  the fork; for the disc the rim slides through rD horizontally, so the vertical rate is the
  same). dD dq from classical accelerations (``forwardKinematics(q, v, 0)``) plus the contact
  point's own motion: for a material point of body b at a moving point p(q),
  d/dt (J_p dq)|_{ddq=0} = a_p + w_b x (dp/dt - v_p).
* Drag as a force at the frame's CoM through its point Jacobian; rider torques as
  single-body torques through the body-axis angular Jacobians (single-sided, as the thesis).

The engine also offers the duck-typed methods the reference solvers use (``forward``,
``constraint_residual``, ``inverse_dynamics_step``...), so inverse kinematics, the 13x13 inverse
dynamics and forward runs use the same code and integrator as the reference, on Pinocchio's terms.
"""

from __future__ import annotations

import numpy as np

from reference_model import COORDINATES, Model
from reference_model.model import DEP, IND, ForwardResult, raise_on_status, torque_array
from reference_model.scenarios import Scenario, run_forward, run_inverse

from .base import CAPABILITIES, Engine, EngineError

try:
    import pinocchio as pin
except ImportError as exc:  # pragma: no cover - pin is a declared dependency
    raise EngineError("the Pinocchio adapter needs the package 'pin' (pip install pin)") from exc

N_Q, N_C = 8, 5
# joint ids in the Pinocchio model (0 is the universe)
J_XC, J_YC, J_PHI, J_THETA, J_PSI, J_BETA, J_GAMMA, J_EPS = range(1, 9)
E_Z = np.array([0.0, 0.0, 1.0])


def _cross(a, b) -> np.ndarray:
    """a x b for 3-vectors (np.cross's axis handling costs ~25 us a call: 60 % of a forward
    run's time before this)."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def build_pinocchio_model(model: Model) -> "pin.Model":
    """The thesis tree with the model's parameters; joint order = the thesis's q order."""
    p = model.params
    pm = pin.Model()
    pm.name = f"bicycle-{model.name}"
    I3 = pin.SE3.Identity()

    def at(x, y, z):
        return pin.SE3(np.eye(3), np.array([x, y, z], dtype=float))

    def inertia(body, com):
        return pin.Inertia(getattr(p, f"m{body}"), np.asarray(com, dtype=float), p.inertia(body))

    j = pm.addJoint(0, pin.JointModelPX(), I3, "xc")
    j = pm.addJoint(j, pin.JointModelPY(), I3, "yc")
    j = pm.addJoint(j, pin.JointModelRZ(), I3, "phi")
    j_theta = pm.addJoint(j, pin.JointModelRX(), I3, "theta")
    j_psi = pm.addJoint(j_theta, pin.JointModelRY(), at(0, 0, p.R_rear), "psi")
    pm.appendBodyToJoint(j_psi, inertia(2, [0, 0, 0]), I3)
    j_beta = pm.addJoint(j_theta, pin.JointModelRY(), at(0, 0, p.R_rear), "beta")
    pm.appendBodyToJoint(j_beta, inertia(3, [p.x3, 0, p.z3]), I3)
    j_gamma = pm.addJoint(j_beta, pin.JointModelRZ(), at(p.xa, 0, p.za), "gamma")
    pm.appendBodyToJoint(j_gamma, inertia(4, [p.dx4, 0, p.dz4]), I3)
    j_eps = pm.addJoint(j_gamma, pin.JointModelRY(), at(p.x5, 0, p.z5), "eps")
    pm.appendBodyToJoint(j_eps, inertia(5, [0, 0, 0]), I3)
    pm.gravity = pin.Motion(np.array([0.0, 0.0, -p.g]), np.zeros(3))
    names = tuple(pm.names[1:])
    if names != COORDINATES or list(pm.idx_qs[1:]) != list(range(N_Q)) \
            or list(pm.idx_vs[1:]) != list(range(N_Q)):
        raise EngineError(f"Pinocchio joint order {names} / idx_q {list(pm.idx_qs[1:])} does not "
                          f"follow the thesis order {COORDINATES}")
    return pm


class PinocchioEngine(Engine):
    """Mass matrix, RNEA, gravity, rolling constraints, forces and forward runs from Pinocchio."""

    name = "pinocchio"
    capabilities = frozenset(CAPABILITIES)

    def __init__(self, model: Model):
        super().__init__(model)
        self.pin_model = build_pinocchio_model(model)
        self.data = self.pin_model.createData()
        p = model.params
        self._R_front = p.R_front
        self._cv = p.cv
        self._com3 = np.array([p.x3, 0.0, p.z3])
        self._disc = model.contact == "disc"
        # duck-typed attributes the reference solvers read
        self.params, self.contact = p, model.contact
        self.coordinates = COORDINATES

    # -- batching ----------------------------------------------------------------------
    @staticmethod
    def _batched(fn, *arrays):
        first = np.asarray(arrays[0], dtype=float)
        if first.ndim == 1:
            return fn(*(np.asarray(a, dtype=float) for a in arrays))
        arrs = [np.broadcast_to(np.asarray(a, dtype=float), (first.shape[0], np.shape(a)[-1]))
                for a in arrays]
        return np.array([fn(*row) for row in zip(*arrs)])

    # -- rigid-body terms --------------------------------------------------------------
    def _M(self, q):
        M = pin.crba(self.pin_model, self.data, q)
        return np.triu(M) + np.triu(M, 1).T

    def mass_matrix(self, q):
        return self._batched(self._M, q)

    def inverse_dynamics(self, q, dq, ddq):
        return self._batched(lambda a, b, c: pin.rnea(self.pin_model, self.data, a, b, c).copy(),
                             q, dq, ddq)

    def gravity(self, q):
        return self._batched(
            lambda a: -pin.computeGeneralizedGravity(self.pin_model, self.data, a).copy(), q)

    def _bias_forces(self, q, dq):
        """Qv + Qgrav = -rnea(q, dq, 0)."""
        return -pin.rnea(self.pin_model, self.data, q, dq, np.zeros(N_Q))

    def _applied(self, q, dq, T):
        """Qaero + S T from Pinocchio's Jacobians (kinematics must be current for q)."""
        pm, d = self.pin_model, self.data
        J3 = pin.getJointJacobian(pm, d, J_BETA, pin.LOCAL_WORLD_ALIGNED)
        o3 = d.oMi[J_BETA]
        r = o3.rotation @ self._com3
        Jg3 = J3[:3] - _skew(r) @ J3[3:]
        vG3 = Jg3 @ dq
        Q = -self._cv * np.linalg.norm(vG3) * (Jg3.T @ vG3)
        # single-sided rider torques about body axes: steer z4 on the fork, pedal y2 on the
        # rear wheel, anti-roll x3 on the frame
        for joint, axis, tau in ((J_GAMMA, 2, T[0]), (J_PSI, 1, T[1]), (J_BETA, 0, T[2])):
            if tau != 0.0:
                Jl = pin.getJointJacobian(pm, d, joint, pin.LOCAL)
                Q = Q + Jl[3 + axis] * tau
        return Q

    def S(self, q):
        def one(q):
            pin.computeJointJacobians(self.pin_model, self.data, q)
            cols = [pin.getJointJacobian(self.pin_model, self.data, j, pin.LOCAL)[3 + ax]
                    for j, ax in ((J_GAMMA, 2), (J_PSI, 1), (J_BETA, 0))]
            return np.stack(cols, axis=1)
        return self._batched(one, q)

    def Qaero(self, q, dq):
        def one(q, dq):
            pin.computeJointJacobians(self.pin_model, self.data, q)
            return self._applied(q, dq, (0.0, 0.0, 0.0))
        return self._batched(one, q, dq)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        def one(q, dq, T):
            F = self._bias_forces(q, dq)
            pin.computeJointJacobians(self.pin_model, self.data, q)
            return F + self._applied(q, dq, T)
        single = np.ndim(q) == 1
        T = torque_array(torques, 1 if single else np.shape(q)[0], single)
        return self._batched(one, q, dq, T[0] if single else T)

    # -- rolling constraints -----------------------------------------------------------
    def _contact_geometry(self):
        """Front contact point rD and, for the disc, the pieces of its time derivative."""
        d = self.data
        rG5 = d.oMi[J_EPS].translation
        R4 = d.oMi[J_GAMMA].rotation
        if not self._disc:
            return rG5 - self._R_front * R4[:, 2]
        a = R4[:, 1]
        n = E_Z - a[2] * a
        return rG5 - self._R_front * n / np.linalg.norm(n)

    def _point(self, joint, p, frame=pin.LOCAL_WORLD_ALIGNED):
        """Point Jacobian (3x8) of body `joint`'s material point at p, and its w, v_p."""
        d = self.data
        J = pin.getJointJacobian(self.pin_model, d, joint, frame)
        r = p - d.oMi[joint].translation
        return J[:3] - _skew(r) @ J[3:], J[3:], r

    def _constraints(self, q, dq, with_bias: bool):
        pm, d = self.pin_model, self.data
        pin.forwardKinematics(pm, d, q, dq, np.zeros(N_Q))
        pin.computeJointJacobians(pm, d, q)
        rC = np.array([q[0], q[1], 0.0])
        rD = self._contact_geometry()
        JC, wJ2, rC2 = self._point(J_PSI, rC)
        JD5, wJ5, rD5 = self._point(J_EPS, rD)
        JD4, wJ4, rD4 = self._point(J_GAMMA, rD)
        D = np.vstack([JD4[2], JC[0], JC[1], JD5[0], JD5[1]])
        vC, vD5, vD4 = JC @ dq, JD5 @ dq, JD4 @ dq
        C = np.array([rD[2], vC[0], vC[1], vD5[0], vD5[1]])
        if not with_bias:
            return C, D, None
        lwa = pin.LOCAL_WORLD_ALIGNED

        def material_accel(joint, r):
            a = pin.getClassicalAcceleration(pm, d, joint, lwa)
            w = pin.getVelocity(pm, d, joint, lwa).angular
            return a.linear + _cross(a.angular, r) + _cross(w, _cross(w, r)), w, a.angular

        aC, w2, _ = material_accel(J_PSI, rC2)
        aD5, w5, _ = material_accel(J_EPS, rD5)
        aD4, w4, al4 = material_accel(J_GAMMA, rD4)
        # the contact points' own motion: rC = [xc, yc, 0]; rD fixed in the fork (thesis) or
        # the disc's lowest point rG5 - R u, u = n/|n|, n = e_z - a_z a, a = fork y axis
        pC = np.array([dq[0], dq[1], 0.0])
        if not self._disc:
            pD, ppD_z = vD4, aD4[2]
        else:
            a = d.oMi[J_GAMMA].rotation[:, 1]
            da = _cross(w4, a)
            dda = _cross(al4, a) + _cross(w4, da)
            n = E_Z - a[2] * a
            dn = -(da[2] * a + a[2] * da)
            ddn = -(dda[2] * a + 2 * da[2] * da + a[2] * dda)
            m = np.linalg.norm(n)
            u = n / m
            dm = u @ dn
            du = (dn - u * dm) / m
            ddm = du @ dn + u @ ddn
            ddu = (ddn - 2 * du * dm - u * ddm) / m
            aG5 = material_accel(J_EPS, np.zeros(3))[0]
            vG5 = pin.getVelocity(pm, d, J_EPS, lwa).linear
            pD = vG5 - self._R_front * du
            ppD_z = aG5[2] - self._R_front * ddu[2]
        bC = aC + _cross(w2, pC - vC)
        bD = aD5 + _cross(w5, pD - vD5)
        bias = np.array([ppD_z, bC[0], bC[1], bD[0], bD[1]])
        return C, D, bias

    def constraint_residual(self, q, dq):
        return self._batched(lambda a, b: self._constraints(a, b, False)[0], q, dq)

    def constraint_jacobian(self, q):
        return self._batched(lambda a: self._constraints(a, np.zeros(N_Q), False)[1], q)

    def constraint_bias(self, q, dq):
        return self._batched(lambda a, b: self._constraints(a, b, True)[2], q, dq)

    # -- the thesis's linear systems on Pinocchio's terms ---------------------------------
    def _forward_one(self, q, dq, T, a1, a2):
        C, D, bias = self._constraints(q, dq, True)
        F = self._applied(q, dq, T) + self._bias_forces(q, dq)
        M = self._M(q)
        K = np.zeros((N_Q + N_C, N_Q + N_C))
        K[:N_Q, :N_Q], K[:N_Q, N_Q:], K[N_Q:, :N_Q] = M, D.T, D
        rhs = np.concatenate([F, -bias - 2 * a1 * (D @ dq) - a2 * a2 * C])
        try:
            x = np.linalg.solve(K, rhs)
        except np.linalg.LinAlgError:
            return np.zeros(N_Q), np.zeros(N_C), 1
        ok = np.all(np.isfinite(x))
        return x[:N_Q], x[N_Q:], 0 if ok else 2

    def forward(self, q, dq, torques=(0.0, 0.0, 0.0), baumgarte=(0.0, 0.0)) -> ForwardResult:
        """[M D'; D 0][ddq; lambda] = [F + S T; -dD dq - 2 a1 D dq - a2^2 C], all from Pinocchio."""
        a1, a2 = (float(b) for b in baumgarte)
        q = np.asarray(q, dtype=float)
        if q.ndim == 1:
            T = torque_array(torques, 1, True)[0]
            ddq, lam, st = self._forward_one(q, np.asarray(dq, float), T, a1, a2)
            return ForwardResult(ddq, lam, np.array([st], dtype=np.intc))
        n = q.shape[0]
        T = torque_array(torques, n, False)
        res = [self._forward_one(q[i], np.asarray(dq[i], float), T[i], a1, a2) for i in range(n)]
        return ForwardResult(np.array([r[0] for r in res]), np.array([r[1] for r in res]),
                             np.array([r[2] for r in res], dtype=np.intc))

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        res = self.forward(q, dq, torques)
        if res.status.any():
            raise_on_status(res.status, "pinocchio forward_acceleration")
        return res.ddq

    def inverse_dynamics_step(self, q, dq, ddq_ind):
        """The thesis's 13x13 system with Pinocchio's M, forces, D and dD dq."""
        def one(q, dq, ind):
            C, D, bias = self._constraints(q, dq, True)
            F = self._bias_forces(q, dq) + self._applied(q, dq, (0.0, 0.0, 0.0))
            M, S = self._M(q), self.S(q)
            A = np.zeros((13, 13))
            A[:N_Q, :5], A[:N_Q, 5:8], A[:N_Q, 8:] = M[:, DEP], -S, D.T
            A[N_Q:, :5] = D[:, DEP]
            b = np.concatenate([F - M[:, IND] @ ind, -bias - D[:, IND] @ ind])
            x = np.linalg.solve(A, b)
            ddq = np.empty(N_Q)
            ddq[DEP], ddq[IND] = x[:5], ind
            return np.concatenate([ddq, x[5:8], x[8:]])
        out = self._batched(one, q, dq, ddq_ind)
        if out.ndim == 1:
            return out[:8], out[8:11], out[11:], np.zeros(1, dtype=np.intc)
        return out[:, :8], out[:, 8:11], out[:, 11:], np.zeros(out.shape[0], dtype=np.intc)

    # -- scenarios ---------------------------------------------------------------------
    def run_inverse(self, scenario: Scenario):
        return run_inverse(self, scenario)

    def simulate(self, scenario: Scenario, **options):
        return run_forward(self, scenario, **options)
