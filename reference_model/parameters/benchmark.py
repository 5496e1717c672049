"""The Meijaard et al. (2007) benchmark bicycle in the reference model's parametrization.

Source: J. P. Meijaard, J. M. Papadopoulos, A. Ruina, A. L. Schwab, "Linearized dynamics
equations for the balance and steer of a bicycle: a benchmark and review", Proc. R. Soc. A 463
(2007) 1955-1982, Table 1. The benchmark is published in its own axes: x forward, **z down**,
y to the right, origin at the rear contact point in the upright reference configuration. The
reference model (thesis notation, ``PARAMETER_NAMES``) uses x forward, **z up**, y to
the left, and measures every length in the frame's or the fork's own axes. This module holds
Table 1 (:data:`TABLE1`, :class:`Table1` and its checks) and the formulas from it to the
model's 30 parameter values (:func:`model_values`, :func:`reference_parameters`) and back
(:func:`benchmark_values`), on plain values: it knows no
:class:`~reference_model.parameters.values.Parameters` (which builds itself from a Table 1
with these formulas: ``Parameters.from_benchmark``, ``parameters_from_benchmark``,
``to_benchmark`` live there) and no file (``reference_model.parameters.model_file`` writes
the parameter file, ``reference_model.parameters.benchmark_files`` reads and writes Table 1's
own files). ``reference_model/parameters/benchmark.toml`` is their output for Table 1
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
* ``g`` = Table 1's g, ``cv = 0`` (the benchmark has no drag). Front contact model ``disc`` (the
  true lowest point of the front wheel, as the benchmark's knife-edge wheel): it is part of
  what :func:`reference_parameters` returns, so no model is ever built from benchmark
  parameters with an implicit contact.

**The reverse** (:func:`to_benchmark`), for a model with disc contact, no drag and wheels with
``Izz = Ixx``: the upright pitch beta solves ``R_rear - (xa + x5) sin(beta) + (za + z5) cos(beta)
= R_front`` (hub above the disc's lowest point; the root of smallest ``|beta|``), ``lambda =
-beta``; every point back in global axes, ``w`` = the front hub's x, the trail from where the
steering axis (through A along z3) meets the ground, the tensors rotated back (the formulas
above with ``s -> -s``) and their xz products flipped to z down. A model that carries its Table
1 (``Parameters.benchmark``, from an import or a ``[benchmark]`` table) gets those values back
exactly, once they are checked to reproduce the model's values.

**Checks on Table 1** (:class:`Table1` validates on construction, naming Table 1's keys):
finite reals; ``w, rR, rF, g`` and the masses > 0; ``|lam| < pi/2``; each body's tensor
(``IR = diag(IRxx, IRyy, IRxx)``, ``IB``, ``IH``, ``IF`` likewise) positive definite. The
triangle inequality of principal moments is checked when building the model: an error naming
the Table 1 keys in "strict" mode, a warning carried by the model in "warn" mode.

"""


from __future__ import annotations

import decimal
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from .schema import (MEMORY_SOURCE, PARAMETER_GROUPS, PARAMETER_NAMES, TRIANGLE_RTOL,
                     ParameterError, TriangleInequalityError, as_real, closest,
                     principal_moments)

__all__ = [
    "BENCHMARK_DESCRIPTIONS", "BENCHMARK_NAMES", "CONSISTENCY_RTOL", "FORMULAS_MODULE", "TABLE1",
    "Table1", "benchmark_values", "checked_table", "consistent_table", "inconsistency",
    "model_values", "reference_parameters", "table1_from_mapping",
]

#: Module holding the formulas, named in every file written from them (the name users import
#: them by; the code is in reference_model/parameters/benchmark.py).
FORMULAS_MODULE = "reference_model.benchmark (reference_model/benchmark.py)"

#: Table 1's 26 names -> meaning (benchmark axes: x forward, z down; SI units, lam in rad).
BENCHMARK_DESCRIPTIONS: dict[str, str] = {
    "w": "wheel base, m",
    "c": "trail, m",
    "lam": "steer axis tilt from vertical (pi/2 - head angle), rad",
    "g": "gravity, m/s^2",
    "rR": "rear wheel radius, m",
    "mR": "rear wheel mass, kg",
    "IRxx": "rear wheel diametral inertia (= IRzz), kg m^2",
    "IRyy": "rear wheel polar inertia, kg m^2",
    "xB": "rear body + rider CoM, forward, m",
    "zB": "rear body + rider CoM, z down, m",
    "mB": "rear body + rider mass, kg",
    "IBxx": "rear body inertia xx, kg m^2",
    "IByy": "rear body inertia yy, kg m^2",
    "IBzz": "rear body inertia zz, kg m^2",
    "IBxz": "rear body inertia xz (z-down tensor entry), kg m^2",
    "xH": "front assembly (fork + handlebar) CoM, forward, m",
    "zH": "front assembly CoM, z down, m",
    "mH": "front assembly mass, kg",
    "IHxx": "front assembly inertia xx, kg m^2",
    "IHyy": "front assembly inertia yy, kg m^2",
    "IHzz": "front assembly inertia zz, kg m^2",
    "IHxz": "front assembly inertia xz (z-down tensor entry), kg m^2",
    "rF": "front wheel radius, m",
    "mF": "front wheel mass, kg",
    "IFxx": "front wheel diametral inertia (= IFzz), kg m^2",
    "IFyy": "front wheel polar inertia, kg m^2",
}
BENCHMARK_NAMES: tuple[str, ...] = tuple(BENCHMARK_DESCRIPTIONS)

_POSITIVE = ("w", "rR", "rF", "g", "mR", "mB", "mH", "mF")
# body letter -> (xx, yy, zz, xz or None): the wheels' zz is their xx (axisymmetric)
_TENSORS: dict[str, tuple[str, str, str, str | None]] = {
    "R": ("IRxx", "IRyy", "IRxx", None),
    "B": ("IBxx", "IByy", "IBzz", "IBxz"),
    "H": ("IHxx", "IHyy", "IHzz", "IHxz"),
    "F": ("IFxx", "IFyy", "IFxx", None),
}
_BODY = {"R": "rear wheel", "B": "rear body + rider", "H": "front assembly", "F": "front wheel"}

def _real(file: str, key: str, value: object) -> float:
    """A finite real number (NumPy scalars, ints, Fractions, Decimals) as a Python float: the
    schema's check, in Python's spelling (a Table 1 mapping comes from code or a file of
    numbers), Decimals too (they are no ``numbers.Real``)."""
    if isinstance(value, decimal.Decimal):
        value = float(value)
    return as_real(file, key, value, python_literals=True)



def _validate(values: Mapping[str, float], file: str, prefix: str) -> None:
    """Signs, the head angle, positive definite tensors (hard errors, Table 1 keys named)."""
    for n in _POSITIVE:
        if not values[n] > 0.0:
            raise ParameterError(file, prefix + n, f"{n} = {values[n]!r} must be > 0 "
                                 f"({BENCHMARK_DESCRIPTIONS[n]})", f"use a positive {n}")
    if not abs(values["lam"]) < math.pi / 2:
        raise ParameterError(file, prefix + "lam", f"lam = {values['lam']!r} rad is not a steer "
                             "axis tilt in (-pi/2, pi/2)",
                             "give lam in radians (pi/2 - head angle), e.g. 0.3141592653589793")
    for body, (kxx, kyy, kzz, kxz) in _TENSORS.items():
        bad = [k for k in dict.fromkeys((kxx, kyy, kzz)) if not values[k] > 0.0]
        if bad:
            raise ParameterError(file, ", ".join(prefix + k for k in bad),
                                 f"inertia of the {_BODY[body]} is not positive definite: "
                                 + ", ".join(f"{k} = {values[k]!r}" for k in bad),
                                 "use positive moments of inertia in kg m^2")
        if kxz is not None and not values[kxx] * values[kzz] - values[kxz] ** 2 > 0.0:
            raise ParameterError(
                file, ", ".join(prefix + k for k in (kxz, kxx, kzz)),
                f"inertia of the {_BODY[body]} is not positive definite: {kxz}^2 = "
                f"{values[kxz] ** 2!r} >= {kxx}*{kzz} = {values[kxx] * values[kzz]!r}",
                f"make |{kxz}| < sqrt({kxx}*{kzz}) = {math.sqrt(values[kxx] * values[kzz]):.6g} "
                "kg m^2 (check its sign and units)")


def _triangle_violations(values: Mapping[str, float], prefix: str) -> list[tuple[str, str]]:
    """(keys, problem) for each body whose principal moments break I1 + I2 >= I3."""
    found = []
    for body, (kxx, kyy, kzz, kxz) in _TENSORS.items():
        xz = values[kxz] if kxz is not None else 0.0
        moments = principal_moments(values[kxx], values[kyy], values[kzz], xz)
        for i in range(3):
            others = moments[(i + 1) % 3] + moments[(i + 2) % 3]
            if others < moments[i] - TRIANGLE_RTOL * max(moments):
                # y is a principal axis; the other two moments come from the x-z block
                keys = [kyy] if i == 1 else [k for k in dict.fromkeys((kxx, kzz, kxz)) if k]
                found.append((", ".join(prefix + k for k in keys),
                              f"inertia of the {_BODY[body]} violates the triangle inequality "
                              f"of principal moments by {moments[i] / others - 1.0:.2%}: "
                              f"{moments[i]!r} > {others!r} (sum of the other two; principal "
                              f"moments {tuple(round(m, 12) for m in moments)} kg m^2)"))
    return found


@dataclass(frozen=True)
class Table1:
    """Table 1 of Meijaard et al. (2007), as published (x forward, z down, SI units).

    Inertia tensors are about the body's CoM in the benchmark's global axes at upright;
    ``IB``/``IH`` are given by their non-zero entries (``xz`` is the tensor entry, as printed).
    Any real numbers are accepted and kept as Python floats (a NumPy scalar never reaches a
    written file); construction validates (module docstring, "Checks on Table 1").
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

    def __post_init__(self) -> None:
        values = {n: _real(MEMORY_SOURCE, n, getattr(self, n)) for n in BENCHMARK_NAMES}
        for n, v in values.items():
            object.__setattr__(self, n, v)
        _validate(values, MEMORY_SOURCE, "")

    def as_dict(self) -> dict[str, float]:
        """The 26 values by Table 1 name, in Table 1's order."""
        return {n: getattr(self, n) for n in BENCHMARK_NAMES}


TABLE1 = Table1()


def table1_from_mapping(
    mapping: Mapping[str, Any] | Table1, *, source: str = MEMORY_SOURCE, prefix: str = ""
) -> Table1:
    """Validate a mapping of Table 1's 26 names to real numbers (or a Table1) into a Table1.

    Errors name ``source`` and the key (``prefix + name``, e.g. ``benchmark.w`` in a parameter
    file's ``[benchmark]`` table): not a mapping, unknown names (with the closest valid one),
    missing names, values that are not finite reals, and the checks of :class:`Table1`.
    """
    file = str(source)
    if isinstance(mapping, Table1):
        return mapping
    if not isinstance(mapping, Mapping):
        raise ParameterError(file, prefix.rstrip(".") or "(benchmark)",
                             f"expected a mapping of Table 1 names to numbers, got "
                             f"{type(mapping).__name__}",
                             "give w, c, lam, g, rR, ... as name = value pairs")
    for key in mapping:
        if key not in BENCHMARK_DESCRIPTIONS:
            hint = closest(str(key), BENCHMARK_NAMES)
            raise ParameterError(file, f"{prefix}{key}", f"unknown benchmark parameter {key!r}",
                                 (f"did you mean {hint!r}? " if hint else "remove it; ")
                                 + "Table 1's names are " + ", ".join(BENCHMARK_NAMES))
    missing = [n for n in BENCHMARK_NAMES if n not in mapping]
    if missing:
        raise ParameterError(file, ", ".join(prefix + n for n in missing),
                             f"{len(missing)} of Table 1's 26 parameters missing: "
                             + ", ".join(missing),
                             "add " + "; ".join(f"{n} ({BENCHMARK_DESCRIPTIONS[n]})"
                                                for n in missing[:3])
                             + ("; ..." if len(missing) > 3 else ""))
    values = {n: _real(file, prefix + n, mapping[n]) for n in BENCHMARK_NAMES}
    _validate(values, file, prefix)
    return Table1(**values)


def _frame_components(dx: float, dz: float, c: float, s: float) -> tuple[float, float]:
    """Components along the frame's x and z axes, (c, 0, s) and (-s, 0, c), of (dx, 0, dz)."""
    return c * dx + s * dz, -s * dx + c * dz


def _frame_inertia(xx: float, zz: float, xz_down: float, c: float, s: float) -> tuple[float, float, float]:
    """(I'xx, I'zz, I'xz) in frame axes of a tensor given in the benchmark's z-down axes."""
    xz = -xz_down  # rotation by pi about x: the xz product changes sign
    return (c * c * xx + 2.0 * c * s * xz + s * s * zz,
            s * s * xx - 2.0 * c * s * xz + c * c * zz,
            c * s * (zz - xx) + (c * c - s * s) * xz)


def model_values(t: Table1) -> dict[str, float]:
    """The model's 30 parameters (``PARAMETER_NAMES`` order, SI) from Table 1."""
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


def reference_parameters(t: Table1 = TABLE1) -> dict[str, Any]:
    """Keyword arguments of :class:`Parameters` for Table 1: the model's 30 values
    (``PARAMETER_NAMES`` order, SI; module docstring), then ``contact="disc"`` (the benchmark's
    knife-edge wheel) and ``benchmark=t`` (provenance), so ``Parameters(**reference_parameters(t))``
    is the benchmark bicycle with its own contact model, never the thesis's by default."""
    return {**model_values(t), "contact": "disc", "benchmark": t}


def checked_table(
    mapping: Mapping[str, Any] | Table1,
    *,
    source: str = MEMORY_SOURCE,
    allow_triangle_violation: bool = False,
) -> Table1:
    """:func:`table1_from_mapping`, and the triangle inequality of each body's principal
    moments: an error naming Table 1's keys unless ``allow_triangle_violation`` (the model
    built from it then carries the violation in its ``warnings``)."""
    table = table1_from_mapping(mapping, source=source)
    violations = _triangle_violations(table.as_dict(), "")
    if violations and not allow_triangle_violation:
        keys, problem = violations[0]
        raise TriangleInequalityError(
            str(source), keys, problem,
            "check the values and units; if they are measured and right, allow it with "
            "allow_triangle_violation=True (bicycle-xval import --allow-triangle-violation)")
    return table


# -- provenance: a model that carries its Table 1 ---------------------------------------------

# The model's values computed again from a stored Table 1 must agree to rounding: per parameter,
# |difference| <= CONSISTENCY_RTOL * scale, the scale being the largest magnitude among the
# values the formula combines (all lengths; one body's tensor entries; the value itself for the
# copied masses, radii, g). The formulas take a handful of roundings (measured <= 3 ulp on
# Table 1) and a platform's cos/sin may differ by an ulp, so 1e-14 (~45 ulp) never refuses a
# file written by this module, while any edit of a value in the file (>= 1e-12 relative for
# 12 significant digits) is caught.
CONSISTENCY_RTOL = 1e-14


def _scales(values: Mapping[str, float]) -> dict[str, float]:
    lengths = max(abs(values[n]) for n in PARAMETER_NAMES[:10])
    out = {n: lengths for n in PARAMETER_NAMES[:10]}
    for body in (3, 4):
        keys = [f"I{body}{a}" for a in ("xx", "yy", "zz", "xz")]
        out.update(dict.fromkeys(keys, max(abs(values[k]) for k in keys)))
    for n in PARAMETER_NAMES:
        out.setdefault(n, abs(values[n]))
    return out


def inconsistency(values: Mapping[str, float], table: Table1) -> tuple[str, float, float] | None:
    """The first of the model's parameter ``values`` not reproduced by ``table`` (name, value,
    formula), or None."""
    expected = model_values(table)
    have = {n: values[n] for n in PARAMETER_NAMES}
    scales = _scales(have)
    for n in PARAMETER_NAMES:
        if abs(have[n] - expected[n]) > CONSISTENCY_RTOL * scales[n]:
            return n, have[n], expected[n]
    return None


def consistent_table(values: Mapping[str, float], mapping: Mapping[str, Any], *,
                     source: str, key: str = "benchmark") -> Table1:
    """The Table 1 of a parameter file's ``[key]`` table, after checking that the model's
    parameter ``values`` follow from it (to rounding: :data:`CONSISTENCY_RTOL`)."""
    table = table1_from_mapping(mapping, source=source, prefix=f"{key}.")
    bad = inconsistency(values, table)
    if bad is not None:
        n, found, expected = bad
        raise ParameterError(
            source, f"{PARAMETER_GROUPS[n]}.{n}",
            f"{n} = {found!r} does not follow from the [{key}] table ({expected!r} by "
            f"{FORMULAS_MODULE}): the file is not true to its source",
            f"regenerate the file from its benchmark parameters (bicycle-xval import), or remove "
            f"the [{key}] table if the model's values were changed on purpose")
    return table


# -- the reverse ------------------------------------------------------------------------------


def _upright_pitch(p: Mapping[str, float]) -> float | None:
    """beta at upright with disc contact: R_rear - a sin(beta) + b cos(beta) = R_front, with
    (a, b) the front hub from the rear hub in frame axes; the root of smallest |beta|."""
    a, b = p["xa"] + p["x5"], p["za"] + p["z5"]
    rho, k = math.hypot(a, b), p["R_front"] - p["R_rear"]
    if not abs(k) <= rho:
        return None
    phi, delta = math.atan2(a, b), math.acos(k / rho)
    roots = [math.remainder(-phi + sgn * delta, 2.0 * math.pi) for sgn in (1.0, -1.0)]
    return min(roots, key=abs)


def _blockers(p: Mapping[str, float], contact: str, beta: float | None) -> list[str]:
    out = []
    if contact != "disc":
        out.append(f"model.contact = {contact!r} (the benchmark's front wheel is a knife edge "
                   "touching the ground at its lowest point: contact 'disc')")
    if p["cv"] != 0.0:
        out.append(f"environment.cv = {p['cv']!r} kg/m (the benchmark has no drag)")
    for body, wheel in ((2, "rear"), (5, "front")):
        if p[f"I{body}zz"] != p[f"I{body}xx"]:
            out.append(f"inertia.I{body}zz = {p[f'I{body}zz']!r} differs from "
                       f"inertia.I{body}xx = {p[f'I{body}xx']!r} (Table 1's {wheel} "
                       "wheel has Izz = Ixx)")
    if beta is None:
        out.append("geometry: the front wheel cannot touch the ground with the frame upright "
                   "(no upright pitch beta)")
    elif not abs(beta) < math.pi / 2:
        out.append(f"geometry: upright pitch beta = {beta!r} rad gives no steer axis tilt in "
                   "(-pi/2, pi/2)")
    return out


def benchmark_values(values: Mapping[str, float], *, contact: str, name: str, source: str,
                     table: Table1 | None = None) -> dict[str, float]:
    """Table 1's 26 values (``BENCHMARK_NAMES`` order, SI) of the model whose 30 parameter
    ``values`` are given (with its front ``contact`` model, ``name`` and ``source`` for the
    message), if it has a benchmark counterpart (contact "disc", ``cv = 0``, wheels with
    ``Izz = Ixx``).

    ``table``, the Table 1 the model was built from (if any), is returned exactly once checked
    to reproduce ``values``; otherwise the reverse formulas of the module docstring (exact to
    rounding). Raises one :class:`ParameterError` listing every parameter without a benchmark
    counterpart otherwise.
    """
    beta = _upright_pitch(values)
    blockers = _blockers(values, contact, beta)
    if blockers:
        raise ParameterError(source, "(benchmark export)",
                             f"model {name!r} has no Meijaard et al. (2007) benchmark "
                             "counterpart: " + "; ".join(blockers),
                             "export a model with contact 'disc', cv = 0 and wheels with "
                             "Izz = Ixx (e.g. params.replace(cv=0.0).with_contact('disc'))")
    if table is not None and inconsistency(values, table) is None:
        return table.as_dict()
    p = values
    lam = -beta
    c, s = math.cos(lam), math.sin(lam)

    def point(px: float, pz: float) -> tuple[float, float]:     # frame comps -> (x, z down)
        return c * px - s * pz, -(p["R_rear"] + s * px + c * pz)

    def tensor(xx: float, zz: float, xz: float) -> tuple[float, float, float]:  # -> z down
        return (c * c * xx - 2.0 * c * s * xz + s * s * zz,
                s * s * xx + 2.0 * c * s * xz + c * c * zz,
                -(c * s * (xx - zz) + (c * c - s * s) * xz))

    xB, zB = point(p["x3"], p["z3"])
    xA, zA = point(p["xa"], p["za"])              # zA is minus the height of A
    xH, zH = point(p["xa"] + p["dx4"], p["za"] + p["dz4"])
    w, _ = point(p["xa"] + p["x5"], p["za"] + p["z5"])
    trail = xA - s * zA / c - w                   # A + t z3 reaches the ground (z3 = (-s, c))
    IBxx, IBzz, IBxz = tensor(p["I3xx"], p["I3zz"], p["I3xz"])
    IHxx, IHzz, IHxz = tensor(p["I4xx"], p["I4zz"], p["I4xz"])
    out = {
        "w": w, "c": trail, "lam": lam, "g": p["g"],
        "rR": p["R_rear"], "mR": p["m2"], "IRxx": p["I2xx"], "IRyy": p["I2yy"],
        "xB": xB, "zB": zB, "mB": p["m3"], "IBxx": IBxx, "IByy": p["I3yy"], "IBzz": IBzz,
        "IBxz": IBxz,
        "xH": xH, "zH": zH, "mH": p["m4"], "IHxx": IHxx, "IHyy": p["I4yy"], "IHzz": IHzz,
        "IHxz": IHxz,
        "rF": p["R_front"], "mF": p["m5"], "IFxx": p["I5xx"], "IFyy": p["I5yy"],
    }  # fmt: skip
    assert tuple(out) == BENCHMARK_NAMES
    return out
