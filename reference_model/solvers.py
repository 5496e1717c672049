"""Solvers of the thesis model: consistent initial state, inverse kinematics, inverse and
forward dynamics.

* `consistent_state`: given the independent coordinates (theta, psi, gamma) and their rates,
  solve the frame pitch beta from the holonomic constraint [rD]_z = 0 (Newton) and the
  dependent rates from D dq = 0, and report the correction applied.
* `inverse_kinematics`: the thesis's `cinBicicleta` — prescribed theta(t), psi(t), gamma(t);
  the dependent rates from D_dep dq_dep = -D_ind dq_ind integrated at tight tolerance;
  optionally beta re-solved from [rD]_z = 0 at every evaluation so no drift builds up.
* `inverse_dynamics`: the thesis's 13x13 system along an inverse-kinematics motion, giving the
  rider torques T = [Mdir, Mped, Mvue] and the five multipliers.
* `simulate`: forward dynamics (`din_Bicicleta`) with the constraints handled by Baumgarte
  stabilisation as in the thesis (a1 = a2 = 10), by projection onto the constraint manifold
  after every step, or not at all (exact accelerations only). A run ends cleanly at a fall
  (|theta| reaching ``fall_limit``) or at a solver failure, returning its status and the
  partial trajectory, never NaNs.
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.integrate import DOP853, solve_ivp
from scipy.optimize import brentq

from .model import DEP, IND, N_C, N_Q, Model

BETA = 5            # index of the frame pitch in q
THETA = 3           # index of the roll angle in q
CONSTRAINT_HANDLING = ("baumgarte", "projection", "none")
THESIS_BAUMGARTE = (10.0, 10.0)
DEFAULT_FALL_LIMIT = 1.4  # rad (80 deg): the frame is on the ground well before pi/2


def checked_fall_limit(fall_limit) -> float:
    """The fall limit (the lean |theta| in rad at which a forward run ends as a fall) as a
    float, or ValueError in one line: a real, finite, positive number (not a bool, not text).
    The one rule every time loop applies (the reference's solvers, the engines' own)."""
    if not (isinstance(fall_limit, numbers.Real) and not isinstance(fall_limit, bool)
            and math.isfinite(fall_limit) and fall_limit > 0):
        raise ValueError(f"fall_limit must be a positive angle in rad; got {fall_limit!r}")
    return float(fall_limit)


class ConstraintSolveError(ArithmeticError):
    """Newton on [rD]_z = 0 did not converge, or D_dep is singular."""


# -- consistent initial state ----------------------------------------------------------

@dataclass(frozen=True)
class ConsistentState:
    """A state satisfying all five constraints, and how far the input was from it."""

    q: np.ndarray
    dq: np.ndarray
    q_given: np.ndarray
    dq_given: np.ndarray
    iterations: int
    residual_before: np.ndarray   # C at (q_given, dq_given)
    residual_after: np.ndarray    # C at (q, dq)

    @property
    def beta_correction(self) -> float:
        """beta(consistent) - beta(given), rad."""
        return float(self.q[BETA] - self.q_given[BETA])

    def describe(self) -> str:
        return (f"beta corrected by {self.beta_correction:+.6e} rad in {self.iterations} Newton "
                f"iteration(s); front contact height {self.residual_before[0]:+.3e} m -> "
                f"{self.residual_after[0]:+.1e} m; max |velocity constraint| "
                f"{np.max(np.abs(self.residual_before[1:])):.3e} -> "
                f"{np.max(np.abs(self.residual_after[1:])):.1e} m/s")


def solve_beta(model: Model, q, tol: float = 1e-14, max_iter: int = 50) -> tuple[np.ndarray, int]:
    """q with beta solved from [rD]_z(q) = 0 by Newton (the other coordinates fixed)."""
    q = np.array(q, dtype=np.float64)
    zero = np.zeros(N_Q)
    for it in range(max_iter + 1):
        h = model.constraint_residual(q, zero)[0]
        if abs(h) <= tol:
            return q, it
        slope = model.constraint_jacobian(q)[0, BETA]
        if abs(slope) < 1e-12:
            raise ConstraintSolveError(
                f"d[rD]_z/dbeta = {slope:.2e} at q = {np.round(q, 6).tolist()}: the front contact "
                "height does not depend on the frame pitch here (singular configuration)")
        q[BETA] -= h / slope
    raise ConstraintSolveError(f"Newton on [rD]_z = 0 did not converge in {max_iter} iterations "
                               f"(residual {h:.3e} m); is the configuration reachable?")


def dependent_rates(model: Model, q, dq_ind) -> np.ndarray:
    """Full dq from the independent rates [dtheta, dpsi, dgamma]: D_dep dq_dep = -D_ind dq_ind."""
    D = model.constraint_jacobian(q)
    Ddep = D[:, DEP]
    try:
        dq_dep = np.linalg.solve(Ddep, -D[:, IND] @ np.asarray(dq_ind, dtype=np.float64))
    except np.linalg.LinAlgError:
        raise ConstraintSolveError(f"D_dep is singular at q = {np.round(q, 6).tolist()}: the "
                                   "dependent rates are not determined by theta, psi, gamma here") from None
    dq = np.empty(N_Q)
    dq[DEP] = dq_dep
    dq[IND] = dq_ind
    return dq


def consistent_state(model: Model, q, dq) -> ConsistentState:
    """Project (q, dq) onto the constraints keeping theta, psi, gamma and their rates.

    beta is solved from [rD]_z = 0 starting at the given beta; xc, yc, phi, eps are kept
    (the constraints do not fix them); the dependent rates follow from D dq = 0.
    """
    q0 = np.array(q, dtype=np.float64).reshape(N_Q)
    dq0 = np.array(dq, dtype=np.float64).reshape(N_Q)
    if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(dq0))):
        raise ValueError("initial state must be finite (no NaN or inf in q0, dq0)")
    before = model.constraint_residual(q0, dq0)
    q1, its = solve_beta(model, q0)
    dq1 = dependent_rates(model, q1, dq0[IND])
    return ConsistentState(q1, dq1, q0, dq0, its, before, model.constraint_residual(q1, dq1))


# -- inverse kinematics and dynamics ---------------------------------------------------

@dataclass(frozen=True)
class IndependentMotion:
    """Prescribed independent coordinates: a function t -> (q_ind, dq_ind, ddq_ind), each
    array (..., 3) for [theta, psi, gamma] and t scalar or (N,)."""

    function: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]
    description: str = ""

    def __call__(self, t):
        return self.function(np.asarray(t, dtype=np.float64))


@dataclass(frozen=True)
class Motion:
    """A kinematically admissible motion sampled on a grid (q, dq, ddq all (N, 8))."""

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq_ind: np.ndarray
    info: dict = field(default_factory=dict)


def inverse_kinematics(model: Model, motion: IndependentMotion, t, q_dep0=(0, 0, 0, 0, 0), *,
                       reproject: bool = False, rtol: float = 1e-12, atol: float = 1e-12) -> Motion:
    """The thesis's inverse kinematics on the sample grid t.

    Integrates dq_dep = -D_dep^-1 D_ind dq_ind(t) with DOP853 at tight tolerance (the thesis:
    ode23s at MATLAB's default 1e-3). With ``reproject=True`` beta is not integrated but solved
    from [rD]_z = 0 at every evaluation, so the holonomic constraint holds to round-off.
    The start is made consistent on any model: beta(t0) is solved from [rD]_z = 0 starting at
    the given q_dep0's beta (reported in ``info["initial_correction"]``, ``["beta_correction"]``).
    """
    t = np.asarray(t, dtype=np.float64)
    if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0):
        raise ValueError("t must be a strictly increasing 1-D grid of at least 2 samples")
    q_dep0 = np.asarray(q_dep0, dtype=np.float64)
    if q_dep0.shape != (5,):
        raise ValueError(f"q_dep0 must be [xc, yc, phi, beta, eps] (5,); got shape {q_dep0.shape}")

    def assemble(ti, y):
        qi, dqi, _ = motion(ti)
        q = np.empty(N_Q)
        q[IND] = qi
        q[DEP] = y
        if reproject:
            q, _ = solve_beta(model, q)
        return q, dqi

    def rhs(ti, y):
        q, dqi = assemble(ti, y)
        return dependent_rates(model, q, dqi)[DEP]

    # A consistent start on any model: beta solved from [rD]_z = 0 starting at the given beta
    # (q_dep0 = 0 is consistent for the thesis geometry only; the benchmark's upright pitch is
    # -pi/10), as forward runs do; the correction is reported in info.
    q_start = np.empty(N_Q)
    q_start[IND] = motion(t[0])[0]
    q_start[DEP] = q_dep0
    height0 = float(model.constraint_residual(q_start, np.zeros(N_Q))[0])
    q_fixed, iterations = solve_beta(model, q_start)
    beta_correction = float(q_fixed[BETA] - q_start[BETA])
    height1 = float(model.constraint_residual(q_fixed, np.zeros(N_Q))[0])
    q_dep0 = q_fixed[DEP]
    t0 = time.perf_counter()
    sol = solve_ivp(rhs, (t[0], t[-1]), q_dep0, method="DOP853", t_eval=t, rtol=rtol, atol=atol)
    if sol.status != 0:
        raise ConstraintSolveError(f"inverse kinematics integration failed: {sol.message}")
    q_ind, dq_ind, ddq_ind = motion(t)
    q = np.empty((t.size, N_Q))
    q[:, IND] = q_ind
    q[:, DEP] = sol.y.T
    if reproject:
        for k in range(t.size):
            q[k], _ = solve_beta(model, q[k])
    dq = np.array([dependent_rates(model, q[k], dq_ind[k]) for k in range(t.size)])
    return Motion(t, q, dq, np.asarray(ddq_ind, dtype=np.float64),
                  {"rtol": rtol, "atol": atol, "reproject": reproject, "nfev": int(sol.nfev),
                   "wall_seconds": time.perf_counter() - t0, "beta_correction": beta_correction,
                   "initial_correction": (f"beta corrected by {beta_correction:+.6e} rad in "
                                          f"{iterations} Newton iteration(s); front contact height "
                                          f"{height0:+.3e} m -> {height1:+.1e} m")})


@dataclass(frozen=True)
class InverseDynamics:
    """Rider torques and multipliers along a motion (thesis: Dinamica_inversa)."""

    motion: Motion
    ddq: np.ndarray       # (N, 8)
    T: np.ndarray         # (N, 3): Mdir, Mped, Mvue (N m)
    lam: np.ndarray       # (N, 5)
    status: np.ndarray    # (N,) 0 ok


def inverse_dynamics(model: Model, motion: Motion) -> InverseDynamics:
    """Solve the 13x13 system of the thesis at every sample of an admissible motion."""
    ddq, T, lam, status = model.inverse_dynamics_step(motion.q, motion.dq, motion.ddq_ind)
    bad = np.flatnonzero(status)
    if bad.size:
        raise ConstraintSolveError(f"the 13x13 inverse-dynamics system is singular at t = "
                                   f"{motion.t[bad[0]]:.4f} s ({bad.size} sample(s))")
    return InverseDynamics(motion, ddq, T, lam, status)


# -- forward dynamics ------------------------------------------------------------------

@dataclass(frozen=True)
class Trajectory:
    """A forward run on the output grid; ``status`` is 'completed', 'fell' or 'failed'.

    When the run ends early, the grid stops at the last sample reached and the final row is
    the event itself (the fall, or the last accepted step before a failure). No NaNs.

    ``diagnostics`` holds an engine's own per-sample quantities on the same grid, each an (N,)
    array (e.g. a soft-contact engine's slip speeds and penetrations; empty for exact
    rolling, whose residuals are ``C``).
    """

    t: np.ndarray          # (N,)
    q: np.ndarray          # (N, 8)
    dq: np.ndarray         # (N, 8)
    ddq: np.ndarray        # (N, 8), from the same constraint handling as the run
    C: np.ndarray          # (N, 5) constraint residuals
    T: np.ndarray          # (N, 3) applied rider torques
    status: str
    message: str
    t_end: float
    settings: dict = field(default_factory=dict)   # deterministic: method, tolerances, ...
    timing: dict = field(default_factory=dict)     # volatile: wall time, evaluations
    diagnostics: dict = field(default_factory=dict)  # name -> (N,) array on the output grid


class _RhsFailure(Exception):
    def __init__(self, t, status):
        super().__init__(t, status)
        self.t, self.status = t, status


class _NonFiniteStart(Exception):
    """The start, once projected, is not finite: a failed run (DOP853 refuses such a start)."""


TorqueInput = Callable[[float], np.ndarray]


def _torque_function(torques) -> TorqueInput:
    if callable(torques):
        return torques
    T = np.asarray(torques, dtype=np.float64)
    if T.shape != (3,) or not np.all(np.isfinite(T)):
        raise ValueError(f"torques must be [Mdir, Mped, Mvue] (3 finite numbers) or a function of t; "
                         f"got {torques!r}")
    return lambda t: T


def project_state(model: Model, q, dq) -> tuple[np.ndarray, np.ndarray]:
    """Onto the constraint manifold: beta from [rD]_z = 0, then dq onto D dq = 0 in the
    kinetic-energy metric (dq - M^-1 D^T (D M^-1 D^T)^-1 D dq, the smallest change of
    kinetic energy)."""
    q, _ = solve_beta(model, q)
    M = model.mass_matrix(q)
    D = model.constraint_jacobian(q)
    MinvDt = np.linalg.solve(M, D.T)
    dq = dq - MinvDt @ np.linalg.solve(D @ MinvDt, D @ dq)
    return q, dq


def simulate(model: Model, q0, dq0, t_eval, torques=(0.0, 0.0, 0.0), *,
             constraints: str = "baumgarte", baumgarte=THESIS_BAUMGARTE, rtol: float = 1e-10,
             atol: float = 1e-12, fall_limit: float = DEFAULT_FALL_LIMIT,
             progress: Callable[[float], None] | None = None) -> Trajectory:
    """Forward dynamics from (q0, dq0) on the grid t_eval (DOP853, dense output).

    ``constraints``: 'baumgarte' (thesis, D ddq = -dD dq - 2 a1 D dq - a2^2 C), 'projection'
    (exact accelerations, state projected onto the constraints after every step) or 'none'
    (exact accelerations; the drift is left visible). The initial state is used as given:
    project it first with `consistent_state` if needed.
    """
    if constraints not in CONSTRAINT_HANDLING:
        raise ValueError(f"constraints must be one of {CONSTRAINT_HANDLING}; got {constraints!r}")
    t_eval = np.asarray(t_eval, dtype=np.float64)
    if t_eval.ndim != 1 or t_eval.size < 2 or np.any(np.diff(t_eval) <= 0):
        raise ValueError("t_eval must be a strictly increasing 1-D grid of at least 2 samples")
    fall_limit = checked_fall_limit(fall_limit)
    torque = _torque_function(torques)
    a12 = tuple(float(a) for a in baumgarte) if constraints == "baumgarte" else (0.0, 0.0)
    y0 = np.concatenate([np.asarray(q0, dtype=np.float64).reshape(N_Q),
                         np.asarray(dq0, dtype=np.float64).reshape(N_Q)])
    if not np.all(np.isfinite(y0)):
        raise ValueError("initial state must be finite (no NaN or inf in q0, dq0)")
    nfev = [0]

    def rhs(t, y):
        nfev[0] += 1
        res = model.forward(y[:N_Q], y[N_Q:], torque(t), a12)
        if res.status[0]:
            raise _RhsFailure(t, int(res.status[0]))
        return np.concatenate([y[N_Q:], res.ddq])

    out_t: list[float] = []
    out_y: list[np.ndarray] = []
    status, message = "completed", "reached the end of the grid"
    t0 = time.perf_counter()
    i = 0
    try:
        if constraints == "projection":
            q, dq = project_state(model, y0[:N_Q], y0[N_Q:])
            y0 = np.concatenate([q, dq])
            if not np.all(np.isfinite(y0)):     # DOP853 would refuse it with a ValueError
                raise _NonFiniteStart("the projected initial state is not finite")
        # Baumgarte makes the velocity rows decay at 2 a1 + a2^2 (120/s for the thesis's 10, 10):
        # near an equilibrium the error estimate vanishes and DOP853 would step far outside its
        # stability region (|h lambda| <~ 6), amplifying round-off on the dense output; bound h.
        rate = 2 * a12[0] + a12[1] ** 2
        max_step = 3.0 / rate if rate > 0 else np.inf
        solver = DOP853(rhs, t_eval[0], y0, t_eval[-1], rtol=rtol, atol=atol, max_step=max_step)
        out_t.append(t_eval[0])
        out_y.append(y0.copy())
        i = 1
        if abs(y0[THETA]) >= fall_limit:
            status, message = "fell", f"|theta| = {abs(y0[THETA]):.3f} rad >= fall limit at the start"
        while status == "completed" and solver.status == "running":
            msg = solver.step()
            if solver.status == "failed":
                status, message = "failed", f"integrator failed at t = {solver.t:.6f} s: {msg}"
                break
            sol = solver.dense_output()
            t_new = solver.t
            t_stop = t_new
            if abs(solver.y[THETA]) >= fall_limit:
                sign = np.sign(solver.y[THETA])
                t_stop = brentq(lambda s: sign * sol(s)[THETA] - fall_limit, solver.t_old, t_new,
                                xtol=1e-14, rtol=4 * np.finfo(float).eps)
                status, message = "fell", (f"|theta| reached the fall limit {fall_limit:.4f} rad "
                                           f"at t = {t_stop:.6f} s")
            while i < t_eval.size and t_eval[i] <= t_stop:
                y = sol(t_eval[i])
                if constraints == "projection":  # samples on the manifold too, not only step ends
                    y = np.concatenate(project_state(model, y[:N_Q], y[N_Q:]))
                out_t.append(t_eval[i])
                out_y.append(y)
                i += 1
            if status == "fell" and out_t[-1] < t_stop:
                out_t.append(t_stop)
                out_y.append(sol(t_stop))
            if constraints == "projection" and status == "completed":
                q, dq = project_state(model, solver.y[:N_Q], solver.y[N_Q:])
                solver.y = np.concatenate([q, dq])
                solver.f = rhs(t_new, solver.y)
            if progress is not None:
                progress(t_new)
    except _RhsFailure as exc:
        status = "failed"
        reason = {1: "singular constraint/mass system", 2: "non-finite state"}.get(exc.status, "?")
        message = f"right-hand side failed at t = {exc.t:.6f} s: {reason}"
    except _NonFiniteStart as exc:
        status, message = "failed", str(exc)
    except (ArithmeticError, np.linalg.LinAlgError) as exc:  # ConstraintSolveError; numpy's
        status, message = "failed", f"constraint projection failed: {exc}"  # solves (ValueError)
    t_arr = np.asarray(out_t)
    Y = np.asarray(out_y).reshape(-1, 2 * N_Q)
    good = np.all(np.isfinite(Y), axis=1)
    if not np.all(good):  # never hand NaNs to the user: cut at the first non-finite sample
        k = int(np.argmin(good))
        t_arr, Y = t_arr[:k], Y[:k]
        status, message = "failed", f"state became non-finite after t = {t_arr[-1] if k else t_eval[0]:.6f} s"
    q, dq = Y[:, :N_Q], Y[:, N_Q:]
    T = np.array([torque(tk) for tk in t_arr]).reshape(-1, 3)
    fwd = model.forward(q, dq, T, a12)
    ddq = fwd.ddq
    ok = fwd.status == 0
    if not np.all(ok):
        k = int(np.argmin(ok))
        t_arr, q, dq, ddq, T = t_arr[:k], q[:k], dq[:k], ddq[:k], T[:k]
        status, message = "failed", f"singular system at t = {t_arr[-1] if k else t_eval[0]:.6f} s"
    C = model.constraint_residual(q, dq).reshape(-1, N_C)
    return Trajectory(
        t=t_arr, q=q, dq=dq, ddq=ddq, C=C, T=T, status=status, message=message,
        t_end=float(t_arr[-1]) if t_arr.size else float(t_eval[0]),
        settings={"integrator": "DOP853", "rtol": rtol, "atol": atol, "constraints": constraints,
                  "baumgarte": list(a12) if constraints == "baumgarte" else None,
                  "fall_limit": fall_limit},
        timing={"wall_seconds": time.perf_counter() - t0, "nfev": nfev[0]},
    )
