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
  numerically per state on the generated matrices (`eliminate`); it does not form the KKT
  system. The multipliers follow from the dependent rows, ``A_d'^T lam' = (M' du - F')_d``.
* forward runs (`KaneEngine.simulate`): the reference's own solvers
  (`reference_model.scenarios.run_forward`, DOP853, the scenario's constraint handling and
  fall events) with `KaneEngine.forward` as the right-hand side: the constrained equations
  above with the thesis's Baumgarte terms ``2 a1 A' u + a2^2 C'`` added to the bias. One state
  is evaluated by the generated scalar code (plain floats, ~0.1 ms), a batch by the
  vectorized one.

Only the disc front contact is Moore's geometry; the thesis's contact (the rim point along
the fork's -z) is not, and asking for it raises `CapabilityError`.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from reference_model import Model
from reference_model.model import ForwardResult, torque_array
from reference_model.moore import rates_from_moore, rates_to_moore
from reference_model.scenarios import Scenario, run_forward

from ..base import CapabilityError, Engine
from ..facts import Costs, RunSetup
from ..linear import DifferenceEigenvalues
from . import codegen
from .names import MOORE_PARAMETERS

__all__ = ["KaneEngine", "moore_parameters", "T_MAP", "ROW_SIGNS"]

#: u' = T_MAP @ dq (thesis rates -> Moore's speeds), from `reference_model.moore`.
T_MAP = rates_to_moore(np.eye(8)).T
#: dq = T_INV @ u' (Moore's speeds -> thesis rates).
T_INV = rates_from_moore(np.eye(8)).T
#: Moore's constraint rows -> the thesis's [rD_z, vC_x, vC_y, vD_x, vD_y].
ROW_SIGNS = np.array([-1.0, 1.0, -1.0, 1.0, -1.0])
#: Moore's independent speeds (u4 roll, u6 rear wheel, u7 steer) and dependent ones.
INDEPENDENT = (3, 5, 6)
DEPENDENT = (0, 1, 2, 4, 7)
_IND, _DEP = np.array(INDEPENDENT), np.array(DEPENDENT)
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


def _inverse(Ad: np.ndarray) -> tuple[float, np.ndarray | None]:
    """(reciprocal 1-norm condition number, inverse) of A_d; (0, None) if exactly singular.
    The 1-norm condition number (LAPACK's rcond measure) is within a factor 5 of the
    2-norm one for a 5x5 matrix and costs two sums instead of an SVD."""
    try:
        inv = np.linalg.inv(Ad)
    except np.linalg.LinAlgError:
        return 0.0, None
    return 1.0 / (np.abs(Ad).sum(axis=0).max() * np.abs(inv).sum(axis=0).max()), inv


def _speed_partition(A: np.ndarray):
    """One state's (dependent speeds (5,), independent speeds (3,), rcond of A_d, A_d^-1).

    Moore's choice (independent u4, u6, u7: roll, rear wheel, steer) when its A_d is well
    conditioned (rcond >= `RCOND_MOORE`); else the five columns a column-pivoted QR of A picks.
    Near a steer of +-90 degrees Moore's A_d becomes nearly singular (measured rcond 2e-5 at
    steer 1.49 rad on the benchmark bicycle) and the elimination would lose five digits
    there, though the constraints themselves stay well conditioned (cond(D) < 11).
    """
    rcond, inv = _inverse(A[:, _DEP])
    if rcond >= RCOND_MOORE:
        return _DEP, _IND, rcond, inv
    piv = scipy.linalg.qr(A, mode="r", pivoting=True)[1]
    dep, ind = np.sort(piv[:5]), np.sort(piv[5:])
    return (dep, ind, *_inverse(A[:, dep]))


def eliminate(M, F, A, b) -> tuple[np.ndarray, np.ndarray] | None:
    """Kane's constrained equations at one state, in Moore's coordinates: (du/dt (8,),
    Moore's multipliers (5,)), or None where the constraints do not determine five speeds.

    ``M du = F + A^T lam``, ``A du + b = 0`` (b: the acceleration-level constraint bias,
    Baumgarte terms included). The dependent speeds' coefficients ``C = -A_d^-1 A_i`` give
    the nonholonomic partial velocities ``W = [I; C]`` (rows placed per the partition), the
    generalized forces are reduced onto the independent speeds,
    ``(W^T M W) du_i = W^T (F - M du_p)``, ``du_p = -A_d^-1 b`` the dependent accelerations
    the constraints force at du_i = 0. The multipliers are not needed for du; they are the
    constraint forces ``A_d^T lam = (M du - F)_d`` (for the solvers' `ForwardResult`).
    """
    dep, ind, rcond, inv = _speed_partition(A)
    if not rcond > RCOND_MIN:
        return None
    W = np.zeros((8, 3))
    W[ind] = np.eye(3)
    W[dep] = -inv @ A[:, ind]
    du_p = np.zeros(8)
    du_p[dep] = -inv @ b
    Wt = W.T
    du = W @ np.linalg.solve(Wt @ M @ W, Wt @ (F - M @ du_p)) + du_p
    lam = inv.T @ (M @ du - F)[dep]
    return du, lam


class KaneEngine(DifferenceEigenvalues, Engine):
    """Moore's Whipple bicycle (sympy KanesMethod, generated numpy code), disc contact only."""

    name = "kane"
    capabilities = frozenset({"mass_matrix", "generalized_forces", "constraint_jacobian",
                              "constraint_bias", "forward_acceleration", "simulate",
                              "eigenvalues"})
    contacts = ("disc",)
    label = "Kane"
    colour = "tab:purple"
    marker = "D"
    #: the reference's own solvers on Kane's equations: judged to [trajectory]
    trajectory_tolerance = "trajectory"
    run_setups = (RunSetup(kinds=("forward",),
                           settings="Moore's Whipple bicycle by Kane's method (sympy KanesMethod, "
                                    "generated code, dependent speeds eliminated per state) in the "
                                    "reference's solvers (same integrator and tolerances); disc "
                                    "front contact only; no inverse dynamics"),)
    #: per simulated second of its own runs (DOP853 with projection, ~3.6 ms per right-hand
    #: side): the 1 s energy drift run measured 1.3-1.6 s of CPU on the 2-core machine. Its
    #: thesis-contact scenario runs are refused at once; declared at 0.3 s the energy drift
    #: was queued last and ran alone at the end of the run
    costs = Costs(run_per_second=1.4, short_run=0.8, terms=1.5, faults=2.0)

    @classmethod
    def prepare(cls) -> None:
        """Derive and generate the code if the cache is cold (~9 s), once, before workers fork."""
        codegen.load()

    def __init__(self, model: Model):
        if model.contact not in self.contacts:
            raise CapabilityError(
                f"engine 'kane' cannot use the front contact {model.contact!r}: Moore's Whipple "
                "bicycle touches the ground at the disc's lowest point, not at the thesis's rim "
                "point along the fork's -z; use a disc-contact model (e.g. thesis-disc)")
        super().__init__(model)
        self.p = moore_parameters(model.params)
        self.code = codegen.load()
        # duck-typed attributes the reference solvers read
        self.params, self.contact = model.params, model.contact

    # -- Moore's coordinates ------------------------------------------------------------
    def _moore(self, q, dq=None):
        qa, one = _states(q, "q")
        qm = rates_to_moore(qa)
        if dq is None:
            return qm, None, one
        da, _ = _states(dq, "dq")
        _same(qa, da, "q and dq")
        return qm, rates_to_moore(da), one

    def _out(self, x: np.ndarray, one: bool) -> np.ndarray:
        if not np.all(np.isfinite(x)):
            raise ArithmeticError(f"engine '{self.name}': a non-finite value at this state")
        return x[0] if one else x

    def _generated(self, name: str, shape: tuple[int, int], qm: np.ndarray,
                   um: np.ndarray | None = None) -> np.ndarray:
        """Moore's generated ``name`` (N, rows, cols); one state through its scalar version
        (``name_one``: 40-50 us for M per call, measured, against ~0.5 ms for the vectorized
        code on one state, which the initial-state solve and the projection after every step
        of a run would pay)."""
        args = (qm,) if um is None else (qm, um)
        if len(qm) != 1:
            return getattr(self.code, name)(*args, self.p)
        try:
            flat = getattr(self.code, f"{name}_one")(*(a[0].tolist() for a in args),
                                                     self.p.tolist())
            return np.array(flat, dtype=float).reshape((1, *shape))
        except (ArithmeticError, ValueError, TypeError):   # math domain, complex powers
            return np.full((1, *shape), np.nan)             # `_out` says non-finite

    # -- the capabilities ----------------------------------------------------------------
    def mass_matrix(self, q):
        qm, _, one = self._moore(q)
        Mm = self._generated("mass", (8, 8), qm)
        return self._out(T_MAP.T @ Mm @ T_MAP, one)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        qm, um, one = self._moore(q, dq)
        F = self.code.forcing(qm, um, self.p, _torques(torques, len(qm)))[:, :, 0]
        return self._out(F @ T_MAP, one)

    def constraint_jacobian(self, q):
        qm, _, one = self._moore(q)
        A = self._generated("jacobian", (5, 8), qm)
        return self._out(ROW_SIGNS[:, None] * A @ T_MAP, one)

    def constraint_bias(self, q, dq):
        qm, um, one = self._moore(q, dq)
        b = self.code.bias(qm, um, self.p)[:, :, 0]
        return self._out(ROW_SIGNS * b, one)

    def constraint_residual(self, q, dq):
        """C = [rD_z, vC_x, vC_y, vD_x, vD_y] from Moore's constraint expressions (the
        reference solvers' duck-typed method: initial states, projection, Baumgarte)."""
        qm, um, one = self._moore(q, dq)
        return self._out(ROW_SIGNS * self._generated("constraints", (5, 1), qm, um)[:, :, 0], one)

    # -- Kane's constrained equations -------------------------------------------------------
    def _forward_one(self, q, dq, T, a12) -> tuple[np.ndarray, np.ndarray, int]:
        """(ddq, lambda, status) at one thesis state; status 0 ok, 1 singular or a non-finite
        result, 2 non-finite state. Moore's M, F, A, b and C from the generated scalar code
        (`codegen.TERMS_ONE`); the Baumgarte terms ``2 a1 A u + a2^2 C`` join the bias."""
        um = T_MAP @ dq
        out = None
        try:
            t = np.array(self.code.terms_one((T_MAP @ q).tolist(), um.tolist(), self.p.tolist(),
                                             T.tolist()), dtype=float)
            A, b = t[72:112].reshape(5, 8), t[112:117]
            a1, a2 = a12
            if a1 or a2:
                b = b + 2.0 * a1 * (A @ um) + (a2 * a2) * t[117:122]
            out = eliminate(t[:64].reshape(8, 8), t[64:72], A, b)
        except (ArithmeticError, ValueError, TypeError):   # math domain, complex powers, NaN
            pass
        if out is not None:
            ddq, lam = T_INV @ out[0], -ROW_SIGNS * out[1]
            if math.isfinite(ddq.sum() + lam.sum()):
                return ddq, lam, 0
        finite = math.isfinite(q.sum() + dq.sum() + T.sum())
        return np.full(8, np.nan), np.full(5, np.nan), 1 if finite else 2

    def forward(self, q, dq, torques=(0.0, 0.0, 0.0), baumgarte=(0.0, 0.0)) -> ForwardResult:
        """Kane's constrained equations with the thesis's constraint handling, in the thesis's
        coordinates: ``D ddq = -dD dq - 2 a1 D dq - a2^2 C`` (``baumgarte=(a1, a2)``; (0, 0)
        gives the exact accelerations), ``M ddq + D^T lambda = F + S T`` like the reference's
        `reference_model.Model.forward` (the duck-typed method its solvers call).

        Never raises on a bad state: the status array says (0 ok, 1 singular or a non-finite
        result, 2 non-finite state), ddq and lambda are NaN there.
        """
        a12 = (float(baumgarte[0]), float(baumgarte[1]))
        qa, one = _states(q, "q")
        da, _ = _states(dq, "dq")
        _same(qa, da, "q and dq")
        T = np.asarray(torque_array(torques, len(qa), one), dtype=float)
        res = [self._forward_one(qa[k], da[k], T[k], a12) for k in range(len(qa))]
        ddq = np.array([r[0] for r in res])
        lam = np.array([r[1] for r in res])
        status = np.array([r[2] for r in res], dtype=np.intc)
        return ForwardResult(ddq[0], lam[0], status) if one else ForwardResult(ddq, lam, status)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        res = self.forward(q, dq, torques)
        if res.status.any():
            k = int(np.flatnonzero(res.status)[0])
            raise ArithmeticError(
                f"engine '{self.name}': at state {k} " + ("the constraints do not determine five "
                                                   "speeds (a kinematic singularity)"
                                                   if res.status[k] == 1 else
                                                   "the state is not finite"))
        return res.ddq

    # -- scenarios -------------------------------------------------------------------------
    def simulate(self, scenario: Scenario, **options):
        """A forward run of ``scenario`` on Kane's equations: the reference's solvers
        (`reference_model.scenarios.run_forward`: the initial state projected on Kane's
        constraints, DOP853, the scenario's constraint handling, fall events) with this
        engine's `forward` as the right-hand side. A torque history named by another scenario
        (replay: zigzag's inverse dynamics) is an input, computed by the reference model, as
        for Exudyn: this engine has no inverse dynamics."""
        return run_forward(self, scenario, torques_from=self.model, **options)
