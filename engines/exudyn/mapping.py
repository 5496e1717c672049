"""Between the thesis's minimal coordinates and the poses of the four bodies.

Forward (``body_states``): q, dq -> CoM positions, rotation matrices, CoM velocities and
angular velocities (global) of bodies 2..5, written directly from the thesis's kinematics
(see docs/model.md; the parameters are the `Parameters` of the model):

    Ai2 = Rz(phi) Rx(theta)    A2 = Ai2 Ry(psi)    A3 = Ai2 Ry(beta)
    A4 = A3 Rz(gamma)          A5 = A4 Ry(eps)
    rG2 = [xc, yc, 0] + Ai2 [0, 0, R_rear]     rA = rG2 + A3 [xa, 0, za]
    rG3 = rG2 + A3 [x3, 0, z3]   rG4 = rA + A4 [dx4, 0, dz4]   rG5 = rA + A4 [x5, 0, z5]

The redundant Exudyn build is started from these states, and the round trip
``poses_to_q(body_states(q)) == q`` is tested.

Backward (``poses_to_q``, ``velocities_to_dq``): what the redundant build's sensors give
(rear hub position, the four rotation matrices, the CoM velocity of the rear wheel and the
four angular velocities) -> q and dq:

* phi, theta, beta from the frame's A3 = Rz(phi) Rx(theta) Ry(beta): its third row is
  [-cos(theta) sin(beta), sin(theta), cos(theta) cos(beta)], its second column
  [-sin(phi) cos(theta), cos(phi) cos(theta), sin(theta)];
* psi from Ai2^T A2 = Ry(psi) (the rear wheel relative to the leaned frame: psi is absolute
  in i2, as in the thesis), gamma from A3^T A4 = Rz(gamma), eps from A4^T A5 = Ry(eps);
* xc, yc from the rear hub position minus Ai2 [0, 0, R_rear];
* the angles come out wrapped to (-pi, pi]; ``unwrap_angles`` makes each series continuous
  and shifts it by whole turns so that it starts at the initial state's value.

dq is **solved from the angular velocities through the linear map**, not differentiated:
the frame's angular velocity w3 = phi' e_Z + theta' Rz(phi) e_x + beta' Ai2 e_y is a 3x3
linear system for (phi', theta', beta'); the joint rates are the relative angular velocities
projected on the joint axes, psi' = (w2 - w_i2) . Ai2 e_y, gamma' = (w4 - w3) . A3 e_z,
eps' = (w5 - w4) . A4 e_y; and [xc', yc'] are the horizontal components of
vG2 - w_i2 x Ai2 [0, 0, R_rear] (the hub's velocity minus the leaned frame's rotation about
the contact point). This is exact at every sample (no finite-difference error).
"""

from __future__ import annotations

import numpy as np

N_Q = 8
XC, YC, PHI, THETA, PSI, BETA, GAMMA, EPS = range(N_Q)
ANGLES = (PHI, THETA, PSI, BETA, GAMMA, EPS)
BODIES = (2, 3, 4, 5)
E_X, E_Y, E_Z = np.eye(3)


# -- elementary rotations, batched over leading axes ---------------------------------------

def _rot(axis: int, a) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    if axis == 0:
        m = [[o, z, z], [z, c, -s], [z, s, c]]
    elif axis == 1:
        m = [[c, z, s], [z, o, z], [-s, z, c]]
    else:
        m = [[c, -s, z], [s, c, z], [z, z, o]]
    return np.moveaxis(np.array(m), (0, 1), (-2, -1))


def Rx(a):
    return _rot(0, a)


def Ry(a):
    return _rot(1, a)


def Rz(a):
    return _rot(2, a)


def _mv(A, v):
    """A @ v batched: A (..., 3, 3), v (3,) or (..., 3)."""
    return np.einsum("...ij,...j->...i", A, v)


# -- forward: q, dq -> body states --------------------------------------------------------

def rotations(q) -> dict[str, np.ndarray]:
    """Ai2 and A2..A5 at q (8,) or (N, 8)."""
    q = np.asarray(q, dtype=float)
    Ai2 = Rz(q[..., PHI]) @ Rx(q[..., THETA])
    A3 = Ai2 @ Ry(q[..., BETA])
    A4 = A3 @ Rz(q[..., GAMMA])
    return {"i2": Ai2, 2: Ai2 @ Ry(q[..., PSI]), 3: A3, 4: A4, 5: A4 @ Ry(q[..., EPS])}


def body_states(params, q, dq=None) -> dict:
    """Global CoM positions ``r``, rotation matrices ``A``, CoM velocities ``v`` and angular
    velocities ``w`` of bodies 2..5 (dicts keyed by body number), plus the steering-axis
    point ``rA``. q, dq: (8,) or (N, 8); dq None gives no velocities."""
    p = params
    q = np.asarray(q, dtype=float)
    A = rotations(q)
    Ai2 = A["i2"]
    rC = np.stack([q[..., XC], q[..., YC], np.zeros_like(q[..., XC])], axis=-1)
    hub = _mv(Ai2, np.array([0.0, 0.0, p.R_rear]))
    rG2 = rC + hub
    d3 = _mv(A[3], np.array([p.x3, 0.0, p.z3]))
    dA = _mv(A[3], np.array([p.xa, 0.0, p.za]))
    rA = rG2 + dA
    d4 = _mv(A[4], np.array([p.dx4, 0.0, p.dz4]))
    d5 = _mv(A[4], np.array([p.x5, 0.0, p.z5]))
    out = {"A": {b: A[b] for b in BODIES}, "Ai2": Ai2, "rA": rA,
           "r": {2: rG2, 3: rG2 + d3, 4: rA + d4, 5: rA + d5}}
    if dq is None:
        return out
    dq = np.asarray(dq, dtype=float)
    ez = np.broadcast_to(E_Z, hub.shape)
    w_i2 = dq[..., PHI, None] * ez + dq[..., THETA, None] * _mv(Rz(q[..., PHI]), E_X)
    y_i2 = _mv(Ai2, E_Y)
    w2 = w_i2 + dq[..., PSI, None] * y_i2
    w3 = w_i2 + dq[..., BETA, None] * y_i2
    w4 = w3 + dq[..., GAMMA, None] * _mv(A[3], E_Z)
    w5 = w4 + dq[..., EPS, None] * _mv(A[4], E_Y)
    vC = np.stack([dq[..., XC], dq[..., YC], np.zeros_like(dq[..., XC])], axis=-1)
    vG2 = vC + np.cross(w_i2, hub)
    vA = vG2 + np.cross(w3, dA)
    out["v"] = {2: vG2, 3: vG2 + np.cross(w3, d3), 4: vA + np.cross(w4, d4),
                5: vA + np.cross(w4, d5)}
    out["w"] = {2: w2, 3: w3, 4: w4, 5: w5}
    return out


# -- backward: body poses -> q, dq ---------------------------------------------------------

def poses_to_q(params, r2, A2, A3, A4, A5) -> np.ndarray:
    """q (wrapped angles) from the rear hub position r2 (..., 3) and the rotation matrices
    A2..A5 (..., 3, 3) of the rear wheel, frame, fork and front wheel."""
    r2, A2, A3, A4, A5 = (np.asarray(a, dtype=float) for a in (r2, A2, A3, A4, A5))
    theta = np.arctan2(A3[..., 2, 1], np.hypot(A3[..., 2, 0], A3[..., 2, 2]))
    beta = np.arctan2(-A3[..., 2, 0], A3[..., 2, 2])
    phi = np.arctan2(-A3[..., 0, 1], A3[..., 1, 1])
    Ai2 = Rz(phi) @ Rx(theta)
    T = np.swapaxes
    R2 = T(Ai2, -1, -2) @ A2           # = Ry(psi)
    R4 = T(A3, -1, -2) @ A4            # = Rz(gamma)
    R5 = T(A4, -1, -2) @ A5            # = Ry(eps)
    psi = np.arctan2(R2[..., 0, 2], R2[..., 0, 0])
    gamma = np.arctan2(R4[..., 1, 0], R4[..., 0, 0])
    eps = np.arctan2(R5[..., 0, 2], R5[..., 0, 0])
    rC = r2 - _mv(Ai2, np.array([0.0, 0.0, params.R_rear]))
    return np.stack([rC[..., 0], rC[..., 1], phi, theta, psi, beta, gamma, eps], axis=-1)


def velocities_to_dq(params, q, v2, w2, w3, w4, w5) -> np.ndarray:
    """dq at (already mapped) q from the rear hub velocity v2 and the global angular
    velocities w2..w5, by solving the linear map (see the module docstring)."""
    q = np.asarray(q, dtype=float)
    v2, w2, w3, w4, w5 = (np.asarray(a, dtype=float) for a in (v2, w2, w3, w4, w5))
    A = rotations(q)
    Ai2 = A["i2"]
    x_i1 = _mv(Rz(q[..., PHI]), E_X)
    y_i2 = _mv(Ai2, E_Y)
    ez = np.broadcast_to(E_Z, x_i1.shape)
    G = np.stack([ez, x_i1, y_i2], axis=-1)             # w3 = G [phi', theta', beta']
    rates = np.linalg.solve(G, w3[..., None])[..., 0]
    dphi, dtheta, dbeta = rates[..., 0], rates[..., 1], rates[..., 2]
    w_i2 = dphi[..., None] * ez + dtheta[..., None] * x_i1
    dpsi = np.einsum("...i,...i->...", w2 - w_i2, y_i2)
    dgamma = np.einsum("...i,...i->...", w4 - w3, _mv(A[3], E_Z))
    deps = np.einsum("...i,...i->...", w5 - w4, _mv(A[4], E_Y))
    vC = v2 - np.cross(w_i2, _mv(Ai2, np.array([0.0, 0.0, params.R_rear])))
    return np.stack([vC[..., 0], vC[..., 1], dphi, dtheta, dpsi, dbeta, dgamma, deps], axis=-1)


def unwrap_angles(q, q_start=None) -> np.ndarray:
    """q (N, 8) with each angle series made continuous (np.unwrap) and shifted by whole turns
    so that its first sample is within pi of ``q_start`` (default: as it comes)."""
    q = np.array(q, dtype=float, copy=True)
    if q.shape[0] == 0:
        return q
    idx = list(ANGLES)
    q[:, idx] = np.unwrap(q[:, idx], axis=0)
    if q_start is not None:
        q_start = np.asarray(q_start, dtype=float)
        turns = np.round((q_start[idx] - q[0, idx]) / (2 * np.pi))
        q[:, idx] += 2 * np.pi * turns
    return q
