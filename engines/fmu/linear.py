"""The roll/steer linearization of an engine about upright straight running, from a
Jacobian-vector product of its state derivatives: pure arithmetic, no FMU calls of its own.

The bicycle's state is s = (q, dq) (16, thesis coordinates) with f(s) = (dq, ddq), ddq the exact
constrained accelerations. The steady motion at forward speed v: theta = gamma = 0, the rear
wheel rolling at ``d_psi = v / R_rear``, the frame pitch beta solved from the front contact's
height ``C[0] = [rD]_z = 0`` (Newton), the dependent rates from the constraint Jacobian,
``dq_dep = -D_dep^-1 D_ind dq_ind``. The independent roll/steer states are
x = [theta, gamma, d_theta, d_gamma]; each one's tangent of the constraint manifold keeps the
dependent coordinates on the constraints to first order:

* theta or gamma: ``dq_k = 1``, ``d beta = -D[0, k] / D[0, beta]`` (the height row of D is the
  gradient of [rD]_z), and the dependent rates change with D along that direction:
  ``D_dep d(dq_dep) = -(dD . dq_dir) dq0``;
* d_theta or d_gamma: ``d(dq_k) = 1``, ``D_dep d(dq_dep) = -D[:, k]``.

Then ``A[:, k] = J_f(s0) t_k`` read at the rows of [d_theta, d_gamma, dd_theta, dd_gamma]: four
Jacobian-vector products, exactly the linearization of the reduced dynamics that
reference_model/linearize.py differentiates by complex steps (beta's dependence on roll and
steer, the dependent rates' on the configuration). The eigenvalues are sorted by
`reference_model.linearize.sort_eigenvalues`.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from reference_model.linearize import LinearizationError, sort_eigenvalues
from reference_model.names import COORDINATES

__all__ = ["ROWS", "roll_steer_eigenvalues", "state_matrix", "tangents", "upright_state"]

_THETA, _PSI, _BETA, _GAMMA = (COORDINATES.index(n) for n in ("theta", "psi", "beta", "gamma"))
_DEP = np.array([COORDINATES.index(n) for n in ("xc", "yc", "phi", "beta", "eps")])
_IND = np.array([_THETA, _PSI, _GAMMA])
#: the rows of f = (dq, ddq) holding [d_theta, d_gamma, dd_theta, dd_gamma]
ROWS = np.array([_THETA, _GAMMA, 8 + _THETA, 8 + _GAMMA])
_NEWTON_TOL = 1e-14   # m: the front contact's height at the solved pitch
_NEWTON_MAX = 50

Residual = Callable[[np.ndarray, np.ndarray], np.ndarray]   # (q, dq) -> C (5,)
Jacobian = Callable[[np.ndarray], np.ndarray]               # q -> D (5, 8)
Along = Callable[[np.ndarray, np.ndarray], np.ndarray]      # (q, dq_dir) -> dD . dq_dir (5, 8)
Jvp = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]   # (q, dq, ds) -> J_f ds (16,)


def upright_state(residual: Residual, jacobian: Jacobian, v: float,
                  R_rear: float) -> tuple[np.ndarray, np.ndarray]:
    """(q, dq) of upright straight running at forward speed ``v`` (m/s) on the constraints:
    beta by Newton on the front contact's height, the dependent rates from D."""
    q = np.zeros(8)
    for _ in range(_NEWTON_MAX):
        height = float(residual(q, np.zeros(8))[0])
        if abs(height) <= _NEWTON_TOL:
            break
        slope = float(jacobian(q)[0, _BETA])
        if not abs(slope) > 1e-12:
            raise LinearizationError("d[rD]_z/dbeta vanishes at upright: the front contact does "
                                     "not fix the frame pitch; check the geometry")
        q[_BETA] -= height / slope
    else:
        raise LinearizationError(f"Newton on [rD]_z = 0 for the pitch beta did not converge in "
                                 f"{_NEWTON_MAX} iterations (height {height:.2e} m)")
    D = jacobian(q)
    dq = np.zeros(8)
    dq[_PSI] = v / R_rear
    dq[_DEP] = np.linalg.solve(D[:, _DEP], -D[:, _IND] @ dq[_IND])
    return q, dq


def tangents(jacobian: Jacobian, along: Along, q0: np.ndarray, dq0: np.ndarray) -> np.ndarray:
    """(4, 16): the state changes ds per unit theta, gamma, d_theta, d_gamma that keep the
    constraints to first order (module docstring)."""
    D = jacobian(q0)
    out = np.zeros((4, 16))
    for k, j in enumerate((_THETA, _GAMMA)):
        dq_dir = np.zeros(8)
        dq_dir[j] = 1.0
        dq_dir[_BETA] = -D[0, j] / D[0, _BETA]
        out[k, :8] = dq_dir
        out[k, 8 + _DEP] = np.linalg.solve(D[:, _DEP], -along(q0, dq_dir) @ dq0)
    for k, j in enumerate((_THETA, _GAMMA), start=2):
        out[k, 8 + j] = 1.0
        out[k, 8 + _DEP] = np.linalg.solve(D[:, _DEP], -D[:, j])
    return out


def state_matrix(jvp: Jvp, jacobian: Jacobian, along: Along, q0: np.ndarray,
                 dq0: np.ndarray) -> np.ndarray:
    """A (4x4): d/dt [theta, gamma, d_theta, d_gamma] = A [theta, gamma, d_theta, d_gamma]."""
    T = tangents(jacobian, along, q0, dq0)
    return np.column_stack([jvp(q0, dq0, t)[ROWS] for t in T])


def roll_steer_eigenvalues(jvp: Jvp, derivatives: Callable[[np.ndarray, np.ndarray], np.ndarray],
                           residual: Residual, jacobian: Jacobian, along: Along, speeds,
                           R_rear: float, g: float) -> np.ndarray:
    """(n, 4) complex: the roll/steer eigenvalues (1/s) at each forward speed (m/s), sorted as
    `sort_eigenvalues`. ``derivatives(q, dq)`` is f's ddq, checked to vanish at each steady
    motion to 1e-8 of the accelerations' scale g + (v / R_rear)^2 R_rear (drag, or any force
    that keeps it from being one, raises `LinearizationError`)."""
    v = np.atleast_1d(np.asarray(speeds, dtype=float))
    if v.ndim != 1 or not np.all(np.isfinite(v)):
        raise ValueError(f"speeds must be a finite speed or a 1-D array of them (m/s); got {speeds!r}")
    out = np.empty((v.size, 4), dtype=complex)
    for i, vi in enumerate(v):
        q0, dq0 = upright_state(residual, jacobian, float(vi), R_rear)
        ddq = derivatives(q0, dq0)
        scale = g + vi * vi / R_rear
        if np.max(np.abs(ddq)) > 1e-8 * scale:
            raise LinearizationError(
                f"upright straight running at {vi:g} m/s is not a steady motion of this engine "
                f"(accelerations up to {np.max(np.abs(ddq)):.2e} there; drag cv > 0?); fix: "
                "linearize a model without drag, model.params.replace(cv=0.0)")
        out[i] = sort_eigenvalues(np.linalg.eigvals(state_matrix(jvp, jacobian, along, q0, dq0)))
    return out
