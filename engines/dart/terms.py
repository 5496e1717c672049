"""The thesis's terms from one DART skeleton of the thesis tree (`skeleton.build_skeleton`),
in the thesis's coordinates, one state at a time.

What is DART's and what is ours:

* M = ``Skeleton.getMassMatrix`` (DART's articulated-body / composite algorithm);
* DART writes the equations as M ddq + c(q, dq) + g(q) = tau: ``getCoriolisForces`` is c = -Qv
  and ``getGravityForces`` is g = -Qgrav (the gravity *torque*); ``computeInverseDynamics``
  (no external forces, no damping, no spring forces) leaves M ddq + c + g = M ddq - Qv - Qgrav
  in the joint forces, the thesis's inverse dynamics with no sign change;
* the rolling constraints: DART has no rolling contact, so D is assembled from DART's world
  point Jacobians (``Skeleton.getLinearJacobian(body, offset, World)``) at the current contact
  points, and dD dq from their classical time derivatives (``getLinearJacobianDeriv``, the
  acceleration of a material point at ddq = 0) plus the contact point's own motion through the
  body: for a material point of body b at a moving point p(q),
  d/dt (J_p dq) = dJ_p/dt dq + w_b x (dp/dt - v_p). The rear contact rC is taken on the rear
  wheel; the front contact rD on the front wheel (the thesis's fork-axis point rG5 - R z4, or
  the disc's lowest point rG5 - R n/|n|, n = e_z - (e_z . y4) y4); the holonomic row is the
  vertical velocity of the fork's material point at rD (rD is fixed in the fork for the thesis's
  contact; for the disc the point slides horizontally along the rim, so the vertical rate is the
  same), its rate d2 rD_z / dt2;
* the drag at the frame's CoM through its point Jacobian, the rider torques as single-body
  torques through the angular Jacobians (``getAngularJacobian``), each about its body's axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .skeleton import Coordinates

import dartpy as dart

__all__ = ["Kinematics", "TermsOf"]

N_Q, N_C = 8, 5
E_Z = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Kinematics:
    """The rolling constraints at one state, thesis order: C (5,), D (5, 8), D dq (5,),
    dD dq (5,) (None unless asked for), and Q = Qaero + S T (8,)."""

    C: np.ndarray
    D: np.ndarray
    Ddq: np.ndarray
    bias: np.ndarray | None
    Q: np.ndarray


def _cross(a, b) -> np.ndarray:
    """a x b for two 3-vectors (np.cross costs ~20 us a call at this size, this ~2 us)."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def _disc_direction(a, da, dda):
    """u = n/|n|, n = e_z - a_z a (a the axle) and its first two time derivatives, z only for
    the second (the rate of rD_z): (u, du, ddu_z)."""
    n = E_Z - a[2] * a
    dn = -(da[2] * a + a[2] * da)
    ddn = -(dda[2] * a + 2.0 * da[2] * da + a[2] * dda)
    m = np.linalg.norm(n)
    u = n / m
    dm = u @ dn
    du = (dn - u * dm) / m
    ddm = du @ dn + u @ ddn
    return u, du, (ddn[2] - 2.0 * du[2] * dm - u[2] * ddm) / m


class TermsOf:
    """The terms of one skeleton (its state is set by every call)."""

    def __init__(self, skeleton, coordinates: Coordinates, params, disc: bool):
        self.sk, self.map = skeleton, coordinates
        self.world = dart.dynamics.Frame.World()
        body = skeleton.getBodyNode
        self.rear, self.frame = body("rear_wheel"), body("frame")
        self.fork, self.front = body("fork"), body("front_wheel")
        self.R_front, self.cv, self.disc = float(params.R_front), float(params.cv), disc
        self.com3 = np.asarray(self.frame.getLocalCOM(), dtype=float)
        self.zeros = np.zeros(N_Q)

    # -- state ---------------------------------------------------------------------------
    def set(self, q, dq=None, ddq=None) -> None:
        sk, to = self.sk, self.map.to_dart
        sk.setPositions(to(q))
        sk.setVelocities(self.zeros if dq is None else to(dq))
        sk.setAccelerations(self.zeros if ddq is None else to(ddq))

    # -- rigid-body terms ----------------------------------------------------------------
    def mass_matrix(self, q) -> np.ndarray:
        self.set(q)
        M = self.map.matrix(self.sk.getMassMatrix())
        return 0.5 * (M + M.T)

    def gravity(self, q) -> np.ndarray:
        self.set(q)
        return -self.map.from_dart(self.sk.getGravityForces())

    def bias_forces(self, q, dq) -> np.ndarray:
        """Qv + Qgrav = -(c + g), DART's Coriolis-and-gravity forces with the thesis's sign."""
        self.set(q, dq)
        return -self.map.from_dart(self.sk.getCoriolisAndGravityForces())

    def inverse_dynamics(self, q, dq, ddq) -> np.ndarray:
        self.set(q, dq, ddq)
        self.sk.computeInverseDynamics(False, False, False)
        return self.map.from_dart(self.sk.getForces())

    # -- Jacobians in the thesis's columns ---------------------------------------------
    def _placements(self) -> None:
        """(R, o) of the four bodies at the current state, read once per evaluation."""
        self._X = {}
        for b in (self.rear, self.frame, self.fork, self.front):
            T = b.getWorldTransform()
            self._X[b.getName()] = (T.rotation(), T.translation())

    def _offset(self, body, p):
        R, o = self._X[body.getName()]
        return R.T @ (p - o)

    def linear(self, body, p) -> np.ndarray:
        """J_p (3, 8): the world velocity Jacobian of body's material point at world point p."""
        return self.map.from_dart(self.sk.getLinearJacobian(body, self._offset(body, p),
                                                            self.world))

    def linear_rate(self, body, p, dq) -> np.ndarray:
        """dJ_p/dt dq (3,): the material point's classical acceleration at ddq = 0."""
        J = self.sk.getLinearJacobianDeriv(body, self._offset(body, p), self.world)
        return self.map.from_dart(J) @ dq

    def angular(self, body) -> np.ndarray:
        return self.map.from_dart(self.sk.getAngularJacobian(body, self.world))

    def S(self, q) -> np.ndarray:
        """S (8, 3): steer about the fork's z, pedal about the rear wheel's y, anti-roll about
        the frame's x, each on its body alone."""
        self.set(q)
        self._placements()
        return self._S()

    def _S(self) -> np.ndarray:
        cols = [(self.fork, 2), (self.rear, 1), (self.frame, 0)]
        return np.column_stack([self.angular(b).T @ self._X[b.getName()][0][:, k]
                                for b, k in cols])

    # -- the rolling constraints and the applied loads ----------------------------------
    def kinematics(self, q, dq, torques, with_bias: bool, with_loads: bool = True) -> Kinematics:
        """The constraints at (q, dq); dD dq if ``with_bias``; Q (else zeros) if ``with_loads``."""
        q, dq = np.asarray(q, dtype=float), np.asarray(dq, dtype=float)
        self.set(q, dq)
        self._placements()
        R4 = self._X["fork"][0]
        rG5 = self._X["front_wheel"][1]
        a = R4[:, 1]
        if self.disc:
            w4 = self.angular(self.fork) @ dq
            al4 = self.map.from_dart(self.sk.getAngularJacobianDeriv(self.fork, self.world)) @ dq
            da = _cross(w4, a)
            u, du, ddu_z = _disc_direction(a, da, _cross(al4, a) + _cross(w4, da))
        else:
            u = R4[:, 2]
        rD = rG5 - self.R_front * u
        rC = np.array([q[0], q[1], 0.0])
        J4D, J2C, J5D = self.linear(self.fork, rD), self.linear(self.rear, rC), \
            self.linear(self.front, rD)
        D = np.vstack([J4D[2], J2C[:2], J5D[:2]])
        Ddq = D @ dq
        C = np.concatenate([[rD[2]], Ddq[1:]])
        Q = self._loads(dq, torques) if with_loads else np.zeros(N_Q)
        if not with_bias:
            return Kinematics(C, D, Ddq, None, Q)
        w2, w5 = self.angular(self.rear) @ dq, self.angular(self.front) @ dq
        vC = J2C @ dq
        bC = self.linear_rate(self.rear, rC, dq) + _cross(w2, np.array([dq[0], dq[1], 0.0]) - vC)
        vD5 = J5D @ dq
        if self.disc:
            vG5 = self.linear(self.front, rG5) @ dq
            pD = vG5 - self.R_front * du                    # dp/dt of the disc's lowest point
            b0 = self.linear_rate(self.front, rG5, dq)[2] - self.R_front * ddu_z
        else:
            pD = J4D @ dq                                   # rD moves with the fork
            b0 = self.linear_rate(self.fork, rD, dq)[2]
        bD = self.linear_rate(self.front, rD, dq) + _cross(w5, pD - vD5)
        return Kinematics(C, D, Ddq, np.array([b0, bC[0], bC[1], bD[0], bD[1]]), Q)

    def _loads(self, dq, torques) -> np.ndarray:
        """Qaero + S T: the drag at the frame's CoM, the rider torques about body axes."""
        R3, o3 = self._X["frame"]
        J3 = self.linear(self.frame, o3 + R3 @ self.com3)
        vG3 = J3 @ dq
        return J3.T @ (-self.cv * np.linalg.norm(vG3) * vG3) + self._S() @ np.asarray(torques)
