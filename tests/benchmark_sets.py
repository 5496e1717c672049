"""Bicycles in BicycleParameters' ``<Name>Benchmark.txt`` format, made here (not copied).

* ``Table1Benchmark.txt``: Meijaard et al. (2007) Table 1 itself, typed from the paper
  (lam = pi/10 written with 17 digits), uncertainties 0.
* ``Perturbed{1,2,3}Benchmark.txt``: every parameter but g scaled by 1 +- (10..20 %), signs
  and sizes from ``numpy.random.default_rng(seed)``, rounded to 6 significant digits, redrawn
  (same generator) until every tensor is positive definite and obeys the triangle inequality
  with a 1 % margin; uncertainties 0.5 % of the value (3 digits), as measured sets carry.
* ``TriangleBenchmark.txt``: Table 1 with IByy = 1.02 x (sum of the other two principal
  moments of IB, 10 + 2 kg m^2) = 12.24: the triangle inequality broken by 2 %, as three of
  BicycleParameters' measured bicycles break it by 1-3 %.

``python tests/benchmark_sets.py`` rewrites ``tests/data/benchmark/``; a test checks the
committed files equal :func:`sets` (so they stay what this docstring says).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "data" / "benchmark"

NAMES = ("w", "c", "lam", "g", "rR", "mR", "IRxx", "IRyy", "xB", "zB", "mB", "IBxx", "IByy",
         "IBzz", "IBxz", "xH", "zH", "mH", "IHxx", "IHyy", "IHzz", "IHxz", "rF", "mF", "IFxx",
         "IFyy")
TABLE1 = {
    "w": "1.02", "c": "0.08", "lam": "0.31415926535897931", "g": "9.81",
    "rR": "0.3", "mR": "2.0", "IRxx": "0.0603", "IRyy": "0.12",
    "xB": "0.3", "zB": "-0.9", "mB": "85.0", "IBxx": "9.2", "IByy": "11.0", "IBzz": "2.8",
    "IBxz": "2.4", "xH": "0.9", "zH": "-0.7", "mH": "4.0", "IHxx": "0.05892", "IHyy": "0.06",
    "IHzz": "0.00708", "IHxz": "-0.00756", "rF": "0.35", "mF": "3.0", "IFxx": "0.1405",
    "IFyy": "0.28",
}  # fmt: skip
TENSORS = (("IRxx", "IRyy", "IRxx", None), ("IBxx", "IByy", "IBzz", "IBxz"),
           ("IHxx", "IHyy", "IHzz", "IHxz"), ("IFxx", "IFyy", "IFxx", None))
SEEDS = {"Perturbed1": 11, "Perturbed2": 22, "Perturbed3": 33}


def principal_moments(v: dict[str, float], tensor) -> list[float]:
    xx, yy, zz, xz = (v[k] if k else 0.0 for k in tensor)
    return sorted(np.linalg.eigvalsh(np.array([[xx, 0, xz], [0, yy, 0], [xz, 0, zz]])))


def physical(v: dict[str, float], margin: float) -> bool:
    """Every tensor positive definite, I1 + I2 >= (1 + margin) I3 for the largest I3."""
    for tensor in TENSORS:
        m = principal_moments(v, tensor)
        if m[0] <= 0 or m[0] + m[1] < (1 + margin) * m[2]:
            return False
    return all(v[k] > 0 for k in ("w", "rR", "rF", "mR", "mB", "mH", "mF"))


def perturbed(seed: int) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    base = {k: float(x) for k, x in TABLE1.items()}
    while True:
        size = rng.uniform(0.10, 0.20, len(NAMES))
        sign = rng.choice([-1.0, 1.0], len(NAMES))
        v = {k: float(f"{base[k] * (1 + s * d):.6g}") for k, s, d in zip(NAMES, sign, size)}
        v["g"] = base["g"]
        if physical(v, 0.01):
            return v


def _line(name: str, value: str, uncertainty: str) -> str:
    return f"{name} = {value}+/-{uncertainty}"


def sets() -> dict[str, str]:
    """File name -> text."""
    out = {"Table1Benchmark.txt": "\n".join(_line(k, TABLE1[k], "0.0") for k in NAMES) + "\n"}
    for label, seed in SEEDS.items():
        v = perturbed(seed)
        lines = [_line(k, repr(v[k]), f"{abs(v[k]) * 0.005:.3g}") for k in sorted(NAMES)]
        out[f"{label}Benchmark.txt"] = "\n".join(lines) + "\n"
    v = {k: float(x) for k, x in TABLE1.items()}
    m = principal_moments({**v, "IByy": 0.0}, TENSORS[1])          # 0, 2, 10 (xz block)
    assert math.isclose(m[1] + m[2], 12.0, rel_tol=1e-14)
    triangle = dict(TABLE1, IByy="12.24")                           # 1.02 * 12
    out["TriangleBenchmark.txt"] = "\n".join(_line(k, triangle[k], "0.0") for k in NAMES) + "\n"
    return out


if __name__ == "__main__":
    DATA.mkdir(parents=True, exist_ok=True)
    for name, text in sets().items():
        (DATA / name).write_text(text, encoding="utf-8")
        print(f"wrote {DATA / name}", file=sys.stderr)
