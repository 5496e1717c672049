"""The roll/steer eigenvalues of any engine about upright straight running, from its own
constraints and constrained accelerations (the ``eigenvalues`` capability's generic arithmetic,
as `engines.stepping` is for an engine's own time loop).

    lam = eigenvalues_by_differences(engine, speeds)        # (n, 4) complex, 1/s
    weave, capsize = critical_speeds(lambda v: engine.eigenvalues(v), (0.0, 10.0))

The state is the thesis's [theta, gamma, d_theta, d_gamma] (roll, steer and their rates) with
the rear wheel rolling at ``d_psi = v / R_rear`` (the rear contact moving forward at v). For
each perturbed state the frame pitch beta is solved from the engine's own front-contact
height (Newton on row 0 of its ``constraint_residual``, slope from its
``constraint_jacobian``) and the dependent rates [xc, yc, phi, beta, eps] from its constraint
Jacobian, ``dq_dep = -D_dep^-1 D_ind dq_ind``; so the linearization uses the engine's own
contact (e.g. a toroidal tyre's) and nothing of the reference's. The state matrix A (4x4) is
central differences of ``d/dt [theta, gamma, d_theta, d_gamma] = [d_theta, d_gamma,
dd_theta, dd_gamma]`` (``forward_acceleration``, zero torques), its eigenvalues sorted as
`reference_model.linearize.sort_eigenvalues`.

Accuracy: central differences with step ``h`` have a truncation error ``h^2/6 |f'''|`` in each
entry of A (f the rates above) and a round-off error of the accelerations' rounding over
``2 h``. About the upright steady motion f is itself O(h) (an equilibrium: gravity's and the
gyroscopic torques vanish there), so its rounding is relative to O(h) terms and the round-off
stays near eps |A|. Measured on the benchmark bicycle against the reference's complex-step
linearization, 0 to 10 m/s, on the Kane, SymBRiM, Pinocchio, Drake and DART engines' terms:
the largest eigenvalue error is 4.3e-12 /s at h = 1e-6 and 4.3e-10 at 1e-5 (exactly h^2: the
truncation), 4e-14 to 6.4e-14 at h = 1e-7 and still 2.5e-14 at 1e-9 (the round-off floor). So
the default ``DIFFERENCE_STEP`` = 1e-7 rad (rad/s) sits where the truncation (~4e-14) meets
that floor: ~1e-13 /s against eigenvalues of up to ~16 /s, 1e-14 relative. A simple eigenvalue
moves by about the entries' error (these 4x4 matrices are well conditioned); only within
~1e-12 m/s of a speed where two eigenvalues coalesce (the weave pair forming, ~0.7 m/s on the
benchmark) would the square-root growth of that error be visible.

All perturbed states of all speeds go to the engine in one batch per call: Newton on the five
distinct configurations (`upright_configurations`, speed-independent: `DifferenceEigenvalues`
solves them once per engine), then one ``forward_acceleration`` call on 8 n states. An engine
opts in by inheriting `DifferenceEigenvalues` and declaring ``eigenvalues``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from reference_model.linearize import LinearizationError, sort_eigenvalues
from reference_model.names import COORDINATES

__all__ = ["DIFFERENCE_STEP", "DifferenceEigenvalues", "Upright", "critical_speeds",
           "eigenvalues_by_differences", "upright_configurations"]

#: the central differences' step (rad for theta, gamma; rad/s for their rates): module docstring
DIFFERENCE_STEP = 1e-7
_THETA, _PSI, _BETA, _GAMMA = (COORDINATES.index(n) for n in ("theta", "psi", "beta", "gamma"))
_IND = np.array([_THETA, _PSI, _GAMMA])
_DEP = np.array([COORDINATES.index(n) for n in ("xc", "yc", "phi", "beta", "eps")])
_NEWTON_TOL, _NEWTON_MAX = 1e-15, 50     # m of front-contact height; iterations


def _speeds(speeds) -> np.ndarray:
    v = np.atleast_1d(np.asarray(speeds, dtype=float))
    if v.ndim != 1 or not np.all(np.isfinite(v)):
        raise ValueError(f"speeds must be a finite speed or a 1-D array of finite speeds (m/s); "
                         f"got {speeds!r}")
    return v


@dataclass(frozen=True)
class Upright:
    """The five configurations the differences need (upright, then theta +-h, gamma +-h, each
    with beta on the engine's front contact), ``q`` (5, 8), and the engine's constraint
    Jacobian at each, ``D`` (5, 5, 8): independent of the speed, so solved once per engine."""

    q: np.ndarray
    D: np.ndarray
    h: float


def upright_configurations(engine, h: float = DIFFERENCE_STEP) -> Upright:
    """`Upright` of ``engine``'s bicycle: Newton on row 0 of its ``constraint_residual`` (the
    front contact's height) for beta, slope from its ``constraint_jacobian``."""
    params = engine.model.params
    if params.cv != 0.0:
        raise LinearizationError(
            f"model {engine.model.name!r}: cv = {params.cv!r} kg/m: with drag, upright straight "
            "running is not a steady motion; fix: linearize a copy with cv = 0")
    q = np.zeros((5, 8))
    q[1, _THETA], q[2, _THETA], q[3, _GAMMA], q[4, _GAMMA] = h, -h, h, -h
    zero = np.zeros_like(q)
    for _ in range(_NEWTON_MAX):
        r = np.asarray(engine.constraint_residual(q, zero))[:, 0]
        if np.all(np.abs(r) < _NEWTON_TOL):
            return Upright(q, np.asarray(engine.constraint_jacobian(q)), float(h))
        slope = np.asarray(engine.constraint_jacobian(q))[:, 0, _BETA]
        q[:, _BETA] -= r / slope
    raise LinearizationError(
        f"engine {engine.name!r}: Newton on the front contact's height for the frame pitch beta "
        f"did not converge in {_NEWTON_MAX} iterations (last residual {np.max(np.abs(r)):.1e} m); "
        "check the model's geometry")


def eigenvalues_by_differences(engine, speeds, h: float = DIFFERENCE_STEP,
                               upright: Upright | None = None) -> np.ndarray:
    """(n, 4) complex: the roll/steer eigenvalues (1/s) of ``engine``'s bicycle about upright
    straight running at each forward speed in ``speeds`` (m/s), sorted as
    `reference_model.linearize.sort_eigenvalues` (module docstring: the method, its accuracy).
    Needs ``constraint_residual`` (the reference solvers' duck-typed method),
    ``constraint_jacobian`` and ``forward_acceleration``; ``upright``: the engine's
    `upright_configurations` at ``h`` if already solved. A model with drag (cv > 0) has no
    steady upright motion and raises `LinearizationError`."""
    v = _speeds(speeds)
    up = upright if upright is not None and upright.h == h else upright_configurations(engine, h)
    # the 8 perturbations of x = [theta, gamma, d_theta, d_gamma]: (+h, -h) on each in turn;
    # the configuration each uses and its roll and steer rates
    config = np.array([1, 2, 3, 4, 0, 0, 0, 0])
    rates = np.zeros((8, 2))
    rates[4, 0], rates[5, 0], rates[6, 1], rates[7, 1] = h, -h, h, -h
    n = v.size
    q = np.repeat(up.q[config][None], n, axis=0).reshape(-1, 8)          # (8 n, 8)
    ind = np.zeros((n, 8, 3))
    ind[:, :, 0], ind[:, :, 2] = rates[None, :, 0], rates[None, :, 1]
    ind[:, :, 1] = (v / engine.model.params.R_rear)[:, None]
    ind = ind.reshape(-1, 3)
    Dk = np.repeat(up.D[config][None], n, axis=0).reshape(-1, 5, 8)
    dq = np.zeros((8 * n, 8))
    dq[:, _IND] = ind
    dq[:, _DEP] = -np.linalg.solve(Dk[:, :, _DEP], (Dk[:, :, _IND] @ ind[..., None]))[..., 0]
    ddq = np.asarray(engine.forward_acceleration(q, dq)).reshape(n, 8, 8)
    f = np.concatenate([rates[None].repeat(n, axis=0), ddq[:, :, [_THETA, _GAMMA]]], axis=2)
    A = (f[:, 0::2] - f[:, 1::2]).transpose(0, 2, 1) / (2.0 * h)         # (n, 4, 4): d f_i/d x_j
    return sort_eigenvalues(np.linalg.eigvals(A))


class DifferenceEigenvalues:
    """The ``eigenvalues`` capability by `eigenvalues_by_differences`, for an engine class to
    inherit (before `engines.base.Engine`) and declare. The upright configurations depend on
    the engine's model only, so they are solved on the first call and kept on the instance
    (a root search calls it a dozen times: one batched acceleration call each, not ten)."""

    def eigenvalues(self, speeds):
        """Roll/steer eigenvalues about upright straight running, (n, 4): central differences
        of this engine's own accelerations on its own constraints (`engines.linear`)."""
        up = self.__dict__.get("_upright")
        if up is None:
            up = self.__dict__["_upright"] = upright_configurations(self)
        return eigenvalues_by_differences(self, speeds, upright=up)


def critical_speeds(eigenvalues: Callable[[np.ndarray], np.ndarray], speeds: tuple[float, float],
                    step: float = 0.5, xtol: float = 1e-12,
                    known: tuple[np.ndarray, np.ndarray] | None = None
                    ) -> tuple[float | None, float | None]:
    """(weave speed, capsize speed) in m/s within ``speeds`` of a bicycle whose eigenvalues at
    an array of speeds are ``eigenvalues(v)`` ((n, 4), sorted as ``sort_eigenvalues``); None
    where there is none. The definitions are `reference_model.linearize`'s: the weave speed is
    where the first complex pair's real part crosses from + to -; the capsize speed, above it,
    where a real eigenvalue crosses zero, i.e. where the product of the four eigenvalues
    (det A = det K / det M) changes sign. A grid brackets each (``known``: (speeds, their
    eigenvalues) already computed, else a grid of ``step`` over ``speeds``; 0.5 m/s keeps two
    crossings of one mode apart on the bicycles here, and the capsize search starts at the
    weave speed itself, so a capsize just above it is not skipped), then brentq refines it to
    ``xtol`` on the eigenvalues themselves: about seven more calls per speed."""
    from scipy.optimize import brentq

    lo, hi = float(speeds[0]), float(speeds[1])
    if known is None:
        grid = np.linspace(lo, hi, max(int(np.ceil((hi - lo) / step)), 1) + 1)
        lam = np.asarray(eigenvalues(grid))
    else:
        grid, lam = np.asarray(known[0], dtype=float), np.asarray(known[1])
        keep = (grid >= lo) & (grid <= hi)
        grid, lam = grid[keep], lam[keep]

    def weave_re(s: float) -> float:
        one = np.asarray(eigenvalues(np.array([s])))[0]
        return float(one[0].real) if one[0].imag != 0 else float("nan")

    def det(s: float) -> float:
        return float(np.prod(np.asarray(eigenvalues(np.array([s])))[0]).real)

    re = np.where(lam[:, 0].imag != 0, lam[:, 0].real, np.nan)
    hits = np.flatnonzero((re[:-1] > 0) & (re[1:] <= 0))
    weave = None
    if hits.size:
        i = int(hits[0])
        weave = float(grid[i + 1]) if re[i + 1] == 0 else \
            float(brentq(weave_re, grid[i], grid[i + 1], xtol=xtol))
    d = np.prod(lam, axis=1).real
    if weave is not None:
        above = grid > weave
        grid, d = np.r_[weave, grid[above]], np.r_[det(weave), d[above]]
    # a sign change between consecutive non-zero samples; samples exactly zero between them
    # are the crossing itself (np.sign(0) = 0 would hide it from a product of neighbours)
    sign = np.sign(d)
    nonzero = np.flatnonzero(sign != 0)
    change = np.flatnonzero(sign[nonzero[:-1]] * sign[nonzero[1:]] < 0)
    capsize = None
    if change.size:
        a, b = int(nonzero[change[0]]), int(nonzero[change[0] + 1])
        capsize = (float(grid[a + 1]) if b > a + 1 else
                   float(brentq(det, grid[a], grid[b], xtol=xtol)))
    return weave, capsize
