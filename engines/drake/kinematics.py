"""The rolling constraints and the applied loads of one state, from Drake's frame kinematics.

Drake has no rolling contact, so D and dD dq are assembled here from its point Jacobians and
bias accelerations at the current contact points, as in the Pinocchio adapter (docs/engines.md,
"Rolling contact and the constraint rows"):

* D: the translational velocity Jacobians (with respect to v, world frame) of the rear
  wheel's material point at rC (rows x, y), of the front wheel's material point at rD (rows x,
  y) and, for the holonomic row, the vertical velocity of the fork's material point at rD (for
  the thesis's contact rD is fixed in the fork; for the disc the rim slides through rD
  horizontally, so the vertical rate is the same), each shifted from its body's
  ``CalcJacobianSpatialVelocity`` at the body's origin.
* dD dq: for a material point of body b at a point p(q) that moves at dp/dt,
  d/dt (J_p dq) at ddq = 0 = a_bias(p) + w_b x (dp/dt - v_b(p)), with a_bias the acceleration
  at vdot = 0 of the point fixed in b, shifted from the body's ``CalcBiasSpatialAcceleration``
  (which moves at v_b(p), the material point's velocity: for p fixed in b the correction
  vanishes). The disc's holonomic row is the second derivative of rD_z = zG5 - R u_z,
  u = n/|n|, n = e_z - (e_z . a) a (a = the front axle, fixed in the fork): the hub's bias
  acceleration minus R d2u_z/dt2, which needs the fork's angular velocity and bias angular
  acceleration.
* The loads: drag -cv |vG3| vG3 at the frame's CoM through its point Jacobian, the rider
  torques through the bodies' angular velocity Jacobians (the same spatial Jacobians),
  each on one body (steer about z4 on the fork, pedal about y2 on the rear wheel, anti-roll
  about x3 on the frame).

Every vector is returned in the thesis's coordinates (`engines.drake.plant.Mapping`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pydrake.multibody.tree import JacobianWrtVariable

from .plant import BODY_LINKS, Mapping

__all__ = ["Kinematics", "StateTerms"]

WRT_V = JacobianWrtVariable.kV
BODIES = (2, 3, 4, 5)


def _cross(a, b) -> np.ndarray:
    """a x b of two 3-vectors (numpy's cross costs ~100 us here, this ~3 us)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _skew(r) -> np.ndarray:
    """The matrix of r x (.)."""
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


@dataclass(frozen=True)
class StateTerms:
    """One state's constraint rows and loads, in the thesis's order: C (5,), D (5, 8),
    D dq (5,), dD dq (5,) (None unless asked), Qaero (8,) and S (8, 3) (None unless asked)."""

    C: np.ndarray
    D: np.ndarray
    Ddq: np.ndarray
    bias: np.ndarray | None
    Qaero: np.ndarray | None
    S: np.ndarray | None


def _unit_and_rates(a, da, dda):
    """u = n/|n|, n = e_z - a_z a, and its first two time derivatives (a, da, dda: the axle
    and its rates)."""
    n = np.array([0.0, 0.0, 1.0]) - a[2] * a
    dn = -(da[2] * a + a[2] * da)
    ddn = -(dda[2] * a + 2.0 * da[2] * da + a[2] * dda)
    m = math.sqrt(n @ n)
    u = n / m
    dm = u @ dn
    du = (dn - u * dm) / m
    ddm = du @ dn + u @ ddn
    ddu = (ddn - 2.0 * du * dm - u * ddm) / m
    return u, du, ddu


@dataclass(frozen=True)
class _Body:
    """One body at the current state: rotation R, origin o, its origin's Jacobians Jw, Jv
    (3, 8, thesis columns) and velocities w, v (world)."""

    R: np.ndarray
    o: np.ndarray
    Jw: np.ndarray
    Jv: np.ndarray
    w: np.ndarray
    v: np.ndarray

    def point_jacobian(self, p) -> np.ndarray:
        """J (3, 8) of the body's material point at p: Jv - skew(p - o) Jw."""
        return self.Jv - _skew(p - self.o) @ self.Jw

    def point_velocity(self, p) -> np.ndarray:
        return self.v + _cross(self.w, p - self.o)


class Kinematics:
    """Frame kinematics of one plant and context: the contact points, D, dD dq and the loads.
    Per state, one ``CalcJacobianSpatialVelocity`` per body (at its origin, world frame) and,
    for dD dq, one ``CalcBiasSpatialAcceleration``; the points' Jacobians and biases are shifted
    from the origins here (J_p = Jv - skew(r) Jw, a_p = a_o + alpha x r + w x (w x r),
    r = p - o)."""

    def __init__(self, plant, context, mapping: Mapping, params, contact: str):
        self.plant, self.context, self.mapping = plant, context, mapping
        self.world = plant.world_frame()
        self.bodies = {b: plant.GetBodyByName(link) for b, link in BODY_LINKS.items()}
        self.frames = {b: body.body_frame() for b, body in self.bodies.items()}
        self.R_front, self.cv = float(params.R_front), float(params.cv)
        self.com3 = np.array([params.x3, 0.0, params.z3])
        self.disc = contact == "disc"
        self._origin = np.zeros((3, 1))

    def set_state(self, q_drake: np.ndarray, v_drake: np.ndarray) -> None:
        self.plant.SetPositions(self.context, q_drake)
        self.plant.SetVelocities(self.context, v_drake)

    def _body(self, b: int, dq) -> _Body:
        X = self.plant.EvalBodyPoseInWorld(self.context, self.bodies[b])
        J = self.mapping.v_from_drake(self.plant.CalcJacobianSpatialVelocity(
            self.context, WRT_V, self.frames[b], self._origin, self.world, self.world))
        Jw, Jv = J[:3], J[3:]
        return _Body(X.rotation().matrix(), X.translation(), Jw, Jv, Jw @ dq, Jv @ dq)

    def _bias(self, b: int) -> tuple[np.ndarray, np.ndarray]:
        """(alpha, a_o): body b's angular and origin's acceleration at vdot = 0, world."""
        A = self.plant.CalcBiasSpatialAcceleration(self.context, WRT_V, self.frames[b],
                                                   self._origin, self.world, self.world)
        return A.rotational(), A.translational()

    def _point_bias(self, b: int, body: _Body, p) -> np.ndarray:
        """dJ/dt v (3,) of body b's material point at p (fixed in b)."""
        alpha, a_o = self._bias(b)
        r = p - body.o
        return a_o + _cross(alpha, r) + _cross(body.w, _cross(body.w, r))

    def terms(self, q: np.ndarray, dq: np.ndarray, with_bias: bool,
              with_loads: bool = True) -> StateTerms:
        """The state (thesis order) set on the context, then its rows and loads."""
        mp = self.mapping
        self.set_state(mp.q_to_drake(q), mp.v_to_drake(dq))
        B = {b: self._body(b, dq) for b in BODIES}
        rC = np.array([q[0], q[1], 0.0])
        R4, rG5 = B[4].R, B[5].o
        if self.disc:    # the disc's lowest point
            a = R4[:, 1]
            n = np.array([0.0, 0.0, 1.0]) - a[2] * a
            u = n / math.sqrt(n @ n)
        else:            # the thesis's fork-axis point
            u = R4[:, 2]
        rD = rG5 - self.R_front * u
        JC, JD5, JD4 = B[2].point_jacobian(rC), B[5].point_jacobian(rD), B[4].point_jacobian(rD)
        D = np.vstack([JD4[2], JC[:2], JD5[:2]])
        vC, vD5, vD4 = JC @ dq, JD5 @ dq, JD4 @ dq
        C = np.array([rD[2], vC[0], vC[1], vD5[0], vD5[1]])
        Qaero = S = None
        if with_loads:   # drag at the frame's CoM, rider torques about the bodies' axes
            J3 = B[3].point_jacobian(B[3].o + B[3].R @ self.com3)
            vG3 = J3 @ dq
            Qaero = -self.cv * math.sqrt(vG3 @ vG3) * (J3.T @ vG3)
            S = np.column_stack([B[4].Jw.T @ R4[:, 2], B[2].Jw.T @ B[2].R[:, 1],
                                 B[3].Jw.T @ B[3].R[:, 0]])
        bias = self._rates(B, dq, rC, rD, vC, vD4, vD5) if with_bias else None
        return StateTerms(C, D, D @ dq, bias, Qaero, S)

    def _rates(self, B, dq, rC, rD, vC, vD4, vD5) -> np.ndarray:
        """dD dq: each row's material-point bias plus w x (the point's own velocity minus its
        material point's)."""
        w2, w5 = B[2].w, B[5].w
        bC = self._point_bias(2, B[2], rC) + _cross(w2, np.array([dq[0], dq[1], 0.0]) - vC)
        alpha5, a5 = self._bias(5)
        if self.disc:    # rD slides over the rim: its rate from u's
            w4 = B[4].w
            alpha4, _ = self._bias(4)
            a = B[4].R[:, 1]
            da = _cross(w4, a)
            dda = _cross(alpha4, a) + _cross(w4, da)
            _, du, ddu = _unit_and_rates(a, da, dda)
            dpD = B[5].v - self.R_front * du          # the hub is the wheel's origin
            b0 = a5[2] - self.R_front * ddu[2]
        else:            # rD is fixed in the fork: the fork's material point's acceleration
            dpD = vD4
            b0 = self._point_bias(4, B[4], rD)[2]
        r = rD - B[5].o
        bD = a5 + _cross(alpha5, r) + _cross(w5, _cross(w5, r)) + _cross(w5, dpD - vD5)
        return np.array([b0, bC[0], bC[1], bD[0], bD[1]])
