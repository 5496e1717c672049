"""The Meijaard et al. (2007) benchmark bicycle in the reference model's parametrization.

Source: J. P. Meijaard, J. M. Papadopoulos, A. Ruina, A. L. Schwab, "Linearized dynamics
equations for the balance and steer of a bicycle: a benchmark and review", Proc. R. Soc. A 463
(2007) 1955-1982, Table 1. The benchmark is published in its own axes: x forward, **z down**,
y to the right, origin at the rear contact point in the upright reference configuration. The
reference model (thesis notation, ``params.PARAMETER_NAMES``) uses x forward, **z up**, y to
the left, and measures every length in the frame's or the fork's own axes. This module holds
Table 1 (:data:`TABLE1`) and the formulas from it to the model's parameters
(:func:`reference_parameters`); ``reference_model/parameters/benchmark.toml`` is their output
(``python -m reference_model.benchmark --write`` regenerates it, ``--check`` compares).

Formulas (``c = cos(lambda)``, ``s = sin(lambda)``; positions in the model's global axes at
upright, z up, origin at the rear contact; "frame components" of a vector d are
``(c d_x + s d_z, -s d_x + c d_z)``):

* **Frame axes.** The steering axis must be the frame's z axis. The benchmark's axis is tilted
  back by the head angle complement lambda, so the frame's axes are the global ones pitched by
  ``beta = -lambda``: ``x3 = (c, 0, s)``, ``z3 = (-s, 0, c)``. The model solves this beta from the
  front contact (it is not a parameter); the tests check it comes out as ``-lambda``.
* **Going to z up** is a rotation by pi about x: positions ``(x, z) -> (x, -z)``; inertia
  tensors keep ``xx, yy, zz`` and change the sign of the product ``xz`` (``yz`` too, zero here).
* **Points** (global, z up): rear hub ``G2 = (0, 0, rR)``, rear body CoM ``B = (xB, 0, -zB)``,
  front assembly CoM ``H = (xH, 0, -zH)``, front hub ``G5 = (w, 0, rF)``; the steering axis
  meets the ground at ``(w + c_trail, 0, 0)``.
* ``R_rear = rR``, ``R_front = rF``.
* ``x3, z3`` = frame components of ``B - G2 = (xB, 0, -zB - rR)``.
* Steering-axis point A = the foot of the perpendicular from the front hub to the axis, so the
  fork offset is explicit: ``x5 = e = rF s - c_trail c`` (fork offset, perpendicular distance
  of the front hub from the axis, positive ahead), ``z5 = 0``.
* ``xa = (w + c_trail) c - rR s``, ``za = -w s + (rF - rR) c`` (frame components of
  ``A - G2 = G5 - G2 - e x3``).
* ``dx4, dz4`` = frame components of ``H - G2`` minus ``(xa, za)``.
* Masses: ``m2 = mR, m3 = mB, m4 = mH, m5 = mF``.
* Wheels (axisymmetric, spin axis y): ``I2 = diag(IRxx, IRyy, IRxx)``,
  ``I5 = diag(IFxx, IFyy, IFxx)`` (the benchmark's ``Izz = Ixx``).
* Rear body and front assembly: with ``(Ixx, Iyy, Izz, Ixz)`` the z-up tensor
  (``Ixz = -Ixz`` of Table 1), in frame axes
  ``I'xx = c^2 Ixx + 2 c s Ixz + s^2 Izz``, ``I'zz = s^2 Ixx - 2 c s Ixz + c^2 Izz``,
  ``I'xz = c s (Izz - Ixx) + (c^2 - s^2) Ixz``, ``I'yy = Iyy``; the fork's axes equal the
  frame's at zero steer.
* ``g = 9.81``, ``cv = 0`` (the benchmark has no drag). Front contact model ``disc`` (the true
  lowest point of the front wheel, as the benchmark's knife-edge wheel).

Values are written with ``repr``: the shortest decimal that reads back as the same double (at
most 17 significant digits), so the file reproduces these formulas bit for bit.
"""

from __future__ import annotations

import argparse
import math
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

from .params import (BENCHMARK_FILE, PARAMETER_DESCRIPTIONS, PARAMETER_GROUPS, PARAMETER_NAMES,
                     PARAMETER_UNITS)

__all__ = ["BENCHMARK_FILE", "TABLE1", "Table1", "reference_parameters", "toml_text"]



@dataclass(frozen=True)
class Table1:
    """Table 1 of Meijaard et al. (2007), as published (x forward, z down, SI units).

    Inertia tensors are about the body's CoM in the benchmark's global axes at upright;
    ``IB``/``IH`` are given by their non-zero entries (``xz`` is the tensor entry, as printed).
    """

    w: float = 1.02                 # wheel base, m
    c: float = 0.08                 # trail, m
    lam: float = math.pi / 10       # steer axis tilt from vertical (pi/2 - head angle), rad
    g: float = 9.81                 # gravity, m/s^2
    rR: float = 0.3                 # rear wheel radius, m
    mR: float = 2.0                 # rear wheel mass, kg
    IRxx: float = 0.0603            # rear wheel diametral inertia (= IRzz), kg m^2
    IRyy: float = 0.12              # rear wheel polar inertia, kg m^2
    xB: float = 0.3                 # rear body + rider CoM, forward, m
    zB: float = -0.9                # rear body + rider CoM, z down, m
    mB: float = 85.0                # rear body + rider mass, kg
    IBxx: float = 9.2
    IByy: float = 11.0
    IBzz: float = 2.8
    IBxz: float = 2.4               # z-down tensor entry
    xH: float = 0.9                 # front assembly (fork + handlebar) CoM, forward, m
    zH: float = -0.7                # front assembly CoM, z down, m
    mH: float = 4.0                 # front assembly mass, kg
    IHxx: float = 0.05892
    IHyy: float = 0.06
    IHzz: float = 0.00708
    IHxz: float = -0.00756          # z-down tensor entry
    rF: float = 0.35                # front wheel radius, m
    mF: float = 3.0                 # front wheel mass, kg
    IFxx: float = 0.1405            # front wheel diametral inertia (= IFzz), kg m^2
    IFyy: float = 0.28              # front wheel polar inertia, kg m^2


TABLE1 = Table1()


def _frame_components(dx: float, dz: float, c: float, s: float) -> tuple[float, float]:
    """Components along the frame's x and z axes, (c, 0, s) and (-s, 0, c), of (dx, 0, dz)."""
    return c * dx + s * dz, -s * dx + c * dz


def _frame_inertia(xx: float, zz: float, xz_down: float, c: float, s: float) -> tuple[float, float, float]:
    """(I'xx, I'zz, I'xz) in frame axes of a tensor given in the benchmark's z-down axes."""
    xz = -xz_down  # rotation by pi about x: the xz product changes sign
    return (c * c * xx + 2.0 * c * s * xz + s * s * zz,
            s * s * xx - 2.0 * c * s * xz + c * c * zz,
            c * s * (zz - xx) + (c * c - s * s) * xz)


def reference_parameters(t: Table1 = TABLE1) -> dict[str, float]:
    """The model's parameters (``PARAMETER_NAMES`` order, SI) from Table 1 (module docstring)."""
    c, s = math.cos(t.lam), math.sin(t.lam)
    x3, z3 = _frame_components(t.xB, -t.zB - t.rR, c, s)
    e = t.rF * s - t.c * c                                   # fork offset
    xa = (t.w + t.c) * c - t.rR * s
    za = -t.w * s + (t.rF - t.rR) * c
    hx, hz = _frame_components(t.xH, -t.zH - t.rR, c, s)
    I3xx, I3zz, I3xz = _frame_inertia(t.IBxx, t.IBzz, t.IBxz, c, s)
    I4xx, I4zz, I4xz = _frame_inertia(t.IHxx, t.IHzz, t.IHxz, c, s)
    values = {
        "R_rear": t.rR, "R_front": t.rF,
        "x3": x3, "z3": z3,
        "xa": xa, "za": za,
        "dx4": hx - xa, "dz4": hz - za,
        "x5": e, "z5": 0.0,
        "m2": t.mR, "m3": t.mB, "m4": t.mH, "m5": t.mF,
        "I2xx": t.IRxx, "I2yy": t.IRyy, "I2zz": t.IRxx,
        "I3xx": I3xx, "I3yy": t.IByy, "I3zz": I3zz, "I3xz": I3xz,
        "I4xx": I4xx, "I4yy": t.IHyy, "I4zz": I4zz, "I4xz": I4xz,
        "I5xx": t.IFxx, "I5yy": t.IFyy, "I5zz": t.IFxx,
        "g": t.g, "cv": 0.0,
    }  # fmt: skip
    assert tuple(values) == PARAMETER_NAMES
    return values


_COMMENTS: dict[str, str] = {
    "R_rear": "rR",
    "R_front": "rF",
    "x3": "frame x of B - G2 = (xB, -zB - rR): c xB + s (-zB - rR)",
    "z3": "frame z of B - G2: -s xB + c (-zB - rR)",
    "xa": "A = foot of the perpendicular from the front hub on the steering axis: (w + c_trail) c - rR s",
    "za": "-w s + (rF - rR) c",
    "dx4": "frame x of H - G2 = (xH, -zH - rR), minus xa",
    "dz4": "frame z of H - G2, minus za",
    "x5": "fork offset e = rF s - c_trail c (front hub from A, perpendicular to the axis)",
    "z5": "0: A is the foot of the perpendicular from the front hub",
    "m2": "mR", "m3": "mB", "m4": "mH", "m5": "mF",
    "I2xx": "IRxx", "I2yy": "IRyy (spin axis)", "I2zz": "IRzz = IRxx",
    "I3xx": "IB in frame axes: c^2 Ixx + 2 c s Ixz + s^2 Izz (Ixz = -IBxz: z up)",
    "I3yy": "IByy",
    "I3zz": "s^2 Ixx - 2 c s Ixz + c^2 Izz",
    "I3xz": "c s (Izz - Ixx) + (c^2 - s^2) Ixz",
    "I4xx": "IH in frame (= fork at zero steer) axes, same formulas as I3xx (Ixz = -IHxz)",
    "I4yy": "IHyy",
    "I4zz": "as I3zz, from IH",
    "I4xz": "as I3xz, from IH",
    "I5xx": "IFxx", "I5yy": "IFyy (spin axis)", "I5zz": "IFzz = IFxx",
    "g": "g",
    "cv": "no drag in the benchmark",
}  # fmt: skip


def toml_text(t: Table1 = TABLE1) -> str:
    """The parameter file ``benchmark.toml`` for Table 1 (with the formulas as comments)."""
    values = reference_parameters(t)
    head = [
        "# Meijaard et al. (2007) benchmark bicycle, Table 1, in the reference model's parametrization.",
        "# GENERATED by `python -m reference_model.benchmark --write` from reference_model/benchmark.py,",
        "# whose docstring derives every formula; tests/test_benchmark.py recomputes the values.",
        "# Values are repr() of the doubles (shortest exact decimal, <= 17 significant digits).",
        "#",
        "# Table 1 (benchmark axes: x forward, z DOWN): w = 1.02, c_trail = 0.08, lambda = pi/10,",
        "# g = 9.81; rR = 0.3, mR = 2, (IRxx, IRyy) = (0.0603, 0.12); (xB, zB) = (0.3, -0.9), mB = 85,",
        "# IB = [[9.2, 0, 2.4], [0, 11, 0], [2.4, 0, 2.8]]; (xH, zH) = (0.9, -0.7), mH = 4,",
        "# IH = [[0.05892, 0, -0.00756], [0, 0.06, 0], [-0.00756, 0, 0.00708]]; rF = 0.35, mF = 3,",
        "# (IFxx, IFyy) = (0.1405, 0.28).",
        "# Model axes: x forward, z UP; frame axes = global pitched by beta = -lambda (z3 = steering",
        "# axis); c = cos(lambda), s = sin(lambda). Going to z up flips the sign of each xz product.",
        "",
        "[model]",
        'name = "benchmark"',
        'description = "Meijaard et al. (2007) benchmark bicycle: raked steering axis (lambda = pi/10), '
        'trail 0.08 m, wheels 0.3 m / 0.35 m, front assembly CoM off the axis, no drag"',
        'source = "Meijaard, Papadopoulos, Ruina, Schwab, Proc. R. Soc. A 463 (2007) 1955-1982, Table 1"',
        'contact = "disc"',
    ]
    lines = head
    table = None
    for name, value in values.items():
        if PARAMETER_GROUPS[name] != table:
            table = PARAMETER_GROUPS[name]
            lines += ["", f"[{table}]"]
        unit = PARAMETER_UNITS[name]
        entry = f'{name} = {{ value = {value!r}, unit = "{unit}" }}'
        lines.append(f"{entry:<58s} # {PARAMETER_DESCRIPTIONS[name]}: {_COMMENTS[name]}")
    return "\n".join(lines) + "\n"


def _file_values(path: Path) -> dict[str, float]:
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    return {n: data[PARAMETER_GROUPS[n]][n]["value"] for n in PARAMETER_NAMES}


def main(argv: list[str] | None = None) -> int:
    """``--write`` regenerates benchmark.toml; ``--check`` compares it with the formulas."""
    ap = argparse.ArgumentParser(prog="python -m reference_model.benchmark", description=main.__doc__)
    group = ap.add_mutually_exclusive_group(required=True)
    group.add_argument("--write", action="store_true", help=f"write {BENCHMARK_FILE}")
    group.add_argument("--check", action="store_true", help="exit 1 if the file's values differ")
    args = ap.parse_args(argv)
    if args.write:
        BENCHMARK_FILE.write_text(toml_text(), encoding="utf-8")
        print(f"wrote {BENCHMARK_FILE}")
        return 0
    expected = reference_parameters()
    found = _file_values(BENCHMARK_FILE)
    bad = [n for n in PARAMETER_NAMES if found[n] != expected[n]]
    for n in bad:
        print(f"{n}: file {found[n]!r}, formula {expected[n]!r}", file=sys.stderr)
    print(f"{BENCHMARK_FILE}: " + ("matches the formulas" if not bad else f"{len(bad)} value(s) differ"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
