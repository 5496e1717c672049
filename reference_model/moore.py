"""States of the reference model in Moore's coordinates, and back.

Moore's convention is the one of J. K. Moore's dissertation ("Human control of a bicycle",
UC Davis 2012, the Autolev source ``Whipple.al``), of pydy's bicycle example, of symbrim's
``WhippleBicycleMoore`` and of BicycleParameters. In Autolev notation (``simprot(a, b, k, q)``:
frame b is frame a rotated right-handedly by q about a's k-th axis)::

    inertial frame N: x forward, z DOWN (gravity +g n3), y = z x x to the right
    simprot(N, A, 3, q3)   yaw                          A: yaw frame
    simprot(A, B, 1, q4)   roll                         B: roll frame
    simprot(B, C, 2, q5)   pitch of the rear frame      C: rear frame, c3 along the steer axis
    simprot(C, D, 2, q6)   rear wheel, RELATIVE to C    D: rear wheel
    simprot(C, E, 3, q7)   steer                        E: front frame (fork)
    simprot(E, F, 2, q8)   front wheel, RELATIVE to E   F: front wheel
    rear wheel centre  = q1 n1 + q2 n2 - rR b3    (q1, q2: rear contact point)
    steer-axis point   = rear wheel centre + d1 c1;  front wheel centre = that + d2 c3 + d3 e1
    u_i = dq_i/dt, i = 1..8

The reference model (``derivation.CHAINS``; inertial frame x forward, y left, z UP)::

    q = [xc, yc, phi, theta, psi, beta, gamma, eps]
    Ai2 = Rz(phi) Rx(theta)        A2 = Ai2 Ry(psi)     (psi ABSOLUTE: about y of i2, not of 3)
    A3 = Ai2 Ry(beta)              A4 = A3 Rz(gamma)    A5 = A4 Ry(eps)  (eps RELATIVE to 4)
    rG2 = [xc, yc, 0] + Ai2 [0, 0, R_rear];  the steer axis is z3 (A4 = A3 Rz(gamma)).

Derivation of the mapping
-------------------------
Moore's inertial frame N' is the thesis frame N turned by pi about x: coordinates are
``v' = P v`` with ``P = diag(1, -1, -1)``. P is a proper rotation (det +1), so angular
velocities transform like positions, ``w' = P w``. Every body frame of Moore's is taken as
the thesis's body frame turned the same way (axes x, -y, -z), so its rotation matrix (columns
= body axes in N' coordinates) is ``P A P``. Conjugation by P keeps rotations about x and
reverses those about y and z::

    P Rx(a) P = Rx(a),   P Ry(a) P = Ry(-a),   P Rz(a) P = Rz(-a)

hence, body by body (``Ry(a) Ry(b) = Ry(a + b)`` for the rear wheel, which turns about the
same axis y_i2 as the frame pitch):

    roll frame  P Ai2 P = Rz(-phi) Rx(theta)                 = Rz(q3) Rx(q4)
    rear frame  P A3 P  = Rz(-phi) Rx(theta) Ry(-beta)       = Rz(q3) Rx(q4) Ry(q5)
    rear wheel  P A2 P  = Rz(-phi) Rx(theta) Ry(-psi)        = Rz(q3) Rx(q4) Ry(q5 + q6)
    fork        P A4 P  = P A3 P Rz(-gamma)                  = C Rz(q7)
    front wheel P A5 P  = P A4 P Ry(-eps)                    = E Ry(q8)
    rear contact P [xc, yc, 0] = [xc, -yc, 0]                = [q1, q2, 0]

so, one line each (and the same for the rates u = dq'/dt and accelerations, the map being
linear with constant coefficients)::

    q1 = xc            u1 = d_xc
    q2 = -yc           u2 = -d_yc
    q3 = -phi          u3 = -d_phi
    q4 = theta         u4 = d_theta
    q5 = -beta         u5 = -d_beta
    q6 = beta - psi    u6 = d_beta - d_psi
    q7 = -gamma        u7 = -d_gamma
    q8 = -eps          u8 = -d_eps

and back: xc = q1, yc = -q2, phi = -q3, theta = q4, psi = -(q5 + q6), beta = -q5, gamma = -q7,
eps = -q8.

What the signs mean physically:

* roll: the same in both. theta > 0 turns the thesis's up axis towards -y (to the right), and
  q4 > 0 turns Moore's down axis towards -y' (to the left), so its up axis to the right: both
  are a lean to the right.
* yaw and steer: about up (thesis) versus down (Moore): positive phi, gamma turn left,
  positive q3, q7 turn right.
* pitch: Ry(beta) tips the thesis's up-pointing steer axis z3 to [sin beta, 0, cos beta], its
  top forward for beta > 0; Ry(q5) tips Moore's down-pointing c3 to [sin q5, 0, cos q5] in
  N', its bottom forward, i.e. its top BACK, for q5 > 0. A steer axis raked back by the
  head angle complement lambda (the benchmark's) has beta = -lambda and q5 = +lambda.
* wheels: the thesis's psi is absolute in the leaned frame and positive for forward rolling
  (hub speed R_rear dpsi); Moore's q6 is relative to the rear frame and about the right-
  pointing axis, so forward rolling has u6 < 0: upright and straight, v = -rR (u5 + u6) =
  -rR u6. eps and q8 are both relative to the fork and differ only by the axis sense.

No pitch offset: in ``Whipple.al`` the steer is ``simprot(c, e, 3, q7)`` and the front wheel
centre is reached by ``d2 c3``, so c3 is the steer axis; in the thesis the steer is
``A4 = A3 Rz(gamma)``, so z3 is the steer axis. The two rear frames share the steer axis
(opposite senses, absorbed by P), and the map is a change of angle conventions only: it needs
no model parameters and holds for either front-contact variant (the contact model changes the
constraints, not the coordinates). The zero of Moore's wheel angles is a free choice; here
each of Moore's wheel frames is the thesis's wheel frame turned by P, so all eight angles
vanish together. For the thesis's own bicycle (vertical steer axis, front and rear hub at the
same height) upright straight running has beta = 0 and so q5 = 0.

For reference, Moore's geometry in this model's parameters (not needed by the conversion):
d1 = xa, d2 = -(za + z5), d3 = x5, l1 = x3, l2 = -z3, l3 = dx4 - x5, l4 = z5 - dz4, and the
xz products of inertia change sign (body axes x, -y, -z).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .names import COORDINATES

__all__ = ["MOORE_COORDINATES", "MOORE_DESCRIPTIONS", "MooreState", "from_moore",
           "rates_from_moore", "rates_to_moore", "to_moore"]

N_Q = 8

#: Moore's coordinate names, in order.
MOORE_COORDINATES: tuple[str, ...] = tuple(f"q{i}" for i in range(1, N_Q + 1))

#: Moore's coordinate name -> meaning and its expression in the thesis's coordinates.
MOORE_DESCRIPTIONS: dict[str, str] = {
    "q1": "rear contact x, forward (z-down frame) = xc",
    "q2": "rear contact y, to the right (z-down frame) = -yc",
    "q3": "yaw about the downward vertical = -phi",
    "q4": "roll about the yaw frame's x, positive leaning right = theta",
    "q5": "rear-frame pitch about the roll frame's y, positive raking the steer axis back = -beta",
    "q6": "rear wheel angle relative to the rear frame (forward rolling: u6 < 0) = beta - psi",
    "q7": "steer about the downward steer axis, positive to the right = -gamma",
    "q8": "front wheel angle relative to the fork (forward rolling: u8 < 0) = -eps",
}

# indices into the thesis's q
_XC, _YC, _PHI, _THETA, _PSI, _BETA, _GAMMA, _EPS = range(N_Q)
assert COORDINATES == ("xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps")


@dataclass(frozen=True)
class MooreState:
    """A state in Moore's coordinates.

    ``q`` (..., 8) = [q1..q8]; ``u`` (..., 8) = [u1..u8] = dq/dt, or None when no rates were
    given; ``du`` (..., 8) = du/dt, or None when no accelerations were given; ``names`` the
    coordinate names q1..q8 (see `MOORE_DESCRIPTIONS`).
    """

    q: np.ndarray
    u: np.ndarray | None = None
    du: np.ndarray | None = None
    names: tuple[str, ...] = MOORE_COORDINATES


def _array(x, what: str, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """x as a float64 (or complex128, for complex-step use) array of shape (..., 8)."""
    a = np.asarray(x)
    if a.dtype.kind not in "biufc":
        raise ValueError(f"{what} must be numbers of shape (8,) or (..., 8); got dtype {a.dtype}")
    a = a.astype(np.complex128 if a.dtype.kind == "c" else np.float64)
    if a.ndim == 0 or a.shape[-1] != N_Q:
        raise ValueError(f"{what} must have shape (8,) or (..., 8) (last axis: the 8 coordinates); "
                         f"got shape {a.shape}")
    if shape is not None and a.shape != shape:
        raise ValueError(f"{what} must have the same shape as the coordinates, {shape}; "
                         f"got shape {a.shape}")
    return a


def _to_moore(x: np.ndarray) -> np.ndarray:
    """The linear map thesis -> Moore (coordinates, rates and accelerations alike)."""
    out = np.empty_like(x)
    out[..., 0] = x[..., _XC]
    out[..., 1] = -x[..., _YC]
    out[..., 2] = -x[..., _PHI]
    out[..., 3] = x[..., _THETA]
    out[..., 4] = -x[..., _BETA]
    out[..., 5] = x[..., _BETA] - x[..., _PSI]
    out[..., 6] = -x[..., _GAMMA]
    out[..., 7] = -x[..., _EPS]
    return out


def _from_moore(m: np.ndarray) -> np.ndarray:
    """The inverse map Moore -> thesis."""
    out = np.empty_like(m)
    out[..., _XC] = m[..., 0]
    out[..., _YC] = -m[..., 1]
    out[..., _PHI] = -m[..., 2]
    out[..., _THETA] = m[..., 3]
    out[..., _PSI] = -(m[..., 4] + m[..., 5])
    out[..., _BETA] = -m[..., 4]
    out[..., _GAMMA] = -m[..., 6]
    out[..., _EPS] = -m[..., 7]
    return out


def rates_to_moore(dq) -> np.ndarray:
    """Thesis rates (or accelerations) (..., 8) -> Moore's u (or du/dt) (..., 8)."""
    return _to_moore(_array(dq, "dq"))


def rates_from_moore(u) -> np.ndarray:
    """Moore's u (or du/dt) (..., 8) -> thesis rates (or accelerations) (..., 8)."""
    return _from_moore(_array(u, "moore_u"))


def to_moore(q, dq=None, ddq=None) -> MooreState:
    """The reference model's state -> Moore's coordinates.

    ``q`` (8,) or (..., 8) in the thesis order [xc, yc, phi, theta, psi, beta, gamma, eps];
    ``dq`` and ``ddq`` (optional) of the same shape. Returns a `MooreState` whose ``u`` and
    ``du`` are None when ``dq`` / ``ddq`` are not given. Angles are not wrapped. Complex
    input stays complex (so the map can sit inside a complex-step derivative).
    """
    qa = _array(q, "q")
    u = None if dq is None else _to_moore(_array(dq, "dq", qa.shape))
    du = None if ddq is None else _to_moore(_array(ddq, "ddq", qa.shape))
    return MooreState(q=_to_moore(qa), u=u, du=du)


def from_moore(moore_q, moore_u=None, moore_du=None):
    """Moore's coordinates -> the reference model's state.

    ``moore_q`` (8,) or (..., 8) = [q1..q8]; ``moore_u`` (optional) = [u1..u8] of the same
    shape. Returns ``(q, dq)`` in the thesis order, ``dq`` None when ``moore_u`` is not given;
    with ``moore_du`` (du/dt, same shape) returns ``(q, dq, ddq)``.
    """
    if isinstance(moore_q, MooreState):
        raise TypeError("from_moore takes arrays; for a MooreState s call "
                        "from_moore(s.q, s.u) (or from_moore(s.q, s.u, s.du))")
    ma = _array(moore_q, "moore_q")
    dq = None if moore_u is None else _from_moore(_array(moore_u, "moore_u", ma.shape))
    q = _from_moore(ma)
    if moore_du is None:
        return q, dq
    return q, dq, _from_moore(_array(moore_du, "moore_du", ma.shape))
