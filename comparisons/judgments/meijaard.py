"""The linear Whipple bicycle in closed form: J. P. Meijaard, J. M. Papadopoulos, A. Ruina,
A. L. Schwab, "Linearized dynamics equations for the balance and steer of a bicycle: a
benchmark and review", Proc. R. Soc. A 463 (2007) 1955-1982, Appendix A.

Written from the paper, in the benchmark's own axes (x forward, z down, y right) and symbols
(Table 1's 26 values; the paper's intermediate quantities mT, xT, zT, ITxx, ITxz, ITzz, mA, xA,
zA, IAxx, IAxz, IAzz, uA, IAll, IAlx, IAlz, mu, SR, SF, ST, SA), independently of the project's
parametrization (``reference_model.params``) and linearization (``reference_model.linearize``):
what the linearization is checked against (``comparisons.judgments.linear_check``).

The equations of motion over q = [phi, delta] (roll, steer) are the paper's (A 1)::

    M q'' + v C1 q' + (g K0 + v^2 K2) q = [T_phi, T_delta]

The wheels are axisymmetric with their diametral moments equal (the paper's IRzz = IRxx,
IFzz = IFxx): only IRxx and IFxx are read. A Table 1 that gives IRzz or IFzz (BicycleParameters'
files may) is the same bicycle only where they equal IRxx, IFxx; this module does not look.

Everything here is a pure function of its arguments.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = [
    "MATRICES", "ClosedForm", "closed_form", "closed_form_critical_speeds",
    "closed_form_eigenvalues", "max_matched_error", "state_matrix",
]

#: the four matrices' names, in the paper's order
MATRICES = ("M", "C1", "K0", "K2")


def _frozen(rows) -> np.ndarray:
    a = np.array(rows, dtype=np.float64)
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class ClosedForm:
    """The paper's M, C1, K0, K2 (2x2, over [phi, delta], benchmark signs) and g (m/s^2)."""

    M: np.ndarray
    C1: np.ndarray
    K0: np.ndarray
    K2: np.ndarray
    g: float


def closed_form(b: Mapping[str, float]) -> ClosedForm:
    """M, C1, K0, K2 of the bicycle with Table 1 values ``b`` (Appendix A, eqs. A 1 - A 27)."""
    w, c, lam, g = b["w"], b["c"], b["lam"], b["g"]
    rR, mR, IRxx, IRyy = b["rR"], b["mR"], b["IRxx"], b["IRyy"]
    xB, zB, mB = b["xB"], b["zB"], b["mB"]
    IBxx, IBzz, IBxz = b["IBxx"], b["IBzz"], b["IBxz"]
    xH, zH, mH = b["xH"], b["zH"], b["mH"]
    IHxx, IHzz, IHxz = b["IHxx"], b["IHzz"], b["IHxz"]
    rF, mF, IFxx, IFyy = b["rF"], b["mF"], b["IFxx"], b["IFyy"]
    IRzz, IFzz = IRxx, IFxx                     # axisymmetric wheels (module docstring)
    sl, cl = math.sin(lam), math.cos(lam)
    # the whole bicycle (T)
    mT = mR + mB + mH + mF
    xT = (xB * mB + xH * mH + w * mF) / mT
    zT = (-rR * mR + zB * mB + zH * mH - rF * mF) / mT
    ITxx = IRxx + IBxx + IHxx + IFxx + mR * rR**2 + mB * zB**2 + mH * zH**2 + mF * rF**2
    ITxz = IBxz + IHxz - mB * xB * zB - mH * xH * zH + mF * w * rF
    ITzz = IRzz + IBzz + IHzz + IFzz + mB * xB**2 + mH * xH**2 + mF * w**2
    # the front assembly (A = H + F)
    mA = mH + mF
    xA = (xH * mH + w * mF) / mA
    zA = (zH * mH - rF * mF) / mA
    IAxx = IHxx + IFxx + mH * (zH - zA) ** 2 + mF * (rF + zA) ** 2
    IAxz = IHxz - mH * (xH - xA) * (zH - zA) + mF * (w - xA) * (rF + zA)
    IAzz = IHzz + IFzz + mH * (xH - xA) ** 2 + mF * (w - xA) ** 2
    uA = (xA - w - c) * cl - zA * sl
    IAll = mA * uA**2 + IAxx * sl**2 + 2 * IAxz * sl * cl + IAzz * cl**2
    IAlx = -mA * uA * zA + IAxx * sl + IAxz * cl
    IAlz = mA * uA * xA + IAxz * sl + IAzz * cl
    mu = c / w * cl
    SR, SF = IRyy / rR, IFyy / rF
    ST = SR + SF
    SA = mA * uA + mu * mT * xT
    return ClosedForm(
        M=_frozen([[ITxx, IAlx + mu * ITxz],
                   [IAlx + mu * ITxz, IAll + 2 * mu * IAlz + mu**2 * ITzz]]),
        C1=_frozen([[0.0, mu * ST + SF * cl + ITxz / w * cl - mu * mT * zT],
                    [-(mu * ST + SF * cl), IAlz / w * cl + mu * (SA + ITzz / w * cl)]]),
        K0=_frozen([[mT * zT, -SA], [-SA, -SA * sl]]),
        K2=_frozen([[0.0, (ST - mT * zT) / w * cl], [0.0, (SA + SF * sl) / w * cl]]),
        g=float(g),
    )


def state_matrix(cf: ClosedForm, v) -> np.ndarray:
    """A of d/dt [phi, delta, phi', delta'] = A [...] at forward speed ``v`` (m/s): (4, 4) for a
    scalar, (n, 4, 4) for n speeds."""
    vs = np.asarray(v, dtype=np.float64)
    s = vs.reshape(-1, 1, 1)
    Minv = np.linalg.inv(cf.M)
    A = np.zeros((s.shape[0], 4, 4))
    A[:, 0, 2] = A[:, 1, 3] = 1.0
    A[:, 2:, :2] = -(Minv @ (cf.g * cf.K0)) - s**2 * (Minv @ cf.K2)
    A[:, 2:, 2:] = -s * (Minv @ cf.C1)
    return A[0] if vs.ndim == 0 else A


def closed_form_eigenvalues(cf: ClosedForm, v) -> np.ndarray:
    """The four eigenvalues (1/s, numpy's order) of :func:`state_matrix` at ``v``: (4,) for a
    scalar, (n, 4) for n speeds."""
    return np.linalg.eigvals(state_matrix(cf, v))


def _weave_real(cf: ClosedForm, v) -> np.ndarray:
    """Real part of the oscillatory pair of highest frequency at each speed; nan where all four
    eigenvalues are real."""
    lam = np.atleast_2d(closed_form_eigenvalues(cf, v))
    k = np.argmax(np.abs(lam.imag), axis=-1)
    top = np.take_along_axis(lam, k[:, None], axis=-1)[:, 0]
    return np.where(top.imag != 0, top.real, np.nan)


def _eigenvalue_product(cf: ClosedForm, v) -> np.ndarray:
    """The product of the four eigenvalues at each speed: a complex pair contributes
    |lambda|^2 > 0, so it changes sign exactly where a real eigenvalue crosses zero, and is
    continuous there (the real eigenvalue nearest zero need not be, where two real ones trade
    places)."""
    return np.prod(np.atleast_2d(closed_form_eigenvalues(cf, v)), axis=-1).real


def _first_root(f, grid: np.ndarray, down_only: bool) -> float | None:
    """brentq (xtol 1e-14) on the first interval of ``grid`` where ``f`` (vectorized) changes
    sign (from + to - only, if ``down_only``); None if it never does."""
    values = f(grid)
    a, b = values[:-1], values[1:]
    change = (a > 0) & (b <= 0) if down_only else (a * b < 0) | ((a != 0) & (b == 0))
    hits = np.flatnonzero(change)
    if hits.size == 0:
        return None
    i = int(hits[0])
    if values[i + 1] == 0.0:
        return float(grid[i + 1])
    # rtol: brentq's default, 4 eps, the tightest it accepts; it converges in 5 to 7
    # iterations on Table 1 and BicycleParameters' ten bicycles, far below maxiter
    return float(brentq(lambda s: float(f(s)[0]), grid[i], grid[i + 1], xtol=1e-14,
                        maxiter=200))


def _grid(lo: float, hi: float, step: float) -> np.ndarray:
    return np.linspace(lo, hi, max(int(math.ceil((hi - lo) / step)), 1) + 1)


def closed_form_critical_speeds(cf: ClosedForm, speeds: tuple[float, float] = (0.0, 10.0),
                                step: float = 0.01) -> tuple[float | None, float | None]:
    """(weave speed, capsize speed) in m/s within ``speeds`` from the closed form's eigenvalues;
    None where there is none.

    Weave: the first speed where the real part of the oscillatory pair of highest frequency
    crosses from + to -. Capsize: above the weave speed (from ``speeds[0]`` without one), the
    first speed where a real eigenvalue crosses zero, i.e. where the product of the four
    eigenvalues changes sign. Each is bracketed on a grid of ``step`` and refined by brentq
    (xtol 1e-14) on that function of the eigenvalues.
    """
    lo, hi = float(speeds[0]), float(speeds[1])
    weave = _first_root(lambda s: _weave_real(cf, s), _grid(lo, hi, step), down_only=True)
    start = lo if weave is None else weave
    capsize = _first_root(lambda s: _eigenvalue_product(cf, s), _grid(start, hi, step),
                          down_only=False)
    return weave, capsize


def max_matched_error(expected: np.ndarray, got: np.ndarray) -> float:
    """Largest |expected_i - got_j| / max(1, |expected_i|) after nearest matching."""
    rest, worst = list(got), 0.0
    for e in expected:
        j = int(np.argmin([abs(e - r) for r in rest]))
        worst = max(worst, abs(e - rest.pop(j)) / max(1.0, abs(e)))
    return worst
