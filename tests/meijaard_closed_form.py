"""The linear benchmark bicycle in closed form: Meijaard et al. (2007), appendix A, written
from the paper in the benchmark's own axes, independently of the project's parametrization and
linearization (the expected values of tests/test_import.py and tests/test_bicycleparameters.py).
"""

from __future__ import annotations

import math

import numpy as np




def closed_form(b: dict[str, float]) -> dict[str, np.ndarray]:
    """M, C1, K0, K2 of the benchmark bicycle with Table 1 values ``b`` (the paper's eqs.)."""
    w, c, lam, g = b["w"], b["c"], b["lam"], b["g"]
    rR, mR, IRxx, IRyy = b["rR"], b["mR"], b["IRxx"], b["IRyy"]
    xB, zB, mB = b["xB"], b["zB"], b["mB"]
    IBxx, IByy, IBzz, IBxz = b["IBxx"], b["IByy"], b["IBzz"], b["IBxz"]
    xH, zH, mH = b["xH"], b["zH"], b["mH"]
    IHxx, IHzz, IHxz = b["IHxx"], b["IHzz"], b["IHxz"]
    rF, mF, IFxx, IFyy = b["rF"], b["mF"], b["IFxx"], b["IFyy"]
    IRzz, IFzz = IRxx, IFxx
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
    return {
        "M": np.array([[ITxx, IAlx + mu * ITxz],
                       [IAlx + mu * ITxz, IAll + 2 * mu * IAlz + mu**2 * ITzz]]),
        "K0": np.array([[mT * zT, -SA], [-SA, -SA * sl]]),
        "K2": np.array([[0.0, (ST - mT * zT) / w * cl], [0.0, (SA + SF * sl) / w * cl]]),
        "C1": np.array([[0.0, mu * ST + SF * cl + ITxz / w * cl - mu * mT * zT],
                        [-(mu * ST + SF * cl), IAlz / w * cl + mu * (SA + ITzz / w * cl)]]),
    }


def closed_form_eigenvalues(mats: dict[str, np.ndarray], g: float, v: float) -> np.ndarray:
    M, C1, K0, K2 = mats["M"], mats["C1"], mats["K0"], mats["K2"]
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((2, 2)), np.eye(2)],
                  [-Minv @ (g * K0 + v**2 * K2), -Minv @ (v * C1)]])
    return np.linalg.eigvals(A)


def max_matched_error(expected: np.ndarray, got: np.ndarray) -> float:
    """Largest |expected_i - got_j| / max(1, |expected_i|) after nearest matching."""
    rest, worst = list(got), 0.0
    for e in expected:
        j = int(np.argmin([abs(e - r) for r in rest]))
        worst = max(worst, abs(e - rest.pop(j)) / max(1.0, abs(e)))
    return worst
