"""The `kane` engine: Moore's Whipple bicycle by Kane's method, in the thesis's coordinates.

The equations are Moore's (`engines.kane.derivation`), in Moore's coordinates q1..q8, speeds
u = dq/dt, and mapped to the thesis's by the constant linear map of `reference_model.moore`,
``u = T dq`` (T a signed permutation plus ``u6 = d_beta - d_psi``):

* mass matrix        ``M = T^T M' T``            (kinetic energy is invariant)
* generalized forces ``Q = T^T F'``              (virtual power is invariant); F' includes
  gravity, the frame's drag ``-cv |v| v`` and the rider's torques, all exact in Moore's model
* constraints        ``D = R D' T``, ``dD dq = R b'`` with ``R = diag(-1, 1, -1, 1, -1)``:
  Moore's N has y and z reversed (z down), so the front contact's height and the y velocity
  components change sign.
* forward accelerations: Kane's constrained equations. Moore's independent speeds u4, u6, u7
  (roll, rear wheel, steer), dependent u1, u2, u3, u5, u8 (other ones where that choice is
  ill-conditioned, near a steer of +-90 degrees: `_speed_partition`); the dependent speeds' coefficients
  ``C = -A_d^-1 A_i`` give the nonholonomic partial velocities, the generalized forces are
  reduced onto the independent speeds, ``(W^T M' W) du_i = W^T (F' - M' du_p)`` with
  ``W = [I; C]`` and ``du_p`` the dependent accelerations the constraints force at du_i = 0
  (the acceleration-level constraints ``A' du + b' = 0``). This elimination runs
  numerically per state on the generated matrices; it does not form the KKT system.

Only the disc front contact is Moore's geometry; the thesis's contact (the rim point along
the fork's -z) is not, and asking for it raises `CapabilityError`.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from reference_model import Model
from reference_model.moore import rates_from_moore, rates_to_moore

from ..base import CapabilityError, Engine
from . import codegen
from .derivation import MOORE_PARAMETERS

__all__ = ["KaneEngine", "moore_parameters", "T_MAP", "ROW_SIGNS"]

#: u' = T_MAP @ dq (thesis rates -> Moore's speeds), from `reference_model.moore`.
T_MAP = rates_to_moore(np.eye(8)).T
#: Moore's constraint rows -> the thesis's [rD_z, vC_x, vC_y, vD_x, vD_y].
ROW_SIGNS = np.array([-1.0, 1.0, -1.0, 1.0, -1.0])
#: Moore's independent speeds (u4 roll, u6 rear wheel, u7 steer) and dependent ones.
INDEPENDENT = (3, 5, 6)
DEPENDENT = (0, 1, 2, 4, 7)
#: Below this reciprocal condition number of Moore's A_d, the dependent speeds are chosen
#: by pivoting instead (see `_speed_partition`): rcond 1e-2 costs at most two digits.
RCOND_MOORE = 1e-2
#: A_d with a reciprocal condition number below this is singular for the elimination.
RCOND_MIN = 1e-13


def moore_parameters(params) -> np.ndarray:
    """The model's parameters as Moore's, in `MOORE_PARAMETERS` order.

    d1 = xa, d2 = -(za + z5), d3 = x5, l1 = x3, l2 = -z3, l3 = dx4 - x5, l4 = z5 - dz4; Moore's
    body frames are the thesis's with y and z reversed, so the xz products change sign.
    """
    p = params
    m = {
        "rr": p.R_rear, "rf": p.R_front,
        "d1": p.xa, "d2": -(p.za + p.z5), "d3": p.x5,
        "l1": p.x3, "l2": -p.z3, "l3": p.dx4 - p.x5, "l4": p.z5 - p.dz4,
        "mc": p.m3, "md": p.m2, "me": p.m4, "mf": p.m5,
        "IDxx": p.I2xx, "IDyy": p.I2yy, "IDzz": p.I2zz,
        "ICxx": p.I3xx, "ICyy": p.I3yy, "ICzz": p.I3zz, "ICxz": -p.I3xz,
        "IExx": p.I4xx, "IEyy": p.I4yy, "IEzz": p.I4zz, "IExz": -p.I4xz,
        "IFxx": p.I5xx, "IFyy": p.I5yy, "IFzz": p.I5zz,
        "g": p.g, "cv": p.cv,
    }
    return np.array([float(m[k]) for k in MOORE_PARAMETERS])


def _states(x, name: str) -> tuple[np.ndarray, bool]:
    a = np.asarray(x, dtype=float)
    if a.ndim not in (1, 2) or a.shape[-1] != 8:
        raise ValueError(f"{name} must have shape (8,) or (N, 8); got {a.shape}")
    return np.atleast_2d(a), a.ndim == 1


def _torques(torques, n: int) -> np.ndarray:
    T = np.asarray(torques, dtype=float)
    if T.shape == (3,):
        return np.broadcast_to(T, (n, 3))
    if T.shape != (n, 3):
        raise ValueError(f"torques must have shape (3,) or ({n}, 3) [Mdir, Mped, Mvue]; got {T.shape}")
    return T


def _same(a: np.ndarray, b: np.ndarray, names: str) -> None:
    if a.shape != b.shape:
        raise ValueError(f"{names} must have the same shape; got {a.shape} and {b.shape}")


def _speed_partition(A: np.ndarray) -> np.ndarray:
    """Per state, Moore's speeds ordered [5 dependent, 3 independent].

    Moore's choice (independent u4, u6, u7: roll, rear wheel, steer) when its A_d is well
    conditioned (rcond >= `RCOND_MOORE`); else the five columns a column-pivoted QR of A picks.
    Near a steer of +-90 degrees Moore's A_d becomes nearly singular (measured rcond 2e-5 at
    steer 1.49 rad on the benchmark bicycle) and the elimination would lose five digits
    there, though the constraints themselves stay well conditioned (cond(D) < 11).
    """
    moore = np.array(DEPENDENT + INDEPENDENT)
    perm = np.tile(moore, (len(A), 1))
    rcond = 1.0 / np.linalg.cond(A[:, :, list(DEPENDENT)])
    for k in np.flatnonzero(~(rcond >= RCOND_MOORE)):
        if np.all(np.isfinite(A[k])):
            piv = scipy.linalg.qr(A[k], mode="r", pivoting=True)[1]
            perm[k] = np.concatenate([np.sort(piv[:5]), np.sort(piv[5:])])
    return perm


class KaneEngine(Engine):
    """Moore's Whipple bicycle (sympy KanesMethod, generated numpy code), disc contact only."""

    name = "kane"
    capabilities = frozenset({"mass_matrix", "generalized_forces", "constraint_jacobian",
                              "constraint_bias", "forward_acceleration"})
    contacts = ("disc",)

    def __init__(self, model: Model):
        if model.contact not in self.contacts:
            raise CapabilityError(
                f"engine 'kane' cannot use the front contact {model.contact!r}: Moore's Whipple "
                "bicycle touches the ground at the disc's lowest point, not at the thesis's rim "
                "point along the fork's -z; use a disc-contact model (e.g. thesis-disc)")
        super().__init__(model)
        self.p = moore_parameters(model.params)
        self.code = codegen.load()

    # -- Moore's coordinates ------------------------------------------------------------
    def _moore(self, q, dq=None):
        qa, one = _states(q, "q")
        qm = rates_to_moore(qa)
        if dq is None:
            return qm, None, one
        da, _ = _states(dq, "dq")
        _same(qa, da, "q and dq")
        return qm, rates_to_moore(da), one

    @staticmethod
    def _out(x: np.ndarray, one: bool) -> np.ndarray:
        if not np.all(np.isfinite(x)):
            raise ArithmeticError("engine 'kane': a non-finite value at this state")
        return x[0] if one else x

    # -- the capabilities ----------------------------------------------------------------
    def mass_matrix(self, q):
        qm, _, one = self._moore(q)
        Mm = self.code.mass(qm, self.p)
        return self._out(T_MAP.T @ Mm @ T_MAP, one)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        qm, um, one = self._moore(q, dq)
        F = self.code.forcing(qm, um, self.p, _torques(torques, len(qm)))[:, :, 0]
        return self._out(F @ T_MAP, one)

    def constraint_jacobian(self, q):
        qm, _, one = self._moore(q)
        A = self.code.jacobian(qm, self.p)
        return self._out(ROW_SIGNS[:, None] * A @ T_MAP, one)

    def constraint_bias(self, q, dq):
        qm, um, one = self._moore(q, dq)
        b = self.code.bias(qm, um, self.p)[:, :, 0]
        return self._out(ROW_SIGNS * b, one)

    def moore_accelerations(self, qm: np.ndarray, um: np.ndarray, T: np.ndarray) -> np.ndarray:
        """du/dt (N, 8) from Kane's constrained equations, in Moore's coordinates."""
        M = self.code.mass(qm, self.p)
        F = self.code.forcing(qm, um, self.p, T)[:, :, 0]
        A = self.code.jacobian(qm, self.p)
        b = self.code.bias(qm, um, self.p)[:, :, 0]
        n = len(qm)
        perm = _speed_partition(A)                      # (n, 8): 5 dependent, 3 independent
        dep, ind = perm[:, :5], perm[:, 5:]
        Ad = np.take_along_axis(A, dep[:, None, :], axis=2)
        Ai = np.take_along_axis(A, ind[:, None, :], axis=2)
        rcond = 1.0 / np.linalg.cond(Ad)
        if np.any(~(rcond > RCOND_MIN)):
            k = int(np.argmin(np.nan_to_num(rcond)))
            raise ArithmeticError(f"engine 'kane': the constraints do not determine five speeds "
                                  f"at state {k} (rcond {rcond[k]:.1e})")
        W = np.zeros((n, 8, 3))
        np.put_along_axis(W, ind[:, :, None], np.eye(3)[None], axis=1)
        np.put_along_axis(W, dep[:, :, None], -np.linalg.solve(Ad, Ai), axis=1)
        du_p = np.zeros((n, 8))
        np.put_along_axis(du_p, dep, np.linalg.solve(Ad, -b[:, :, None])[:, :, 0], axis=1)
        Wt = np.swapaxes(W, 1, 2)
        rhs = Wt @ (F - (M @ du_p[:, :, None])[:, :, 0])[:, :, None]
        a = np.linalg.solve(Wt @ M @ W, rhs)
        return (W @ a)[:, :, 0] + du_p

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        qm, um, one = self._moore(q, dq)
        du = self.moore_accelerations(qm, um, _torques(torques, len(qm)))
        return self._out(rates_from_moore(du), one)
