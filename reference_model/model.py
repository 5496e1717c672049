"""The numeric thesis bicycle: mass matrix, force terms, constraints, exact accelerations.

Every function takes one state (``q`` of shape (8,)) or a batch (shape (N, 8)) and returns
the matching shape; the work is done by the generated C (see ``codegen``), one C loop per
batch. Sign conventions are the thesis's::

    M ddq + D^T lambda = Qv + Qgrav + Qaero + S T,      D ddq + dD dq = 0
"""

from __future__ import annotations

import ctypes
import functools
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .equations import codegen
from .names import BODY_NAMES, COORDINATES, POINT_NAMES, TORQUE_NAMES
from .parameters.loading import resolve_model
from .parameters.values import Parameters

INDEPENDENT = ("theta", "psi", "gamma")
DEPENDENT = ("xc", "yc", "phi", "beta", "eps")

def _index(names) -> np.ndarray:
    idx = np.array([COORDINATES.index(n) for n in names])
    idx.flags.writeable = False
    return idx


IND = _index(INDEPENDENT)   # positions of theta, psi, gamma in q
DEP = _index(DEPENDENT)     # positions of xc, yc, phi, beta, eps in q
CONSTRAINT_NAMES = ("rD_z", "vC_x", "vC_y", "vD_x", "vD_y")
N_Q, N_C = 8, 5

_STATUS = {1: "the linear system is singular (constraint Jacobian rank-deficient or M not positive "
              "definite): the state is at a kinematic singularity",
           2: "the state or the result is not finite (NaN or inf in the input?)"}

#: the default of `Model._eval`'s dq: the kernel does not read the rates
_NO_RATES = object()
#: the public method of each kernel that reads the rates (for the refusal's message)
_PUBLIC = {"qv": "Qv", "qaero": "Qaero", "dynamics": "generalized_forces",
           "mass_bias": "inverse_dynamics", "constraint_residual": "constraint_residual",
           "constraint_bias": "constraint_bias", "energy": "kinetic_energy"}


class ModelEvaluationError(ArithmeticError):
    """A state where the model cannot be evaluated (singular system, non-finite numbers)."""


_dp = ctypes.c_void_p
_long = ctypes.c_long
_dbl = ctypes.c_double


@functools.lru_cache(maxsize=None)
def _library(contact: str, gyroscopic: bool = True, backend: str | None = None) -> codegen.Library:
    """The loaded generated code of a variant (verified and loaded once per process)."""
    lib = codegen.build(contact, gyroscopic=gyroscopic, backend=backend)
    if lib.backend != "c":
        return lib
    for name in lib.functions:
        fn = getattr(lib.lib, f"bx_{name}_batch")
        fn.argtypes = [_long, _dp, _dp, _dp, _dp]
        fn.restype = None
    f = lib.lib.bx_forward_batch
    f.argtypes = [_long, _dp, _dp, _dp, _dp, _dbl, _dbl, _dp, _dp, _dp]
    f.restype = _long
    f = lib.lib.bx_inverse_dynamics_batch
    f.argtypes = [_long, _dp, _dp, _dp, _dp, _dp, _dp]
    f.restype = _long
    return lib


def _states(x, width: int, what: str) -> tuple[np.ndarray, bool]:
    """x as a C-contiguous float64 (N, width) array, and whether it was a single state."""
    a = np.ascontiguousarray(x, dtype=np.float64)
    if a.ndim == 1 and a.shape[0] == width:
        return a.reshape(1, width), True
    if a.ndim == 2 and a.shape[1] == width:
        return a, False
    raise ValueError(f"{what} must have shape ({width},) or (N, {width}); got shape {a.shape}")


def torque_array(torques, n: int, single: bool) -> np.ndarray:
    """Rider torques as a C-contiguous (n, 3) array: (3,) for every state, or one row per state.

    A scalar or any other shape is refused (a scalar used to be applied to all three)."""
    T = np.asarray(torques, dtype=np.float64)
    if T.shape == (3,):
        return np.ascontiguousarray(np.broadcast_to(T, (n, 3)))
    if T.ndim == 2 and T.shape == (n, 3) and not single:
        return np.ascontiguousarray(T)
    expected = "(3,)" if single else f"(3,) or ({n}, 3), one row per state"
    raise ValueError(f"torques must have shape {expected} [Mdir, Mped, Mvue] in N m; got shape "
                     f"{T.shape}" + (" (a scalar is not applied to all three: write (0, T, 0))"
                                     if T.ndim == 0 else ""))


@dataclass(frozen=True)
class ForwardResult:
    """Constrained accelerations, multipliers and per-state status (0 = ok)."""

    ddq: np.ndarray
    lam: np.ndarray
    status: np.ndarray


class Model:
    """The thesis bicycle with one parameter set and one front-contact model.

    Attributes: ``params`` (validated `Parameters`), ``contact`` ('thesis' or 'disc'),
    ``name``, ``warnings`` (``params.warnings``: what a report using the model must say, e.g.
    an allowed triangle-inequality violation), ``coordinates`` (the thesis order), ``independent`` / ``dependent``
    coordinate names, ``library`` (the compiled code and its cache folder), ``gyroscopic``
    (True, the thesis model; ``Model(params, gyroscopic=False)`` is a deliberately broken
    variant without the gyroscopic terms in Qv, for the fault-injection suite), ``backend``
    ('c', or 'numpy' when no C compiler works or ``backend="numpy"`` is asked for: the same
    generated code as numpy, equal to round-off, slower; see `codegen`).
    """

    coordinates = COORDINATES
    independent = INDEPENDENT
    dependent = DEPENDENT
    constraint_names = CONSTRAINT_NAMES
    torque_names = TORQUE_NAMES
    body_names = BODY_NAMES

    def __init__(self, params: Parameters, *, gyroscopic: bool = True, backend: str | None = None):
        self.params = params
        self.contact = params.contact
        self.name = params.name
        self.warnings = params.warnings     # e.g. an allowed triangle-inequality violation
        self.gyroscopic = bool(gyroscopic)
        self.library = _library(params.contact, self.gyroscopic, backend)
        self.backend = self.library.backend
        self._p = np.ascontiguousarray(params.vector(), dtype=np.float64)
        self._lock = threading.Lock()
        if self.backend != "c":     # numpy backend: every call goes through the batch kernels
            self._kernels = self.library.kernels
            return
        self._pp = self._p.ctypes.data
        self._lib = self.library.lib
        # Single-state fast path: inputs are copied into fixed scratch buffers whose addresses
        # are taken once (numpy's .ctypes.data costs ~1 us per call, more than the C work).
        self._in = np.zeros(2 * N_Q + 3)                   # q | dq | T (3)
        self._out = np.zeros(128)
        self._status = np.zeros(1, dtype=np.intc)
        base = self._in.ctypes.data
        self._pq, self._pdq = base, base + 8 * N_Q
        self._pT = base + 16 * N_Q
        self._pout, self._pst = self._out.ctypes.data, self._status.ctypes.data
        self._kernels = {name: getattr(self._lib, f"bx_{name}_batch") for name in self.library.functions}

    def __repr__(self) -> str:
        variant = "" if self.gyroscopic else ", gyroscopic=False"
        variant += "" if self.backend == "c" else f", backend={self.backend!r}"
        return (f"Model(name={self.name!r}, contact={self.contact!r}, "
                f"source={self.params.source!r}{variant})")

    def with_params(self, params: Parameters) -> "Model":
        """The same model class and variant with another parameter set (e.g. a perturbed copy)."""
        return Model(params, gyroscopic=self.gyroscopic, backend=self.backend)

    # -- generic evaluation ------------------------------------------------------------
    def _eval(self, name: str, q, dq=_NO_RATES, shape=None):
        """Kernel ``name`` at q (and dq, for the kernels of the rates: a caller of those must
        give them; ``None`` there is refused, never read as the last call's or as q)."""
        if dq is None:
            raise ValueError(f"{_PUBLIC.get(name, name)} needs the rates dq (shape (8,) or "
                             "(N, 8)); got None")
        if dq is _NO_RATES:
            dq = None
        fn = self.library.functions[name]
        shape = shape or (fn.size,)
        if self.backend == "c" and np.ndim(q) == 1 and np.shape(q)[0] == N_Q and (dq is None or np.shape(dq) == (N_Q,)):
            with self._lock:
                self._in[:N_Q] = q
                if dq is not None:
                    self._in[N_Q:2 * N_Q] = dq
                self._kernels[name](1, self._pq, self._pdq, self._pp, self._pout)
                return self._out[:fn.size].reshape(shape).copy()
        qa, single = _states(q, N_Q, "q")
        if dq is None:
            da = qa  # unused by the kernel
        else:
            da, single_d = _states(dq, N_Q, "dq")
            if da.shape[0] != qa.shape[0]:
                raise ValueError(f"q and dq must hold the same number of states; got {qa.shape[0]} "
                                 f"and {da.shape[0]}")
        n = qa.shape[0]
        if self.backend != "c":
            out = self._kernels[name](qa, da, self._p)
        else:
            out = np.empty((n, fn.size))
            self._kernels[name](n, qa.ctypes.data, da.ctypes.data, self._pp, out.ctypes.data)
        out = out.reshape((n, *shape))
        return out[0] if single else out

    # -- the thesis's matrices ---------------------------------------------------------
    def mass_matrix(self, q) -> np.ndarray:
        """M(q) = L^T MM L (8x8, symmetric positive definite)."""
        return self._eval("mass_matrix", q, shape=(N_Q, N_Q))

    def Qv(self, q, dq) -> np.ndarray:
        """Quadratic-velocity forces L^T (QQv - MM l dq): gyroscopic and centripetal terms."""
        return self._eval("qv", q, dq)

    def Qgrav(self, q) -> np.ndarray:
        """Generalised gravity forces sum_i H_i^T [0, 0, -m_i g]."""
        return self._eval("qgrav", q)

    def Qaero(self, q, dq) -> np.ndarray:
        """Aerodynamic drag on the frame's CoM, -cv |vG3| H3^T vG3."""
        return self._eval("qaero", q, dq)

    def S(self, q) -> np.ndarray:
        """Rider-torque map (8x3): columns steer torque on the fork about z4, pedal torque on
        the rear wheel about y2, anti-roll torque on the frame about x3 (single-sided)."""
        return self._eval("smat", q, shape=(N_Q, 3))

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Qv + Qgrav + Qaero + S T (8,), T = [Mdir, Mped, Mvue] (N m); batch: T (3,) or (N, 3)."""
        dyn = self._eval("dynamics", q, dq)
        single = dyn.ndim == 1
        T = torque_array(torques, 1 if single else dyn.shape[0], single)
        F = dyn[..., N_Q * N_Q:N_Q * N_Q + N_Q]
        S = dyn[..., N_Q * N_Q + N_Q:].reshape(*dyn.shape[:-1], N_Q, 3)
        return F + np.einsum("...ij,...j->...i", S, T[0] if single else T)

    def inverse_dynamics(self, q, dq, ddq) -> np.ndarray:
        """Unconstrained inverse dynamics M ddq - Qv - Qgrav (what RNEA computes), (8,)."""
        mb = self._eval("mass_bias", q, dq)
        M = mb[..., :N_Q * N_Q].reshape(*mb.shape[:-1], N_Q, N_Q)
        a = np.asarray(ddq, dtype=np.float64)
        if a.shape[-1:] != (N_Q,):
            raise ValueError(f"ddq must have shape (8,) or (N, 8); got {a.shape}")
        return (M @ a[..., None])[..., 0] - mb[..., N_Q * N_Q:]

    def constraint_residual(self, q, dq) -> np.ndarray:
        """C = [rD_z, vC_x, vC_y, vD_x, vD_y] (front contact height, contact-point velocities)."""
        return self._eval("constraint_residual", q, dq)

    def constraint_jacobian(self, q) -> np.ndarray:
        """D (5x8): d rD_z/dq on top of d(vC_x, vC_y, vD_x, vD_y)/d dq, so that D dq = 0."""
        return self._eval("constraint_jacobian", q, shape=(N_C, N_Q))

    def constraint_bias(self, q, dq) -> np.ndarray:
        """dD dq (5,), so that D ddq + dD dq = 0."""
        return self._eval("constraint_bias", q, dq)

    def kinetic_energy(self, q, dq):
        """Kinetic energy of the four bodies (J)."""
        return self._eval("energy", q, dq)[..., 0]

    def potential_energy(self, q):
        """Gravitational potential energy sum m_i g z_Gi (J), zero at ground level."""
        return self._eval("energy", q)[..., 1]

    def points(self, q) -> dict[str, np.ndarray]:
        """Global positions: rear contact rC, steering-axis point rA, CoMs rG2..rG5, front
        contact rD (per the model's contact variant)."""
        pts = self._eval("points", q, shape=(len(POINT_NAMES), 3))
        return {k: pts[..., i, :] for i, k in enumerate(POINT_NAMES)}

    # -- the thesis's linear systems ---------------------------------------------------
    def forward(self, q, dq, torques=(0.0, 0.0, 0.0), baumgarte=(0.0, 0.0)) -> ForwardResult:
        """Solve [M D'; D 0][ddq; lambda] = [F + S T; -dD dq - 2 a1 D dq - a2^2 C].

        Never raises on a singular state: the status array says (0 ok, 1 singular, 2 non-finite).
        ``baumgarte=(a1, a2)``; (0, 0) gives the exact constrained accelerations.
        """
        if (self.backend == "c" and np.shape(q) == (N_Q,) and np.shape(dq) == (N_Q,)
                and np.shape(torques) == (3,)):
            a1, a2 = baumgarte
            with self._lock:
                buf = self._in
                buf[:N_Q] = q
                buf[N_Q:2 * N_Q] = dq
                buf[2 * N_Q:2 * N_Q + 3] = torques
                self._lib.bx_forward_batch(1, self._pq, self._pdq, self._pT, self._pp, float(a1),
                                           float(a2), self._pout, self._pout + 8 * N_Q, self._pst)
                out = self._out
                return ForwardResult(out[:N_Q].copy(), out[N_Q:N_Q + N_C].copy(), self._status.copy())
        qa, single = _states(q, N_Q, "q")
        da, _ = _states(dq, N_Q, "dq")
        n = qa.shape[0]
        if da.shape[0] != n:
            raise ValueError(f"q and dq must hold the same number of states; got {n} and {da.shape[0]}")
        T = torque_array(torques, n, single)
        a1, a2 = baumgarte
        if self.backend != "c":
            ddq, lam, status = self._kernels["forward_batch"](qa, da, T, self._p, float(a1), float(a2))
            if single:
                return ForwardResult(ddq[0], lam[0], status[:1])
            return ForwardResult(ddq, lam, status)
        ddq = np.empty((n, N_Q))
        lam = np.empty((n, N_C))
        status = np.empty(n, dtype=np.intc)
        self._lib.bx_forward_batch(n, qa.ctypes.data, da.ctypes.data, T.ctypes.data, self._pp,
                                   float(a1), float(a2), ddq.ctypes.data, lam.ctypes.data,
                                   status.ctypes.data)
        if single:
            return ForwardResult(ddq[0], lam[0], status[:1])
        return ForwardResult(ddq, lam, status)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Exact constrained accelerations ddq (no Baumgarte); raises ModelEvaluationError at a
        singular or non-finite state."""
        res = self.forward(q, dq, torques)
        if res.status.any():
            raise_on_status(res.status, "forward_acceleration")
        return res.ddq

    def eigenvalues(self, v):
        """The four roll/steer eigenvalues (1/s) of upright straight running at forward
        speed(s) v (m/s), cyclic and constraint zeros removed (`reference_model.linearize`)."""
        from .linearize import eigenvalues
        return eigenvalues(self, v)

    def inverse_dynamics_step(self, q, dq, ddq_ind):
        """The thesis's 13x13 system at given states and independent accelerations.

        ``ddq_ind`` = [ddtheta, ddpsi, ddgamma] (3,) or (N, 3). Returns (ddq, T, lam, status):
        the full accelerations (8,), the rider torques [Mdir, Mped, Mvue] and the 5 multipliers.
        """
        qa, single = _states(q, N_Q, "q")
        da, _ = _states(dq, N_Q, "dq")
        ia, _ = _states(ddq_ind, 3, "ddq_ind")
        n = qa.shape[0]
        if da.shape[0] != n or ia.shape[0] != n:
            raise ValueError("q, dq and ddq_ind must hold the same number of states")
        if self.backend != "c":
            out, status = self._kernels["inverse_dynamics_batch"](qa, da, ia, self._p)
        else:
            out = np.empty((n, 13))
            status = np.empty(n, dtype=np.intc)
            self._lib.bx_inverse_dynamics_batch(n, qa.ctypes.data, da.ctypes.data, ia.ctypes.data,
                                                self._pp, out.ctypes.data, status.ctypes.data)
        ddq = np.empty((n, N_Q))
        ddq[:, DEP] = out[:, :5]
        ddq[:, IND] = ia
        T, lam = out[:, 5:8], out[:, 8:13]
        if single:
            return ddq[0], T[0], lam[0], status[:1]
        return ddq, T, lam, status


def raise_on_status(status: np.ndarray, what: str) -> None:
    """Raise ModelEvaluationError for the first non-zero status of a forward solve."""
    bad = np.flatnonzero(status)
    if bad.size:
        i = int(bad[0])
        raise ModelEvaluationError(f"{what}: state {i} ({bad.size} state(s) in all): "
                                   f"{_STATUS.get(int(status[i]), 'unknown failure')}")


def load_model(
    name_or_path: str | Path = "thesis",
    *,
    contact: str | None = None,
    allow_triangle_violation: bool = False,
) -> Model:
    """Load a named model ('thesis', 'thesis-disc', 'benchmark'), a parameter TOML file, or a
    file of Meijaard et al. (2007) benchmark parameters (.txt in BicycleParameters' format,
    .json, flat .toml; front contact 'disc').

    ``contact`` overrides the file's front-contact model ('thesis' or 'disc');
    ``allow_triangle_violation=True`` loads inertias that break the triangle inequality and
    records it in ``model.warnings``.
    """
    params = resolve_model(name_or_path, allow_triangle_violation=allow_triangle_violation)
    if contact is not None:
        params = params.with_contact(contact)
    return Model(params)
