"""The crown-radius study's arithmetic: the roll/steer eigenvalues of SymBRiM's bicycle about
upright straight running, for a toroidal front tyre, by central differences of the engine's own
constrained accelerations.

The state is the thesis's [theta, gamma, d_theta, d_gamma] with the rear wheel rolling at
``d_psi = v / R_rear``; for each perturbed state the pitch beta is solved from the engine's own
front-contact height (the torus's lowest point, Newton on row 0 of its constraints) and the
dependent rates from its constraint Jacobian, so the crown enters through SymBRiM's contact
point only. Central differences with step ``h`` = 1e-6: truncation ~h^2 and round-off ~1e-16/h,
1e-9..1e-10 relative, far below the crown's effect (checked at crown 0 against the reference's
exact linearization in tests/test_symbrim.py).
"""

from __future__ import annotations

import numpy as np

from reference_model.linearize import sort_eigenvalues

__all__ = ["crown_eigenvalues"]

_THETA, _PSI, _BETA, _GAMMA = 3, 4, 5, 6
_DEP = np.array([0, 1, 2, 5, 7])
_IND = np.array([3, 4, 6])


def _state(engine, x, v):
    """(q, dq) on the engine's constraints for x = [theta, gamma, d_theta, d_gamma]."""
    q = np.zeros(8)
    q[_THETA], q[_GAMMA] = x[0], x[1]
    for _ in range(50):                         # Newton on the front contact's height
        r = engine.constraint_residual(q, np.zeros(8))[0]
        q[_BETA] -= r / engine.constraint_jacobian(q)[0, _BETA]
        if abs(r) < 1e-15:
            break
    D = engine.constraint_jacobian(q)
    dq = np.zeros(8)
    dq[_IND] = [x[2], v / engine.model.params.R_rear, x[3]]
    dq[_DEP] = np.linalg.solve(D[:, _DEP], -D[:, _IND] @ dq[_IND])
    return q, dq


def _rates(engine, x, v):
    q, dq = _state(engine, x, v)
    ddq = engine.forward_acceleration(q, dq)
    return np.array([x[2], x[3], ddq[_THETA], ddq[_GAMMA]])


def crown_eigenvalues(engine, speeds, h: float = 1e-6) -> np.ndarray:
    """(n, 4) eigenvalues (sorted as the reference's) of the engine's roll/steer dynamics at
    each forward speed (m/s), for its bicycle and crown radius."""
    out = []
    for v in np.atleast_1d(np.asarray(speeds, dtype=float)):
        A = np.empty((4, 4))
        for j in range(4):
            e = np.zeros(4)
            e[j] = h
            A[:, j] = (_rates(engine, e, v) - _rates(engine, -e, v)) / (2 * h)
        out.append(sort_eigenvalues(np.linalg.eigvals(A)))
    return np.array(out)
