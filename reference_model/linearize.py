"""Linearized roll and steer dynamics about upright, straight running at forward speed v.

The steady motion: theta = gamma = 0 (upright, steer straight), the rear wheel spinning at
``d_psi = v / R_rear`` so the rear contact moves forward at v, the frame pitch beta solved from
the front contact ``[rD]_z = 0``. It is a steady motion only without drag (``cv = 0``).

**Reduction.** Independent coordinates are the thesis's ``q_ind = [theta, psi, gamma]`` (roll,
rear wheel angle, steer). For a prescribed independent motion (q_ind, dq_ind, ddq_ind), the
holonomic constraint gives beta (Newton), the nonholonomic ones the dependent rates
``dq_dep = -D_dep^-1 D_ind dq_ind`` and accelerations
``ddq_dep = -D_dep^-1 (D_ind ddq_ind + dD dq)``, and the reduced inverse dynamics is the
generalized force conjugate to each independent coordinate (virtual power with the dependent
rates eliminated, i.e. the multipliers eliminated)::

    r = M ddq - Qv - Qgrav            (8,)
    F = r_ind - D_ind^T D_dep^-T r_dep    (3,): [F_theta, F_psi, F_gamma]

This is what the benchmark's roll torque T_phi and steer torque T_delta are: generalized forces
conjugate to roll and steer (an external roll torque on the rear frame, and an action-reaction
steer torque between the frames). It is *not* the model's own rider-torque map S: its Mvue acts
about the frame's x axis (pitched by beta, i.e. by the rake, for the benchmark) and its Mdir is
single-sided (no reaction on the frame), so (Mvue, Mdir) differ from (T_phi, T_delta) by a
configuration-dependent map.

**Exact derivatives.** F is evaluated by numpy code generated from the derivation's own
expressions (``derivation.derive``: M, Qv, Qgrav over its placeholders, D, dD dq, [rD]_z), which
runs on complex numbers, so every derivative is a complex step, ``dF/dx = Im F(x + i h) / h`` with
h = 1e-20: no subtraction, exact to rounding (the Newton solve for beta runs in complex
arithmetic too, so beta's dependence on roll and steer is differentiated as well). F is
quadratic in the rates and linear in the accelerations, so with ``dq_ind = (0, v/R_rear, 0)``::

    dF/d ddq = M_r,   dF/d dq = v C1,   dF/dq = g K0 + v^2 K2

exactly; one evaluation at v = 0 gives M and g K0, one at v = 1 with g = 0 gives C1 and K2.
The roll/steer block is decoupled from psi (left-right symmetry): the psi rows and columns are
zero to rounding (``Linearization.coupling`` reports the largest such entry).

**Cyclic and constraint zeros.** The full linearization in (q, dq_ind) has 11 states; xc, yc,
phi, psi, eps are cyclic (nothing depends on them: zero eigenvalues), beta and the dependent
rates are fixed by the constraints, and the forward speed decouples (another zero eigenvalue).
They are removed by construction: only [theta, gamma, d_theta, d_gamma] are kept, which leaves
exactly the four non-trivial eigenvalues.

**Benchmark convention** (Meijaard et al. 2007: z down, y right): roll phi = theta (both lean
to the right), steer delta = -gamma (the benchmark's steering axis points down, the frame's z3
up). ``Linearization.M/C1/K0/K2`` are in this convention, over ``[phi, delta]``, so
``M q'' + v C1 q' + (g K0 + v^2 K2) q = [T_phi, T_delta]``.

The generated numpy code is cached in ``$BICYCLE_XVAL_CACHE`` (next to the generated C), keyed
by the code generator's key (derivation sources, sympy, contact) and this file; its first line
stamps the contact, the key and the SHA-256 of the rest, checked before the file is run (a cut
file, or another contact's file copied over it, is regenerated). Per parameter set, the
speed-independent matrices are computed once and kept in memory.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Protocol

import numpy as np
from scipy.optimize import brentq

from .equations import codegen
from .names import COORDINATES
from .parameters.schema import PARAMETER_NAMES
from .parameters.values import Parameters

__all__ = [
    "CriticalSpeedError", "Linearization", "LinearizationError", "ParametrizedModel",
    "capsize_speed", "eigenvalues", "linearize", "sort_eigenvalues", "weave_speed",
]


class ParametrizedModel(Protocol):
    """What the linearization needs of a model: its validated parameters
    (`reference_model.model.Model` is one). Typed so, this module does not import the model's,
    which imports this one for ``Model.eigenvalues``."""

    params: Parameters

_IND = tuple(COORDINATES.index(n) for n in ("theta", "psi", "gamma"))
_DEP = tuple(COORDINATES.index(n) for n in ("xc", "yc", "phi", "beta", "eps"))
_BETA = COORDINATES.index("beta")
_G = PARAMETER_NAMES.index("g")
_ROLL_STEER = (0, 2)                 # theta, gamma within q_ind
_TO_BENCHMARK = np.diag([1.0, -1.0])  # [phi, delta] = P [theta, gamma]
_H = 1e-20                            # complex step
_NEWTON_TOL = 1e-14                   # rad, on the real part of the Newton step for beta
_NEWTON_MAX = 50


class LinearizationError(ValueError):
    """The model has no steady upright motion to linearize about (drag, no beta solution)."""


class CriticalSpeedError(ValueError):
    """No weave or capsize speed in the searched range."""


# --------------------------------------------------------------------------------------------
# Generated complex-capable evaluation of the derivation
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Evaluator:
    """numpy functions of (q (8, k), dq (8, k), p (30,)) that accept complex arrays.

    ``front_height``: ([rD]_z, d[rD]_z/dbeta), (2, k); ``constraints``: D (40 rows, row-major
    5x8) then dD dq (5), (45, k); ``dynamics``: M (64 rows, row-major), Qv (8), Qgrav (8), (80, k).
    """

    front_height: Callable[..., np.ndarray]
    constraints: Callable[..., np.ndarray]
    dynamics: Callable[..., np.ndarray]
    path: Path


def _function_source(der, name: str, outputs: list) -> str:
    """One numpy function: placeholders (first CSE stage), then the outputs (second stage)."""
    import sympy as sp
    from sympy.printing.numpy import NumPyPrinter

    printer = NumPyPrinter({"fully_qualified_modules": True})
    sy = der.symbols
    exprs = [sp.sympify(e) for e in outputs]
    lines = [f"def {name}(q, dq, p):",
             "    (" + ", ".join(str(s) for s in sy.q) + ",) = q",
             "    (" + ", ".join(str(s) for s in sy.dq) + ",) = dq",
             "    (" + ", ".join(str(s) for s in sy.p) + ",) = p"]
    used = set().union(*(e.free_symbols for e in exprs)) & set(der.placeholders)
    ph = sorted(used, key=lambda s: s.name)
    if ph:
        reps, red = sp.cse([der.placeholders[s] for s in ph], symbols=sp.numbered_symbols("_k"),
                           order="none")
        lines += [f"    {s} = {printer.doprint(e)}" for s, e in reps]
        lines += [f"    {s} = {printer.doprint(e)}" for s, e in zip(ph, red)]
    reps, red = sp.cse(exprs, symbols=sp.numbered_symbols("_t"), order="none")
    lines += [f"    {s} = {printer.doprint(e)}" for s, e in reps]
    lines.append(f"    _out = numpy.zeros(({len(exprs)},) + numpy.shape(q)[1:], dtype=complex)")
    lines += [f"    _out[{i}] = {printer.doprint(e)}" for i, e in enumerate(red) if e != 0]
    lines.append("    return _out")
    return "\n".join(lines) + "\n\n"


def _module_source(contact: str) -> str:
    der = codegen.derivation(contact)
    head = ("# Generated by reference_model/linearize.py from "
            f"reference_model/equations/derivation.py (contact {contact!r}).\n# Complex-capable numpy evaluation for complex-step "
            "derivatives. Never hand-edited.\nimport numpy\n\n")
    return head + "".join([
        _function_source(der, "front_height", [der.C[0], der.D[0, _BETA]]),
        _function_source(der, "constraints", list(der.D) + list(der.bias)),
        _function_source(der, "dynamics", list(der.M) + list(der.Qv) + list(der.Qgrav)),
    ])


def _cache_file(contact: str) -> Path:
    return codegen.cache_root() / f"linearize-{contact}-{_file_key(contact)}.py"


def _file_key(contact: str) -> str:
    h = hashlib.sha256(codegen.cache_key(contact, backend="numpy").encode())
    h.update(Path(__file__).read_bytes())
    return h.hexdigest()[:20]


def _stamp(contact: str, body: str) -> str:
    """First line of a cached evaluator: what it is for and the hash of the rest, checked before
    it is run (a cut file, or another contact model's file copied over it, is regenerated)."""
    digest = hashlib.sha256(body.encode("utf-8")).hexdigest()
    return f"# bicycle-xval linearize evaluator: contact={contact} key={_file_key(contact)} sha256={digest}\n"


def _verified_text(contact: str, path: Path) -> str | None:
    """The cached evaluator's source if its stamp matches this contact, key and content."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    head, sep, body = text.partition("\n")
    if not sep or head + "\n" != _stamp(contact, body):
        return None
    return body


def _load(text: str, path: Path) -> _Evaluator:
    namespace: dict = {}
    exec(compile(text, str(path), "exec"), namespace)
    return _Evaluator(namespace["front_height"], namespace["constraints"], namespace["dynamics"],
                      path)


@functools.lru_cache(maxsize=None)
def _evaluator(contact: str) -> _Evaluator:
    """The generated evaluator of one contact model: from the cache, or generated now (a few
    seconds: the derivation) and cached; a damaged or foreign cache file is regenerated."""
    path = _cache_file(contact)
    body = _verified_text(contact, path)
    if body is not None:
        try:
            return _load(body, path)
        except Exception:  # noqa: BLE001 - a verified file that still fails: regenerate it
            pass
    text = _module_source(contact)
    evaluator = _load(text, path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        codegen.clean_stale_temporaries(path.parent)
        fd, tmp = tempfile.mkstemp(prefix=codegen.temporary_prefix(path.stem), suffix=".py",
                                   dir=path.parent)
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(_stamp(contact, text) + text)
        os.replace(tmp, path)  # atomic: concurrent runs never read a half-written file
    except OSError as exc:
        raise codegen.CodegenError(
            f"cannot write the linearization evaluator to {path.parent} ({exc.strerror or exc}); "
            f"fix: set {codegen.CACHE_ENV} to a writable folder") from None
    return evaluator


# --------------------------------------------------------------------------------------------
# Reduced inverse dynamics (complex-capable, batched)
# --------------------------------------------------------------------------------------------


def _solve_beta(ev: _Evaluator, q: np.ndarray, p: np.ndarray, what: str) -> np.ndarray:
    """beta solving [rD]_z = 0 for each column of q (complex Newton, other coordinates fixed).

    Iterates until the real step is below 1e-14 rad, then once more so the imaginary (complex
    step) part has converged as well (it is settled one step after the real part).
    """
    beta = q[_BETA].copy()
    settled = False
    for _ in range(_NEWTON_MAX):
        q[_BETA] = beta
        height, slope = ev.front_height(q, np.zeros_like(q), p)
        if np.any(np.abs(slope.real) < 1e-12):
            raise LinearizationError(
                f"{what}: d[rD]_z/dbeta vanishes at beta = {beta.real.tolist()}: the front "
                "contact does not fix the frame pitch; check the geometry (R_front, xa, za, x5, z5)")
        step = height / slope
        beta = beta - step
        if settled:
            q[_BETA] = beta
            return beta
        settled = bool(np.all(np.abs(step.real) <= _NEWTON_TOL))
    raise LinearizationError(
        f"{what}: Newton on [rD]_z = 0 for the frame pitch beta did not converge in "
        f"{_NEWTON_MAX} iterations (last step {np.max(np.abs(step.real)):.2e} rad); check the "
        "geometry: the front wheel must be able to touch the ground")


def _reduced_forces(ev: _Evaluator, p: np.ndarray, x: np.ndarray, beta0: float) -> np.ndarray:
    """Reduced inverse dynamics F (k, 3) = [F_theta, F_psi, F_gamma] at independent motions x.

    ``x`` (k, 9): [theta, psi, gamma, d_theta, d_psi, d_gamma, dd_theta, dd_psi, dd_gamma]
    (complex allowed); the cyclic coordinates xc, yc, phi, eps are 0, beta is solved.
    """
    k = x.shape[0]
    q = np.zeros((8, k), dtype=complex)
    q[list(_IND)] = x[:, 0:3].T
    q[_BETA] = beta0
    _solve_beta(ev, q, p, "linearize")
    cons = ev.constraints(q, np.zeros_like(q), p)
    D = cons[:40].reshape(5, 8, k).transpose(2, 0, 1)                    # (k, 5, 8)
    Dd, Di = D[:, :, _DEP], D[:, :, _IND]
    dq = np.zeros((8, k), dtype=complex)
    dq[list(_IND)] = x[:, 3:6].T
    dq[list(_DEP)] = -np.linalg.solve(Dd, (Di @ x[:, 3:6, None]))[..., 0].T
    bias = ev.constraints(q, dq, p)[40:45].T                               # (k, 5)
    ddq = np.zeros((k, 8), dtype=complex)
    ddq[:, _IND] = x[:, 6:9]
    ddq[:, _DEP] = -np.linalg.solve(Dd, (Di @ x[:, 6:9, None]) + bias[..., None])[..., 0]
    dyn = ev.dynamics(q, dq, p)
    M = dyn[:64].reshape(8, 8, k).transpose(2, 0, 1)
    r = (M @ ddq[..., None])[..., 0] - dyn[64:72].T - dyn[72:80].T       # (k, 8)
    lam = np.linalg.solve(np.swapaxes(Dd, 1, 2), r[:, _DEP, None])        # (k, 5, 1)
    return r[:, _IND] - (np.swapaxes(Di, 1, 2) @ lam)[..., 0]


def _jacobian(ev: _Evaluator, p: np.ndarray, x0: np.ndarray, beta0: float) -> tuple[np.ndarray, np.ndarray]:
    """F(x0) and dF/dx (3, 9) by complex steps, all nine perturbations in one batch."""
    X = np.tile(x0.astype(complex), (10, 1))
    X[np.arange(1, 10), np.arange(9)] += 1j * _H
    F = _reduced_forces(ev, p, X, beta0)
    return F[0].real, (F[1:].imag / _H).T


# --------------------------------------------------------------------------------------------
# Speed-independent matrices (cached per parameter set)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Expansion:
    """dF/d(q_ind, dq_ind, ddq_ind) over [theta, psi, gamma], model signs: M, C1, K0, K2 (3x3)."""

    M: np.ndarray
    C1: np.ndarray
    K0: np.ndarray
    K2: np.ndarray
    beta0: float
    residual: float      # max |F| at the steady motion (v = 0 and v = 1): 0 for an equilibrium
    coupling: float      # max |entry| coupling psi with theta/gamma


def _read_only(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.flags.writeable = False
    return a


@functools.lru_cache(maxsize=64)
def _expansion(params: Parameters) -> _Expansion:
    if params.cv != 0.0:
        raise LinearizationError(
            f"model {params.name!r}: cv = {params.cv!r} kg/m: with drag, upright straight running "
            "at constant speed is not a steady motion of the unforced bicycle; fix: linearize a "
            "copy without drag, model.with_params(model.params.replace(cv=0.0))")
    ev = _evaluator(params.contact)
    p = params.vector()
    q = np.zeros((8, 1), dtype=complex)
    beta0 = float(_solve_beta(ev, q, p, f"model {params.name!r} upright")[0].real)
    x0 = np.zeros(9)
    F0, J0 = _jacobian(ev, p, x0, beta0)            # v = 0: M and g K0
    x1 = x0.copy()
    x1[4] = 1.0 / params.R_rear                      # v = 1 m/s
    p1 = p.copy()
    p1[_G] = 0.0                                     # no gravity: the velocity terms alone
    F1, J1 = _jacobian(ev, p1, x1, beta0)
    M = J0[:, 6:9]
    K0 = J0[:, 0:3] / params.g
    C1 = J1[:, 3:6]
    K2 = J1[:, 0:3]
    psi = [1]
    rs = list(_ROLL_STEER)
    coupling = max(float(np.max(np.abs(A[np.ix_(psi, rs)]))) for A in (M, C1, K0, K2))
    coupling = max(coupling, *(float(np.max(np.abs(A[np.ix_(rs, psi)]))) for A in (M, C1, K0, K2)))
    residual = float(max(np.max(np.abs(F0)), np.max(np.abs(F1))))
    return _Expansion(_read_only(M), _read_only(C1), _read_only(K0), _read_only(K2), beta0,
                      residual, coupling)


def _benchmark_block(A: np.ndarray) -> np.ndarray:
    """The [theta, gamma] block of a 3x3 matrix, in benchmark signs [phi, delta]."""
    return _read_only(_TO_BENCHMARK @ A[np.ix_(_ROLL_STEER, _ROLL_STEER)] @ _TO_BENCHMARK)


# --------------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Linearization:
    """Linear roll/steer dynamics at forward speed ``v`` (m/s) about upright straight running.

    ``A`` (4x4): d/dt [theta, gamma, d_theta, d_gamma] = A [...] (model signs: theta roll, to
    the right; gamma steer about the frame's z3, to the left). ``M, C1, K0, K2`` (2x2): the
    benchmark's matrices over [phi, delta] = [theta, -gamma] (benchmark signs), with
    ``M q'' + v C1 q' + (g K0 + v^2 K2) q = [T_phi, T_delta]`` (T: generalized forces conjugate
    to roll and steer, N m). ``beta0``: frame pitch at upright (rad); ``coupling``: largest entry
    coupling the rear-wheel angle psi with roll/steer (0 to rounding by symmetry); ``residual``:
    largest reduced force at the steady motion itself (0 to rounding).
    """

    v: float
    g: float
    A: np.ndarray
    M: np.ndarray
    C1: np.ndarray
    K0: np.ndarray
    K2: np.ndarray
    beta0: float
    coupling: float
    residual: float

    @property
    def C(self) -> np.ndarray:
        """v C1: the damping-like matrix at this speed (benchmark signs)."""
        return self.v * self.C1

    @property
    def K(self) -> np.ndarray:
        """g K0 + v^2 K2: the stiffness matrix at this speed (benchmark signs)."""
        return self.g * self.K0 + self.v ** 2 * self.K2

    @property
    def A_benchmark(self) -> np.ndarray:
        """A in benchmark signs, over [phi, delta, d_phi, d_delta]."""
        P = np.diag([1.0, -1.0, 1.0, -1.0])
        return P @ self.A @ P

    def eigenvalues(self) -> np.ndarray:
        """The four eigenvalues of A, sorted as :func:`sort_eigenvalues`."""
        return sort_eigenvalues(np.linalg.eigvals(self.A))


def _state_matrices(M: np.ndarray, C1: np.ndarray, K0: np.ndarray, K2: np.ndarray, g: float,
                    v: np.ndarray) -> np.ndarray:
    """A (n, 4, 4) for speeds v (n,) from 2x2 M, C1, K0, K2 (any consistent sign convention)."""
    v = np.asarray(v, dtype=np.float64).reshape(-1)
    Minv = np.linalg.inv(M)
    n = v.size
    A = np.zeros((n, 4, 4))
    A[:, 0, 2] = A[:, 1, 3] = 1.0
    A[:, 2:, :2] = -(Minv @ (g * K0))[None] - v[:, None, None] ** 2 * (Minv @ K2)[None]
    A[:, 2:, 2:] = -v[:, None, None] * (Minv @ C1)[None]
    return A


def _speeds(v, what: str = "v") -> np.ndarray:
    a = np.asarray(v, dtype=np.float64)
    if a.ndim > 1 or not np.all(np.isfinite(a)):
        raise ValueError(f"{what} must be a finite speed or a 1-D array of finite speeds (m/s); "
                         f"got {v!r}")
    return a


def linearize(model: ParametrizedModel, v: float) -> Linearization:
    """Linearize ``model`` about upright straight running at forward speed ``v`` (m/s).

    Raises :class:`LinearizationError` for a model with drag (no steady motion) or a geometry
    whose frame pitch cannot be solved.
    """
    vv = float(_speeds(v))
    e = _expansion(model.params)
    g = model.params.g
    M, C1, K0, K2 = (_benchmark_block(X) for X in (e.M, e.C1, e.K0, e.K2))
    rs = np.ix_(_ROLL_STEER, _ROLL_STEER)
    A = _state_matrices(e.M[rs], e.C1[rs], e.K0[rs], e.K2[rs], g, np.array([vv]))[0]
    A.flags.writeable = False
    return Linearization(vv, g, A, M, C1, K0, K2, e.beta0, e.coupling, e.residual)


def sort_eigenvalues(lam: np.ndarray) -> np.ndarray:
    """Sort eigenvalues along the last axis: complex pairs first (larger |imag| first, then
    larger real part; each pair +imag then -imag), then the real ones in decreasing order.

    For the benchmark above about 0.7 m/s this is Table 2's order: weave (re + im i, re - im i),
    capsize, castor; at v = 0 the four real roots in decreasing order. numpy's (LAPACK's)
    eigenvalues of a real matrix are exactly real or exact conjugate pairs, so "real" means
    imag == 0 exactly.
    """
    lam = np.asarray(lam, dtype=complex)
    keys = (-lam.imag, -lam.real, -np.abs(lam.imag), (lam.imag == 0).astype(float))  # last = first
    order = np.lexsort(keys, axis=-1)
    return np.take_along_axis(lam, order, axis=-1)


def eigenvalues(model: ParametrizedModel, v) -> np.ndarray:
    """The four non-trivial eigenvalues of the roll/steer linearization at speed(s) ``v``.

    ``v`` a scalar (returns (4,) complex) or a 1-D array (returns (n, 4)); order as
    :func:`sort_eigenvalues`. The cyclic and constraint zero eigenvalues are never formed (see
    the module docstring). One 4x4 eigenvalue problem per speed, batched.
    """
    vs = _speeds(v)
    e = _expansion(model.params)
    rs = np.ix_(_ROLL_STEER, _ROLL_STEER)
    A = _state_matrices(e.M[rs], e.C1[rs], e.K0[rs], e.K2[rs], model.params.g, vs)
    lam = sort_eigenvalues(np.linalg.eigvals(A))
    return lam[0] if vs.ndim == 0 else lam


def _weave_real(model: ParametrizedModel, v: float) -> float:
    """Real part of the weave eigenvalue (first complex pair), nan if all four are real."""
    lam = eigenvalues(model, v)
    return float(lam[0].real) if lam[0].imag != 0 else float("nan")


def _capsize_function(model: ParametrizedModel):
    """det(g K0 + v^2 K2) (roll/steer, model signs): zero exactly where an eigenvalue is 0."""
    e = _expansion(model.params)
    rs = np.ix_(_ROLL_STEER, _ROLL_STEER)
    gK0, K2 = model.params.g * e.K0[rs], e.K2[rs]
    return lambda v: float(np.linalg.det(gK0 + v * v * K2))


def _grid(speeds: tuple[float, float], step: float) -> np.ndarray:
    lo, hi = (float(s) for s in speeds)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 <= lo < hi):
        raise ValueError(f"speeds must be (low, high) with 0 <= low < high (m/s); got {speeds!r}")
    n = max(int(np.ceil((hi - lo) / step)), 1)
    return np.linspace(lo, hi, n + 1)


def weave_speed(model: ParametrizedModel, speeds: tuple[float, float] = (0.0, 20.0), *,
                step: float = 0.01) -> float:
    """The weave speed (m/s): where the weave pair's real part crosses from + to -.

    The weave pair is the complex pair of highest frequency (the benchmark has one pair).

    A grid of ``step`` over ``speeds`` brackets the first crossing; brentq (xtol 1e-14) then
    finds the root of the weave eigenvalue's real part on the exact linearization.
    Raises :class:`CriticalSpeedError` if there is none in the range.
    """
    grid = _grid(speeds, step)
    lam = eigenvalues(model, grid)
    re = np.where(lam[:, 0].imag != 0, lam[:, 0].real, np.nan)
    hits = np.flatnonzero((re[:-1] > 0) & (re[1:] <= 0))
    if hits.size == 0:
        raise CriticalSpeedError(
            f"model {model.params.name!r}: no weave speed in [{grid[0]:g}, {grid[-1]:g}] m/s (the "
            "oscillatory pair's real part does not change sign from + to -); widen the range")
    i = int(hits[0])
    if re[i + 1] == 0.0:
        return float(grid[i + 1])
    return float(brentq(lambda s: _weave_real(model, s), grid[i], grid[i + 1], xtol=1e-14,
                        rtol=4 * np.finfo(float).eps, maxiter=200))


def capsize_speed(model: ParametrizedModel, speeds: tuple[float, float] | None = None, *,
                  step: float = 0.01) -> float:
    """The capsize speed (m/s): above the weave speed, where the real capsize eigenvalue crosses
    zero (from stable to unstable).

    An eigenvalue is zero exactly where ``det(g K0 + v^2 K2) = 0`` (the constant coefficient of
    the characteristic polynomial), so brentq (xtol 1e-14) runs on that determinant, bracketed
    by its first sign change on a grid of ``step`` from the weave speed (or ``speeds[0]`` if
    there is no weave speed) to ``speeds[1]`` (default 20 m/s).
    """
    speeds = (0.0, 20.0) if speeds is None else speeds
    try:
        low = weave_speed(model, speeds, step=step)
    except CriticalSpeedError:
        low = float(speeds[0])
    grid = _grid((low, speeds[1]), step)
    det = _capsize_function(model)
    values = np.array([det(s) for s in grid])
    sign = np.sign(values)
    # a sign change between two samples, or a root exactly on a sample that the determinant
    # crosses (a zero that keeps its sign on both sides is no crossing)
    crossed = sign[:-1] * sign[1:] < 0
    crossed[:-1] |= (sign[1:-1] == 0) & (sign[:-2] * sign[2:] < 0)
    hits = np.flatnonzero(crossed)
    if hits.size == 0:
        raise CriticalSpeedError(
            f"model {model.params.name!r}: no capsize speed in [{grid[0]:g}, {grid[-1]:g}] m/s "
            "(no real eigenvalue crosses zero); widen the range")
    i = int(hits[0])
    if values[i + 1] == 0.0:
        return float(grid[i + 1])
    return float(brentq(det, grid[i], grid[i + 1], xtol=1e-14, rtol=4 * np.finfo(float).eps,
                        maxiter=200))
