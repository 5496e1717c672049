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
  gravity from ``computeGeneralizedGravity`` (= -Qgrav); Qv + Qgrav = -``nonLinearEffects``.
* Rolling constraints: Pinocchio has no rolling contact, so D is assembled from the
  world-frame joint Jacobian J (``computeAllTerms`` fills it) shifted to the current contact
  points: for a material point p of body b, J_p = [I, -skew(p)] J_b (J_b: J with the columns
  outside b's support zeroed). The rear contact rC is taken on the rear wheel, the front
  contact rD on the front wheel (the thesis's fork-axis point or the disc's lowest point, per
  the model's contact variant); the holonomic row is the vertical velocity of the fork's
  material point at rD (for the thesis contact rD is fixed in the fork; for the disc the rim
  slides through rD horizontally, so the vertical rate is the same). dD dq from the bodies'
  spatial accelerations at ddq = 0 (Pinocchio's ``data.a``, taken to the world frame: A_b =
  dJ_b dq) plus the contact point's own motion: for a material point of body b at a moving
  point p(q), d/dt (J_p dq)|_{ddq=0} = a_O + alpha x p + w_b x dp/dt, with
  (a_O, alpha) = A_b and (v_O, w_b) the body's spatial velocity (``data.ov``).
* Drag as a force at the frame's CoM through its point Jacobian; rider torques as
  single-body torques through the body-axis angular Jacobians (single-sided, as the thesis).
* Forward dynamics: the KKT system [M D'; D 0] is solved by Pinocchio's ``forwardDynamics``
  (in C++: Cholesky of M and of D M^-1 D^T, with M and the nonlinear effects of the same
  ``computeAllTerms`` call), fed with D and the drift dD dq + 2 a1 D dq + a2^2 C assembled here.

Speed: the right-hand side a forward run evaluates once per integrator stage is one
``computeAllTerms``, one small product W @ J giving D and the applied forces together (no
per-point numpy calls: the 3-vector algebra is plain float arithmetic, cheaper than a numpy
call at this size) and one ``forwardDynamics`` call; everything that depends only on the model
(support masks, the point-operator layout) is built once in the constructor.

The engine also offers the duck-typed methods the reference solvers use (``forward``,
``constraint_residual``, ``inverse_dynamics_step``...), so inverse kinematics, the 13x13 inverse
dynamics and forward runs use the same code and integrator as the reference, on Pinocchio's terms.
"""

from __future__ import annotations

import math

import numpy as np

from reference_model import COORDINATES, Model
from reference_model.model import DEP, IND, ForwardResult, raise_on_status, torque_array
from reference_model.scenarios import Scenario, run_forward, run_inverse

from ..base import CAPABILITIES, Engine, EngineError
from ..batching import batched
from ..facts import Costs, RunSetup
from ..linear import DifferenceEigenvalues

try:
    import pinocchio as pin
except ImportError as exc:  # pragma: no cover - the registry checks REQUIRES first
    raise EngineError("the Pinocchio adapter needs the package 'pin' "
                      "(pip install 'bicycle-xval[pinocchio]')") from exc

N_Q, N_C = 8, 5
# joint ids in the Pinocchio model (0 is the universe)
J_XC, J_YC, J_PHI, J_THETA, J_PSI, J_BETA, J_GAMMA, J_EPS = range(1, 9)


def _cross3(a, b) -> tuple[float, float, float]:
    """a x b for 3-sequences of floats (plain Python: a numpy call costs ~1 us, this ~0.2 us)."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return (a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0)


def _add3(a, b) -> tuple[float, float, float]:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _dot3(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


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


# Bodies whose spatial velocity (v_O, w) in the world frame the right-hand side needs: v_O is
# the velocity of the body's point at the world origin, so a material point p moves at
# v_O + w x p. It is J_b dq (J_b the world Jacobian with the columns outside the body's support
# zeroed), which Pinocchio keeps as data.ov.
BODIES = (J_PSI, J_BETA, J_GAMMA, J_EPS)     # rear wheel, frame, fork, front wheel
# Rows of the operator W (8, 6) with (W @ J) masked row by row to each row's body: rows 0-4 are
# D ([I, -skew(p)] rows of a point's velocity), rows 5-7 the generalised forces of the applied
# wrenches (force, moment about the world origin) on frame, fork and rear wheel (summed).
ROW_BODIES = (J_GAMMA, J_PSI, J_PSI, J_EPS, J_EPS, J_BETA, J_GAMMA, J_PSI)
# rider torques, single-sided about body axes: steer z4 on the fork, pedal y2 on the rear wheel,
# anti-roll x3 on the frame (joint of the body, column of its rotation)
TORQUE_AXES = ((J_GAMMA, 2), (J_PSI, 1), (J_BETA, 0))


def _support_mask(pm, joint: int) -> np.ndarray:
    """1.0 in the velocity columns that move body `joint` (its support), else 0.0."""
    mask = np.zeros(N_Q)
    for j in pm.supports[joint]:
        if j > 0:
            mask[pm.idx_vs[j]] = 1.0
    return mask


def _at(V, p) -> tuple[float, float, float]:
    """Velocity v_O + w x p of a body's material point p, V = (v_O, w) its spatial velocity
    (written out: this runs a few times per right-hand side, a numpy call costs ~1 us)."""
    vx, vy, vz, wx, wy, wz = V
    px, py, pz = p
    return (vx + wy * pz - wz * py, vy + wz * px - wx * pz, vz + wx * py - wy * px)


def _rate_at(a, R, o, V, p, dp) -> tuple[float, float, float]:
    """d/dt (J_p dq) at ddq = 0 for a body's point p moving at dp: a_O + alpha x p + w x dp,
    where (a_O, alpha) = dJ_b dq is the body's world spatial acceleration at ddq = 0, here from
    Pinocchio's local one a = (a_lin, a_ang) and the body's placement (R, o):
    alpha = R a_ang, a_O + alpha x p = R a_lin + alpha x (p - o). V = (v_O, w)."""
    l0, l1, l2, u0, u1, u2 = a
    r0, r1, r2 = R
    x = r0[0] * u0 + r0[1] * u1 + r0[2] * u2
    y = r1[0] * u0 + r1[1] * u1 + r1[2] * u2
    z = r2[0] * u0 + r2[1] * u1 + r2[2] * u2
    px, py, pz = p[0] - o[0], p[1] - o[1], p[2] - o[2]
    wx, wy, wz = V[3], V[4], V[5]
    dx, dy, dz = dp
    return (r0[0] * l0 + r0[1] * l1 + r0[2] * l2 + y * pz - z * py + wy * dz - wz * dy,
            r1[0] * l0 + r1[1] * l1 + r1[2] * l2 + z * px - x * pz + wz * dx - wx * dz,
            r2[0] * l0 + r2[1] * l1 + r2[2] * l2 + x * py - y * px + wx * dy - wy * dx)


#: read-only status arrays of one state (0 ok, 1 singular, 2 non-finite state), not rebuilt per call
_STATUS = tuple(np.array([k], dtype=np.intc) for k in range(3))
for _s in _STATUS:
    _s.setflags(write=False)


class PinocchioEngine(DifferenceEigenvalues, Engine):
    """Mass matrix, RNEA, gravity, rolling constraints, forces and forward runs from Pinocchio."""

    name = "pinocchio"
    capabilities = frozenset(CAPABILITIES)
    label = "Pinocchio"
    colour = "tab:orange"
    marker = "s"
    #: the reference's own solvers on Pinocchio's terms: judged to [trajectory]
    trajectory_tolerance = "trajectory"
    run_setups = (RunSetup(settings="the reference's solvers on Pinocchio's crba, rnea and frame "
                                    "kinematics (same integrator and tolerances)"),)
    costs = Costs(run_per_second=0.6, short_run=0.8, terms=1.5, faults=4.0)

    def __init__(self, model: Model):
        super().__init__(model)
        self.pin_model = pm = build_pinocchio_model(model)
        self.data = d = pm.createData()
        p = model.params
        self._R_front = p.R_front
        self._cv = p.cv
        self._com3 = (p.x3, 0.0, p.z3)
        self._disc = model.contact == "disc"
        # duck-typed attributes the reference solvers read
        self.params, self.contact = p, model.contact
        # what depends on the model only
        self._row_mask = np.vstack([_support_mask(pm, j) for j in ROW_BODIES])
        self._torque_mask = np.column_stack([_support_mask(pm, j) for j, _ in TORQUE_AXES])
        self._wrench_rows = np.array([0.0] * N_C + [1.0] * (len(ROW_BODIES) - N_C))
        self._zeros = np.zeros(N_Q)
        # the operator W, stored transposed (6, 8) so that what changes per call is contiguous:
        # the moment rows 3..5 (24 numbers) and the frame's force (column 5 of rows 0..2)
        self._Wt = np.zeros((6, len(ROW_BODIES)))
        for col, axis in enumerate((2, 0, 1, 0, 1)):   # D rows: the velocity component taken
            self._Wt[axis, col] = 1.0
        self._Wt_moments = self._Wt[3:].ravel()
        self._Wt_force = self._Wt[:3, N_C]
        self._no_torque = np.zeros(3)
        # Views into self.data's buffers (never reallocated: Data has fixed sizes once created),
        # refreshed by every kinematics call; read, never written, and never handed out.
        self._J = d.J                                  # world-frame joint Jacobian (6, 8)
        self._t5 = d.oMi[J_EPS].translation            # front wheel centre rG5
        self._R4 = d.oMi[J_GAMMA].rotation             # fork axes
        self._t3, self._R3 = d.oMi[J_BETA].translation, d.oMi[J_BETA].rotation
        self._R2 = d.oMi[J_PSI].rotation               # rear wheel axes
        self._ov = [d.ov[j].vector for j in BODIES]    # spatial velocities (v_O, w), world
        # local spatial accelerations at ddq = 0 with each body's placement (rear, fork, front)
        self._acc = [(d.a[j].vector, d.oMi[j].rotation, d.oMi[j].translation)
                     for j in (J_PSI, J_GAMMA, J_EPS)]

    # -- batching ----------------------------------------------------------------------
    _batched = staticmethod(batched)

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
        """Qv + Qgrav = -(C(q, dq) dq + g(q)), Pinocchio's nonlinear effects."""
        return -pin.nonLinearEffects(self.pin_model, self.data, q, dq)

    # -- kinematics: constraints and applied forces in one pass --------------------------
    def _kinematics(self, q, dq, T, with_bias: bool):
        """One ``computeAllTerms`` pass (placements, world Jacobian J, spatial velocities and
        accelerations at ddq = 0, and M and the nonlinear effects, left in self.data for
        ``forwardDynamics``) and from it C, D, dD dq and the applied forces.

        Returns (C, D, D dq, dD dq, Q): C, D dq and dD dq as lists of 5 floats (dD dq None
        unless ``with_bias``), D (5, 8), Q = Qaero + S T (8,).
        """
        pm, d = self.pin_model, self.data
        # placements, world Jacobian, spatial velocities and accelerations at ddq = 0, M, nle
        pin.computeAllTerms(pm, d, q, dq)
        ov = self._ov                                    # spatial velocities (v_O, w)
        v2, v3, v4, v5 = ov[0].tolist(), ov[1].tolist(), ov[2].tolist(), ov[3].tolist()
        R4, Rf = self._R4.tolist(), self._R_front
        rG5 = tuple(self._t5.tolist())
        if self._disc:   # lowest point of the disc: rG5 - R u, u = n/|n|, n = e_z - a_z a
            a = (R4[0][1], R4[1][1], R4[2][1])            # fork (= wheel) y axis
            n = (-a[2] * a[0], -a[2] * a[1], 1.0 - a[2] * a[2])
            m = math.sqrt(_dot3(n, n))
            u = (n[0] / m, n[1] / m, n[2] / m)
        else:            # the thesis's fork-axis point: rG5 - R z4
            u = (R4[0][2], R4[1][2], R4[2][2])
        rD = (rG5[0] - Rf * u[0], rG5[1] - Rf * u[1], rG5[2] - Rf * u[2])
        ql = q.tolist()
        rC = (ql[0], ql[1], 0.0)
        R3, (cx, cy, cz), t3 = self._R3.tolist(), self._com3, self._t3.tolist()
        rG3 = (t3[0] + R3[0][0] * cx + R3[0][1] * cy + R3[0][2] * cz,
               t3[1] + R3[1][0] * cx + R3[1][1] * cy + R3[1][2] * cz,
               t3[2] + R3[2][0] * cx + R3[2][1] * cy + R3[2][2] * cz)
        vC, vD5, vD4, vG3 = _at(v2, rC), _at(v5, rD), _at(v4, rD), _at(v3, rG3)
        C = [rD[2], vC[0], vC[1], vD5[0], vD5[1]]
        Ddq = [vD4[2], vC[0], vC[1], vD5[0], vD5[1]]
        # applied wrenches: drag f at rG3 and anti-roll about x3 on the frame, steer about z4 on
        # the fork, pedal about y2 on the rear wheel
        k = -self._cv * math.sqrt(_dot3(vG3, vG3))
        f = (k * vG3[0], k * vG3[1], k * vG3[2])
        m3 = _cross3(rG3, f)
        T0, T1, T2 = T.tolist()
        R2 = self._R2.tolist()
        # W's rows (columns of Wt): D rows [e_i, -skew(p)_i] for fork z at rD, rear wheel x, y
        # at rC, front wheel x, y at rD; wrenches (force, moment about O) on frame, fork, rear
        self._Wt_moments[:] = [
            rD[1], 0.0, -rC[2], 0.0, -rD[2], m3[0] + T2 * R3[0][0], T0 * R4[0][2], T1 * R2[0][1],
            -rD[0], rC[2], 0.0, rD[2], 0.0, m3[1] + T2 * R3[1][0], T0 * R4[1][2], T1 * R2[1][1],
            0.0, -rC[1], rC[0], -rD[1], rD[0], m3[2] + T2 * R3[2][0], T0 * R4[2][2], T1 * R2[2][1],
        ]
        self._Wt_force[:] = f
        WJ = (self._Wt.T @ self._J) * self._row_mask
        D, Q = WJ[:5], self._wrench_rows @ WJ
        if not with_bias:
            return C, D, Ddq, None, Q
        # spatial accelerations at ddq = 0 (= dJ_b dq): Pinocchio's local ones in data.a
        (a2, _, o2), (a4, _, o4), (a5, R5, _) = self._acc
        dl = dq.tolist()
        pC = (dl[0], dl[1], 0.0)
        R5, a5 = R5.tolist(), a5.tolist()
        if self._disc:   # u(a(q)) and its first two rates, from the fork's w and alpha
            w4, (l0, l1, l2) = v4[3:], a4.tolist()[3:]
            al4 = tuple(r[0] * l0 + r[1] * l1 + r[2] * l2 for r in R4)
            da = _cross3(w4, a)
            dda = _add3(_cross3(al4, a), _cross3(w4, da))
            az, daz, ddaz = a[2], da[2], dda[2]
            dn = (-(daz * a[0] + az * da[0]), -(daz * a[1] + az * da[1]), -(daz * az + az * daz))
            ddn_z = -(ddaz * az + 2 * daz * daz + az * ddaz)
            dm = _dot3(u, dn)
            du = ((dn[0] - u[0] * dm) / m, (dn[1] - u[1] * dm) / m, (dn[2] - u[2] * dm) / m)
            ddn = (-(ddaz * a[0] + 2 * daz * da[0] + az * dda[0]),
                   -(ddaz * a[1] + 2 * daz * da[1] + az * dda[1]), ddn_z)
            ddm = _dot3(du, dn) + _dot3(u, ddn)
            ddu_z = (ddn_z - 2 * du[2] * dm - u[2] * ddm) / m
            vG5 = _at(v5, rG5)
            pD = (vG5[0] - Rf * du[0], vG5[1] - Rf * du[1], vG5[2] - Rf * du[2])
            b0 = _rate_at(a5, R5, rG5, v5, rG5, vG5)[2] - Rf * ddu_z     # d2/dt2 of rD_z
        else:            # rD is fixed in the fork
            pD = vD4
            b0 = _rate_at(a4.tolist(), R4, o4.tolist(), v4, rD, vD4)[2]
        bC = _rate_at(a2.tolist(), R2, o2.tolist(), v2, rC, pC)
        bD = _rate_at(a5, R5, rG5, v5, rD, pD)
        return C, D, Ddq, [b0, bC[0], bC[1], bD[0], bD[1]], Q

    def _S(self):
        """S (8, 3): the rider torques' generalised forces, from the current kinematics."""
        axes = [R[:, c] for R, c in ((self._R4, 2), (self._R2, 1), (self._R3, 0))]
        return (self._J[3:].T @ np.column_stack(axes)) * self._torque_mask

    def S(self, q):
        def one(q):
            pin.computeJointJacobians(self.pin_model, self.data, q)
            return self._S()
        return self._batched(one, q)

    def Qaero(self, q, dq):
        return self._batched(lambda a, b: self._kinematics(a, b, self._no_torque, False)[4], q, dq)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        def one(q, dq, T):
            return self._kinematics(q, dq, T, False)[4] + self._bias_forces(q, dq)
        single = np.ndim(q) == 1
        T = torque_array(torques, 1 if single else np.shape(q)[0], single)
        return self._batched(one, q, dq, T[0] if single else T)

    # -- rolling constraints -----------------------------------------------------------
    def constraint_residual(self, q, dq):
        return self._batched(
            lambda a, b: np.array(self._kinematics(a, b, self._no_torque, False)[0]), q, dq)

    def constraint_jacobian(self, q):
        return self._batched(lambda a: self._kinematics(a, self._zeros, self._no_torque, False)[1], q)

    def constraint_bias(self, q, dq):
        return self._batched(
            lambda a, b: np.array(self._kinematics(a, b, self._no_torque, True)[3]), q, dq)

    # -- the thesis's linear systems on Pinocchio's terms ---------------------------------
    def _forward_one(self, q, dq, T, a1, a2):
        """The KKT system solved by Pinocchio (``forwardDynamics``: M and the nonlinear effects
        from ``computeAllTerms``, Cholesky of M and of D M^-1 D^T in C++). Pinocchio solves
        M ddq = tau - nle + D^T lambda_pin, D ddq = -gamma, so lambda (thesis) = -lambda_pin."""
        C, D, Ddq, bias, tau = self._kinematics(q, dq, T, True)
        k1, k2 = 2.0 * a1, a2 * a2
        gamma = np.array([bias[0] + k1 * Ddq[0] + k2 * C[0], bias[1] + k1 * Ddq[1] + k2 * C[1],
                          bias[2] + k1 * Ddq[2] + k2 * C[2], bias[3] + k1 * Ddq[3] + k2 * C[3],
                          bias[4] + k1 * Ddq[4] + k2 * C[4]])
        ddq = pin.forwardDynamics(self.pin_model, self.data, tau, D, gamma)   # M, nle as above
        lam = -self.data.lambda_c
        if math.isfinite(sum(ddq.tolist()) + sum(lam.tolist())):
            return ddq, lam, 0
        # Cholesky of a singular D M^-1 D^T gives non-finite output from finite input
        finite = math.isfinite(sum(q.tolist()) + sum(dq.tolist()) + sum(T.tolist()))
        return ddq, lam, 1 if finite else 2

    def forward(self, q, dq, torques=(0.0, 0.0, 0.0), baumgarte=(0.0, 0.0)) -> ForwardResult:
        """[M D'; D 0][ddq; lambda] = [F + S T; -dD dq - 2 a1 D dq - a2^2 C], all from Pinocchio.

        Status per state: 0 ok, 1 non-finite result from a finite state (a singular
        D M^-1 D^T), 2 non-finite state. Unlike the reference's pivot test, a merely
        ill-conditioned system is not flagged (nor was it by the numpy solve used before).
        """
        a1, a2 = baumgarte
        a1, a2 = float(a1), float(a2)
        q = np.asarray(q, dtype=float)
        if q.ndim == 1:
            # the solvers' per-step call: torques already a float (3,) array skip the check
            T = torques if (type(torques) is np.ndarray and torques.shape == (3,)
                            and torques.dtype == np.float64) else torque_array(torques, 1, True)[0]
            ddq, lam, st = self._forward_one(q, np.asarray(dq, float), T, a1, a2)
            return ForwardResult(ddq, lam, _STATUS[st])
        n = q.shape[0]
        T = torque_array(torques, n, False)
        dq = np.broadcast_to(np.asarray(dq, dtype=float), (n, N_Q))
        res = [self._forward_one(q[i], np.ascontiguousarray(dq[i]), T[i], a1, a2) for i in range(n)]
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
            _, D, _, bias, Qaero = self._kinematics(q, dq, self._no_torque, True)
            S = self._S()
            F = self._bias_forces(q, dq) + Qaero
            M = self._M(q)
            A = np.zeros((13, 13))
            A[:N_Q, :5], A[:N_Q, 5:8], A[:N_Q, 8:] = M[:, DEP], -S, D.T
            A[N_Q:, :5] = D[:, DEP]
            b = np.concatenate([F - M[:, IND] @ ind, -np.asarray(bias) - D[:, IND] @ ind])
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
