"""Parameters of the reference bicycle: names, units, TOML loading and validation.

The parameter set is the flat vector shared by every builder (the generated C code reads
``p[i]`` in :data:`PARAMETER_NAMES` order). In the thesis notation (see
``docs/model.md``), with ``A3``/``A4`` the frame/fork rotation matrices::

    rG2 = rC + Ai2 [0, 0, R_rear]          rear hub = CoM of body 2 (rear wheel)
    rG3 = rG2 + A3 [x3, 0, z3]             CoM of body 3 (frame + rider)
    rA  = rG2 + A3 [xa, 0, za]             point of the steering axis      (thesis x4, z4)
    rG4 = rA + A4 [dx4, 0, dz4]            CoM of body 4 (fork/handlebar)   (thesis: 0, 0)
    rG5 = rA + A4 [x5, 0, z5]              front hub = CoM of body 5 (front wheel)

Masses ``m2..m5``; inertia tensors about each CoM in body axes, ``I3xz``/``I4xz`` being the
tensor entry ``[0, 2] = [2, 0]`` (the wheels have no product of inertia); gravity ``g`` along
-Z; drag coefficient ``cv`` with ``Qaero = -cv |vG3| H3^T vG3``. All values are SI.

File format
-----------
A parameter file is TOML with five tables::

    [model]                      # optional; every key optional
    name = "thesis"              # default: the file name without .toml
    description = "..."
    source = "bibliographic source"
    contact = "thesis"           # front contact model, one of CONTACT_MODELS; default "thesis"

    [geometry]                   # R_rear R_front x3 z3 xa za dx4 dz4 x5 z5
    x3 = { value = 0.26047, unit = "m" }
    [mass]                       # m2 m3 m4 m5
    [inertia]                    # I2xx I2yy I2zz I3xx I3yy I3zz I3xz I4xx ... I5zz
    [environment]                # g cv

    [checks]                     # optional
    triangle = "strict"          # or "warn": see below

    [benchmark]                  # optional: the Table 1 values the file was generated from
    w = 1.02                     # (reference_model/benchmark.py; all 26 names, SI, lam in rad)

The optional ``[benchmark]`` table (written by ``reference_model.benchmark``'s importer) must
agree with the model's values through the formulas of ``reference_model/benchmark.py`` (to
rounding); it makes :func:`reference_model.benchmark.to_benchmark` exact to the last digit.
``load_parameters`` also reads files in the benchmark's own format (the 26 names of Table 1 as
a flat TOML or JSON mapping, or BicycleParameters' ``<Name>Benchmark.txt``), with contact
``disc`` (the benchmark's knife-edge wheel).

Every parameter is required and is written either as ``{ value = <number>, unit = "<unit>" }``
or, for convenience, as a **plain number, which means the canonical unit** (``m2 = 2.612`` is
2.612 kg). Accepted units (converted to the canonical, first one):

* length: ``m``, ``cm``, ``mm``
* mass: ``kg``, ``g``
* inertia: ``kg*m^2``, ``kg m^2``, ``kg·m²``, ``g*cm^2``
* gravity: ``m/s^2``; drag coefficient: ``kg/m``

Validation stops at the first problem and raises one :class:`ParameterError` whose one-line
message names the file, the key (``table.key``), the problem and the fix: TOML syntax errors
(with the line), unknown tables or keys (with the closest valid name), missing keys, values that
are not finite real numbers (booleans and strings are not numbers), missing or unknown units,
non-positive masses, radii or ``g``, negative ``cv``, magnitudes outside the range of any
bicycle (:data:`PARAMETER_BOUNDS`, stated per parameter: 1e300 kg is an error naming the range;
a plausible but unusual value, e.g. the Moon's g, is a :class:`ParameterWarning` in the same
one-line format), inertia tensors that are not positive definite or whose principal moments
violate the triangle inequality, unknown contact models. ``I3zx`` is answered with the
symmetric entry ``I3xz``; a UTF-8 byte-order mark at the start of a file is accepted.
Positive definiteness is always an error; the triangle inequality is an error with
``[checks] triangle = "strict"`` (the default) and, with ``"warn"`` (or
``allow_triangle_violation=True``), a warning kept in :attr:`Parameters.warnings` (measured
inertias of real bicycles break it by a few per cent).
A :class:`Parameters` built in code is validated the same way.

Named models (:data:`NAMED_MODELS`, used by :func:`resolve_model`): ``thesis`` and
``thesis-disc`` (same values, front contact at the true lowest point of the disc), ``benchmark``
(the Meijaard et al. 2007 benchmark bicycle, disc contact; see ``reference_model/benchmark.py``).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
import os
import re
import tomllib
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from .benchmark import Table1

__all__ = [
    "BENCHMARK_FILE",
    "BODY_NAMES",
    "CONTACT_MODELS",
    "NAMED_MODELS",
    "PARAMETERS_DIR",
    "PARAMETER_DESCRIPTIONS",
    "PARAMETER_GROUPS",
    "PARAMETER_NAMES",
    "PARAMETER_UNITS",
    "PARAMETER_BOUNDS",
    "ParameterError",
    "ParameterWarning",
    "Parameters",
    "THESIS_FILE",
    "TRIANGLE_MODES",
    "TriangleInequalityError",
    "load_parameters",
    "parameters_from_mapping",
    "resolve_model",
]

# --------------------------------------------------------------------------------------------
# Names, groups, units
# --------------------------------------------------------------------------------------------

PARAMETER_NAMES: tuple[str, ...] = (
    "R_rear", "R_front",
    "x3", "z3",
    "xa", "za",
    "dx4", "dz4",
    "x5", "z5",
    "m2", "m3", "m4", "m5",
    "I2xx", "I2yy", "I2zz",
    "I3xx", "I3yy", "I3zz", "I3xz",
    "I4xx", "I4yy", "I4zz", "I4xz",
    "I5xx", "I5yy", "I5zz",
    "g",
    "cv",
)  # fmt: skip

_TABLE_MEMBERS: dict[str, tuple[str, ...]] = {
    "geometry": PARAMETER_NAMES[0:10],
    "mass": PARAMETER_NAMES[10:14],
    "inertia": PARAMETER_NAMES[14:28],
    "environment": PARAMETER_NAMES[28:30],
}

#: Parameter name -> the TOML table it lives in.
PARAMETER_GROUPS: dict[str, str] = {
    name: table for table, names in _TABLE_MEMBERS.items() for name in names
}

_TABLE_UNIT: dict[str, str] = {"geometry": "m", "mass": "kg", "inertia": "kg*m^2"}

#: Parameter name -> canonical (SI) unit.
PARAMETER_UNITS: dict[str, str] = {
    name: _TABLE_UNIT.get(PARAMETER_GROUPS[name], "")
    for name in PARAMETER_NAMES
} | {"g": "m/s^2", "cv": "kg/m"}

#: Parameter name -> English meaning with the thesis symbol.
PARAMETER_DESCRIPTIONS: dict[str, str] = {
    "R_rear": "rear wheel radius (thesis R)",
    "R_front": "front wheel radius (thesis R)",
    "x3": "frame+rider CoM from rear hub, frame x (thesis x3)",
    "z3": "frame+rider CoM from rear hub, frame z (thesis z3)",
    "xa": "steering-axis point from rear hub, frame x (thesis x4)",
    "za": "steering-axis point from rear hub, frame z (thesis z4)",
    "dx4": "fork/handlebar CoM from steering-axis point, fork x (thesis 0)",
    "dz4": "fork/handlebar CoM from steering-axis point, fork z (thesis 0)",
    "x5": "front hub from steering-axis point, fork x (thesis x5)",
    "z5": "front hub from steering-axis point, fork z (thesis z5)",
    "m2": "rear wheel mass (thesis m2)",
    "m3": "frame+rider mass (thesis m3)",
    "m4": "fork/handlebar mass (thesis m4)",
    "m5": "front wheel mass (thesis m5)",
    "I2xx": "rear wheel inertia xx (thesis I2)",
    "I2yy": "rear wheel inertia yy, spin axis (thesis I2)",
    "I2zz": "rear wheel inertia zz (thesis I2)",
    "I3xx": "frame+rider inertia xx (thesis I3)",
    "I3yy": "frame+rider inertia yy (thesis I3)",
    "I3zz": "frame+rider inertia zz (thesis I3)",
    "I3xz": "frame+rider inertia tensor entry xz (thesis I3)",
    "I4xx": "fork/handlebar inertia xx (thesis I4)",
    "I4yy": "fork/handlebar inertia yy (thesis I4)",
    "I4zz": "fork/handlebar inertia zz, steering axis (thesis I4)",
    "I4xz": "fork/handlebar inertia tensor entry xz (thesis I4)",
    "I5xx": "front wheel inertia xx (thesis I5)",
    "I5yy": "front wheel inertia yy, spin axis (thesis I5)",
    "I5zz": "front wheel inertia zz (thesis I5)",
    "g": "gravitational acceleration along -Z (thesis g)",
    "cv": "aerodynamic drag coefficient of frame+rider (thesis cv)",
}

#: Front contact models: "thesis" (rD = rG5 - R_front * z axis of A4) or "disc" (lowest point).
CONTACT_MODELS: tuple[str, ...] = ("thesis", "disc")

#: Body number -> English name (thesis numbering; body 1 is the ground).
BODY_NAMES: dict[int, str] = {
    2: "rear wheel",
    3: "frame+rider",
    4: "fork/handlebar",
    5: "front wheel",
}

_TABLES: tuple[str, ...] = ("model", *_TABLE_MEMBERS, "checks", "benchmark")
_CHECK_KEYS: tuple[str, ...] = ("triangle",)
_MODEL_KEYS: tuple[str, ...] = ("name", "description", "source", "contact")
_VALUE_KEYS: tuple[str, ...] = ("value", "unit")

# canonical unit -> {accepted spelling: factor to the canonical unit}
_UNIT_FACTORS: dict[str, dict[str, float]] = {
    "m": {"m": 1.0, "cm": 1e-2, "mm": 1e-3},
    "kg": {"kg": 1.0, "g": 1e-3},
    "kg*m^2": {"kg*m^2": 1.0, "kg m^2": 1.0, "kg·m²": 1.0, "g*cm^2": 1e-7},
    "m/s^2": {"m/s^2": 1.0},
    "kg/m": {"kg/m": 1.0},
}
_UNIT_KIND: dict[str, str] = {
    "m": "length",
    "kg": "mass",
    "kg*m^2": "moment of inertia",
    "m/s^2": "acceleration",
    "kg/m": "drag coefficient",
}

_POSITIVE: tuple[str, ...] = ("R_rear", "R_front", "m2", "m3", "m4", "m5", "g")
_NON_NEGATIVE: tuple[str, ...] = ("cv",)


@dataclass(frozen=True)
class Bounds:
    """Magnitude bounds of one parameter, SI. Outside ``[low, high]`` (applied to |value| when
    ``magnitude``) the value is no bicycle at any scale, from a toy to a cargo bike: an error.
    Outside ``[usual_low, usual_high]`` it is plausible but unusual: a warning (a typo in the
    unit is the usual cause)."""

    low: float
    high: float
    usual_low: float
    usual_high: float
    magnitude: bool = False      # bounds on |value| (signed lengths and products of inertia)
    reason: str = ""


_LENGTH = Bounds(0.0, 10.0, 0.0, 3.0, True, "a position within the bicycle")
_WHEEL_MASS = Bounds(1e-3, 1e3, 0.05, 50.0, reason="a wheel")
_MOMENT = Bounds(1e-9, 1e4, 1e-5, 100.0, reason="a moment of inertia of a bicycle part")
_PRODUCT = Bounds(0.0, 1e4, 0.0, 100.0, True, "a product of inertia of a bicycle part")

#: Parameter name -> its bounds (see `Bounds`): stated per parameter, checked on every
#: construction after the signs and before the inertia tensors.
PARAMETER_BOUNDS: dict[str, Bounds] = {
    "R_rear": Bounds(1e-3, 10.0, 0.05, 1.5, reason="a wheel radius"),
    "R_front": Bounds(1e-3, 10.0, 0.05, 1.5, reason="a wheel radius"),
    **{k: _LENGTH for k in ("x3", "z3", "xa", "za", "dx4", "dz4", "x5", "z5")},
    "m2": _WHEEL_MASS,
    "m3": Bounds(1e-3, 1e4, 1.0, 500.0, reason="frame plus rider"),
    "m4": Bounds(1e-3, 1e3, 0.05, 50.0, reason="a fork and handlebar"),
    "m5": _WHEEL_MASS,
    **{k: _MOMENT for k in ("I2xx", "I2yy", "I2zz", "I3xx", "I3yy", "I3zz", "I4xx", "I4yy",
                            "I4zz", "I5xx", "I5yy", "I5zz")},
    "I3xz": _PRODUCT,
    "I4xz": _PRODUCT,
    "g": Bounds(1e-3, 100.0, 9.7, 9.9, reason="gravity (Earth: 9.78 to 9.83 m/s^2)"),
    "cv": Bounds(0.0, 100.0, 0.0, 5.0, reason="a rider's drag, 0.5 rho Cd A ~ 0.2 to 0.6 kg/m"),
}


class ParameterWarning(UserWarning):
    """A plausible but unusual parameter value (one line, the format of ParameterError)."""

# body -> (xx, yy, zz, xz or None) parameter names
_INERTIA_KEYS: dict[int, tuple[str, str, str, str | None]] = {
    2: ("I2xx", "I2yy", "I2zz", None),
    3: ("I3xx", "I3yy", "I3zz", "I3xz"),
    4: ("I4xx", "I4yy", "I4zz", "I4xz"),
    5: ("I5xx", "I5yy", "I5zz", None),
}
_TRIANGLE_RTOL = 1e-12
#: ``[checks] triangle``: "strict" refuses a triangle-inequality violation, "warn" records it.
TRIANGLE_MODES: tuple[str, ...] = ("strict", "warn")

PARAMETERS_DIR: Path = Path(__file__).resolve().parent / "parameters"
THESIS_FILE: Path = PARAMETERS_DIR / "thesis.toml"
BENCHMARK_FILE: Path = PARAMETERS_DIR / "benchmark.toml"  # generated by reference_model/benchmark.py

#: Model name -> (parameter file, front contact model).
NAMED_MODELS: dict[str, tuple[Path, str]] = {
    "thesis": (THESIS_FILE, "thesis"),
    "thesis-disc": (THESIS_FILE, "disc"),
    "benchmark": (BENCHMARK_FILE, "disc"),   # Meijaard et al. (2007), Table 1
}

MEMORY_SOURCE = "<memory>"


# --------------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------------


class ParameterError(ValueError):
    """An invalid parameter file or value.

    The message is one line: ``<file>: <table.key>: <problem>; fix: <fix>``. The parts are
    also available as the attributes ``file``, ``key``, ``problem`` and ``fix``.
    """

    def __init__(self, file: str, key: str, problem: str, fix: str) -> None:
        self.file = str(file)
        self.key = key
        self.problem = problem
        self.fix = fix
        super().__init__(_one_line(f"{self.file}: {key}: {problem}; fix: {fix}"))

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.file, self.key, self.problem, self.fix))


class TriangleInequalityError(ParameterError):
    """An inertia tensor whose principal moments violate the triangle inequality (positive
    definite, but not a real body's). Refused in "strict" mode, a warning in "warn" mode."""


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _qualified(name: str) -> str:
    """``table.key`` of a parameter name."""
    return f"{PARAMETER_GROUPS[name]}.{name}"


def _closest(word: str, candidates: Iterable[str]) -> str | None:
    pool = list(candidates)
    lowered = {c.lower(): c for c in pool}
    match = difflib.get_close_matches(word.lower(), list(lowered), n=1, cutoff=0.6)
    return lowered[match[0]] if match else None


def _template(name: str) -> str:
    return f'{name} = {{ value = ..., unit = "{PARAMETER_UNITS[name]}" }}'


# --------------------------------------------------------------------------------------------
# Value checks (shared by the loader and Parameters.__post_init__)
# --------------------------------------------------------------------------------------------


def _is_finite_number_text(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def _as_real(file: str, key: str, value: object) -> float:
    """Return ``value`` as a finite float or raise a ParameterError naming ``key``."""
    fix = "write a finite real number, e.g. value = 1.0"
    if isinstance(value, (bool, np.bool_)):
        spelled = "true" if value else "false"
        raise ParameterError(file, key, f"value {spelled} is a boolean, not a number", fix)
    if isinstance(value, str):
        if _is_finite_number_text(value):
            fix = f"remove the quotes: value = {value.strip()}"
        raise ParameterError(file, key, f"value {value!r} is a string, not a number", fix)
    if not isinstance(value, numbers.Real):
        problem = f"value {value!r} of type {type(value).__name__} is not a real number"
        raise ParameterError(file, key, problem, fix)
    number = float(value)
    if not math.isfinite(number):
        raise ParameterError(file, key, f"value {number!r} is not a finite real number", fix)
    return number


def _check_signs(file: str, values: Mapping[str, float]) -> None:
    for name in _POSITIVE:
        if not values[name] > 0.0:
            raise ParameterError(
                file,
                _qualified(name),
                f"{name} = {values[name]!r} {PARAMETER_UNITS[name]} must be > 0 "
                f"({PARAMETER_DESCRIPTIONS[name]})",
                f"use a positive value in {PARAMETER_UNITS[name]}",
            )
    for name in _NON_NEGATIVE:
        if not values[name] >= 0.0:
            raise ParameterError(
                file,
                _qualified(name),
                f"{name} = {values[name]!r} {PARAMETER_UNITS[name]} must be >= 0 "
                f"({PARAMETER_DESCRIPTIONS[name]})",
                f"use a non-negative value in {PARAMETER_UNITS[name]} (0 disables drag)",
            )


def _check_bounds(file: str, values: Mapping[str, float]) -> None:
    """Absurd magnitudes are errors naming the range; unusual ones warnings (PARAMETER_BOUNDS)."""
    for name, b in PARAMETER_BOUNDS.items():
        value = values[name]
        if b is _MOMENT and not value > 0.0:
            continue     # a non-positive moment: _check_inertia names the tensor not positive definite
        x = abs(value) if b.magnitude else value
        unit = PARAMETER_UNITS[name]
        span = (f"|{name}| <= {b.high:g} {unit}" if b.magnitude and b.low == 0.0
                else f"{b.low:g} to {b.high:g} {unit}")
        if not b.low <= x <= b.high:
            raise ParameterError(
                file, _qualified(name),
                f"{name} = {value!r} {unit} is outside the range of {b.reason} ({span}; "
                f"{PARAMETER_DESCRIPTIONS[name]})",
                f"check the value and its unit (the range is in {unit}, after unit conversion)",
            )
        if not b.usual_low <= x <= b.usual_high:
            usual = (f"|{name}| <= {b.usual_high:g} {unit}" if b.magnitude and b.usual_low == 0.0
                     else f"{b.usual_low:g} to {b.usual_high:g} {unit}")
            warnings.warn(ParameterWarning(_one_line(
                f"{file}: {_qualified(name)}: {name} = {value!r} {unit} is unusual for "
                f"{b.reason} (usual: {usual}); fix: check the value and its unit, or ignore this "
                "warning if it is intended")), stacklevel=4)


def _principal_moments(xx: float, yy: float, zz: float, xz: float) -> tuple[float, float, float]:
    """Principal moments of ``[[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]``, one per body axis.

    y is a principal axis; the x-z block is diagonalised in closed form (exact when xz == 0).
    """
    if xz == 0.0:
        return (xx, yy, zz)
    mean = 0.5 * (xx + zz)
    radius = math.hypot(0.5 * (xx - zz), xz)
    return (mean + radius, yy, mean - radius)


def _check_inertia(file: str, body: int, values: Mapping[str, float]) -> None:
    """Positive definiteness and triangle inequality of the inertia tensor of ``body``."""
    kxx, kyy, kzz, kxz = _INERTIA_KEYS[body]
    xx, yy, zz = values[kxx], values[kyy], values[kzz]
    xz = values[kxz] if kxz is not None else 0.0
    what = f"inertia of body {body} ({BODY_NAMES[body]})"
    unit = PARAMETER_UNITS[kxx]

    bad = [k for k in (kxx, kyy, kzz) if not values[k] > 0.0]
    if bad:
        listed = ", ".join(f"{k} = {values[k]!r}" for k in bad)
        raise ParameterError(
            file,
            ", ".join(_qualified(k) for k in bad),
            f"{what} is not positive definite: {listed} {unit} (moments must be > 0)",
            f"use positive moments of inertia in {unit}",
        )
    if kxz is not None and not xx * zz - xz * xz > 0.0:
        limit = math.sqrt(xx * zz)
        raise ParameterError(
            file,
            ", ".join(_qualified(k) for k in (kxz, kxx, kzz)),
            f"{what} is not positive definite: {kxz}^2 = {xz * xz!r} >= "
            f"{kxx}*{kzz} = {xx * zz!r} ({unit})^2",
            f"make |{kxz}| < sqrt({kxx}*{kzz}) = {limit:.6g} {unit} (check its sign and units)",
        )

    moments = _principal_moments(xx, yy, zz, xz)
    tolerance = _TRIANGLE_RTOL * max(moments)
    for i, axis in enumerate("xyz"):
        others = moments[(i + 1) % 3] + moments[(i + 2) % 3]
        if others >= moments[i] - tolerance:
            continue
        if kxz is None or xz == 0.0:
            keys = [(kxx, kyy, kzz)[i]]
            detail = (
                f"{keys[0]} = {moments[i]!r} > sum of the other two moments = {others!r} {unit}"
            )
        else:
            keys = [kyy] if axis == "y" else [kxx, kzz, kxz]
            detail = (
                f"principal moments {tuple(round(m, 12) for m in moments)} {unit}: "
                f"{moments[i]!r} > sum of the other two = {others!r}"
            )
        raise TriangleInequalityError(
            file,
            ", ".join(_qualified(k) for k in keys),
            f"{what} violates the triangle inequality of principal moments "
            f"(I1 + I2 >= I3 for a real body): {detail}",
            f"check the values and units of {', '.join((kxx, kyy, kzz) + ((kxz,) if kxz else ()))}",
        )


def _check_triangle_mode(file: str, mode: object) -> None:
    if mode not in TRIANGLE_MODES:
        raise ParameterError(
            file, "checks.triangle", f"unknown triangle-inequality check mode {mode!r}",
            'use "strict" (refuse, the default) or "warn" (load and record a warning)',
        )


def _check_contact(file: str, contact: object) -> None:
    if contact not in CONTACT_MODELS:
        raise ParameterError(
            file,
            "model.contact",
            f"unknown front contact model {contact!r}",
            "use one of " + ", ".join(repr(c) for c in CONTACT_MODELS)
            + " ('thesis': rim point along the fork z axis; 'disc': lowest point of the disc)",
        )


# --------------------------------------------------------------------------------------------
# Parameters
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Parameters:
    """One validated parameter set of the reference bicycle (SI units, thesis notation).

    The float fields are exactly :data:`PARAMETER_NAMES`, in that order; ``name`` is the model
    name, ``contact`` the front contact model (one of :data:`CONTACT_MODELS`) and ``source``
    the file it was read from (``"<memory>"`` if built in code). Validation runs on every
    construction, including :meth:`replace` and :meth:`with_contact`.

    ``triangle`` is the triangle-inequality check mode (:data:`TRIANGLE_MODES`): "strict"
    raises :class:`TriangleInequalityError`, "warn" keeps one line per violating body in
    ``warnings`` (a tuple of strings, empty for a clean set; not an argument). ``benchmark``
    is the :class:`reference_model.benchmark.Table1` the values were computed from, if any
    (provenance for an exact :func:`reference_model.benchmark.to_benchmark`; not compared;
    :meth:`replace` drops it when a parameter value changes).
    """

    R_rear: float
    R_front: float
    x3: float
    z3: float
    xa: float
    za: float
    dx4: float
    dz4: float
    x5: float
    z5: float
    m2: float
    m3: float
    m4: float
    m5: float
    I2xx: float
    I2yy: float
    I2zz: float
    I3xx: float
    I3yy: float
    I3zz: float
    I3xz: float
    I4xx: float
    I4yy: float
    I4zz: float
    I4xz: float
    I5xx: float
    I5yy: float
    I5zz: float
    g: float
    cv: float
    name: str = "custom"
    contact: str = "thesis"
    source: str = MEMORY_SOURCE
    triangle: str = "strict"
    benchmark: Table1 | None = field(default=None, compare=False, repr=False)
    warnings: tuple[str, ...] = field(init=False, default=(), compare=False)

    def __post_init__(self) -> None:
        source = self.source
        if isinstance(source, os.PathLike):
            source = os.fspath(source)
            object.__setattr__(self, "source", source)
        if not isinstance(source, str):
            raise ParameterError(
                repr(source), "source", "source must be a string", "pass a file path or '<memory>'"
            )
        if not isinstance(self.name, str):
            raise ParameterError(
                source, "model.name", f"name {self.name!r} is not a string", "use a string name"
            )
        values = {n: _as_real(source, _qualified(n), getattr(self, n)) for n in PARAMETER_NAMES}
        for n, v in values.items():
            object.__setattr__(self, n, v)
        _check_signs(source, values)
        _check_bounds(source, values)
        _check_triangle_mode(source, self.triangle)
        warned: list[str] = []
        for body in _INERTIA_KEYS:
            try:
                _check_inertia(source, body, values)
            except TriangleInequalityError as exc:
                if self.triangle == "strict":
                    raise TriangleInequalityError(
                        exc.file, exc.key, exc.problem,
                        f"{exc.fix}; if the values are measured and right, allow it with "
                        '[checks] triangle = "warn" (or allow_triangle_violation=True)',
                    ) from None
                warned.append(f"{exc.key}: {exc.problem} (allowed: triangle = \"warn\")")
        object.__setattr__(self, "warnings", tuple(warned))
        _check_contact(source, self.contact)

    # -- conversions ---------------------------------------------------------------------

    def vector(self) -> np.ndarray:
        """The flat parameter vector ``p`` (float64, :data:`PARAMETER_NAMES` order)."""
        return np.array([getattr(self, n) for n in PARAMETER_NAMES], dtype=np.float64)

    @classmethod
    def from_vector(
        cls,
        p: Iterable[float],
        *,
        name: str = "custom",
        contact: str = "thesis",
        source: str = MEMORY_SOURCE,
        triangle: str = "strict",
    ) -> Parameters:
        """Inverse of :meth:`vector`."""
        values = [float(x) for x in np.asarray(p, dtype=np.float64).ravel()]
        if len(values) != len(PARAMETER_NAMES):
            raise ParameterError(
                source,
                "(vector)",
                f"parameter vector has {len(values)} entries, expected {len(PARAMETER_NAMES)}",
                "pass one value per name in PARAMETER_NAMES, in that order",
            )
        return cls(**dict(zip(PARAMETER_NAMES, values)), name=name, contact=contact, source=source,
                   triangle=triangle)

    @classmethod
    def from_benchmark(
        cls,
        mapping: Mapping[str, Any],
        *,
        name: str = "custom",
        source: str = MEMORY_SOURCE,
        allow_triangle_violation: bool = False,
    ) -> Parameters:
        """The model from Meijaard et al. (2007) Table 1 names (``w, c, lam, g, rR, ...``: all
        26, any real numbers, NumPy scalars included), front contact "disc" (the benchmark's
        knife-edge wheel), the formulas of :mod:`reference_model.benchmark`. Bad input raises
        one :class:`ParameterError` naming the benchmark key."""
        from .benchmark import parameters_from_benchmark  # benchmark.py imports this module

        return parameters_from_benchmark(
            mapping, name=name, source=source, allow_triangle_violation=allow_triangle_violation
        )

    def as_dict(self) -> dict[str, Any]:
        """All init fields: the parameters in :data:`PARAMETER_NAMES` order, then name, contact,
        source, triangle, benchmark. ``Parameters(**p.as_dict()) == p``."""
        out: dict[str, Any] = {n: getattr(self, n) for n in PARAMETER_NAMES}
        out.update(name=self.name, contact=self.contact, source=self.source,
                   triangle=self.triangle, benchmark=self.benchmark)
        return out

    # -- derived copies ------------------------------------------------------------------

    def replace(self, **changes: Any) -> Parameters:
        """A copy with some fields changed, validated again."""
        fields = {f.name for f in dataclasses.fields(self) if f.init}
        for key in changes:
            if key not in fields:
                hint = _closest(key, fields)
                raise ParameterError(
                    self.source,
                    _qualified(key) if key in PARAMETER_GROUPS else key,
                    f"{key!r} is not a field of Parameters",
                    f"use {hint!r}" if hint else "use a name from PARAMETER_NAMES, or name/contact/source",
                )
        if "benchmark" not in changes and any(n in changes for n in PARAMETER_NAMES):
            changes["benchmark"] = None      # the Table 1 provenance no longer holds
        return dataclasses.replace(self, **changes)

    def with_contact(self, contact: str) -> Parameters:
        """The same parameters with another front contact model (see :data:`CONTACT_MODELS`)."""
        return self.replace(contact=contact)

    # -- derived quantities --------------------------------------------------------------

    def inertia(self, body: int) -> np.ndarray:
        """Inertia tensor (3x3, symmetric, kg*m^2) of body 2..5 about its CoM in body axes.

        ``xz`` is the tensor entry ``[0, 2] = [2, 0]`` (thesis I3, I4); the wheels have none.
        """
        if isinstance(body, bool) or body not in _INERTIA_KEYS:
            raise ValueError(
                f"body must be one of {tuple(_INERTIA_KEYS)} "
                f"({', '.join(f'{b}: {n}' for b, n in BODY_NAMES.items())}), got {body!r}"
            )
        kxx, kyy, kzz, kxz = _INERTIA_KEYS[body]
        xz = getattr(self, kxz) if kxz is not None else 0.0
        return np.array(
            [
                [getattr(self, kxx), 0.0, xz],
                [0.0, getattr(self, kyy), 0.0],
                [xz, 0.0, getattr(self, kzz)],
            ],
            dtype=np.float64,
        )


# --------------------------------------------------------------------------------------------
# Loading
# --------------------------------------------------------------------------------------------

_TOML_LOCATION = re.compile(r"\s*\(at line (\d+), column (\d+)\)\s*$")


def _syntax_error(file: str, text: str, exc: tomllib.TOMLDecodeError) -> ParameterError:
    message = str(exc)
    located = _TOML_LOCATION.search(message)
    if located is None:
        return ParameterError(
            file, "(end of file)", f"invalid TOML: {message}", "correct the TOML syntax"
        )
    line, column = int(located.group(1)), int(located.group(2))
    lines = text.splitlines()
    source_line = lines[line - 1].strip() if 0 < line <= len(lines) else ""
    return ParameterError(
        file,
        f"line {line}",
        f"invalid TOML at line {line}, column {column}: {message[: located.start()]}: "
        f"{source_line!r}",
        'correct the TOML syntax on that line, e.g. x3 = { value = 0.26047, unit = "m" }',
    )


_TENSOR_ENTRY = re.compile(r"^I([2-5])([xyz])([xyz])$")


def _tensor_entry_fix(table: str, key: str) -> str | None:
    """The fix for an inertia-tensor entry spelled another way: I3zx is the symmetric entry
    I3xz; products the model has no parameter for (wheels: none; frame, fork: only xz)."""
    m = _TENSOR_ENTRY.match(key)
    if table != "inertia" or m is None or m.group(2) == m.group(3):
        return None
    body, a, b = m.groups()
    swapped = f"I{body}{b}{a}"
    if swapped in PARAMETER_GROUPS:
        return (f"the tensor is symmetric: {key} is the entry {swapped}; rename it to "
                f"inertia.{swapped}")
    has = [k for k in _INERTIA_KEYS[int(body)] if k is not None and k[2] != k[3]]
    if has:
        return (f"remove it: body {body} ({BODY_NAMES[int(body)]}) is symmetric about its x-z "
                f"plane, so {key} = 0; its only product of inertia is inertia.{has[0]}")
    return (f"remove it: body {body} ({BODY_NAMES[int(body)]}) is an axisymmetric wheel with "
            "no product of inertia")


def _unknown_key_error(file: str, table: str, key: str) -> ParameterError:
    local = _TABLE_MEMBERS[table]
    hint = _closest(key, local)
    tensor_fix = _tensor_entry_fix(table, key)
    if tensor_fix is not None:
        fix = tensor_fix
    elif hint is not None:
        fix = f"did you mean {hint!r}? rename it to {table}.{hint}"
    else:
        elsewhere = _closest(key, PARAMETER_NAMES)
        if elsewhere is not None:
            fix = f"did you mean {_qualified(elsewhere)!r}? rename it and put it in [{PARAMETER_GROUPS[elsewhere]}]"
        else:
            fix = f"remove it; valid keys in [{table}] are {', '.join(local)}"
    return ParameterError(file, f"{table}.{key}", f"unknown key {key!r} in [{table}]", fix)


def _check_structure(file: str, data: Mapping[str, Any]) -> None:
    """Tables and keys: nothing unknown, nothing misplaced, nothing missing."""
    for key, value in data.items():
        if key in _TABLES:
            if not isinstance(value, dict):
                raise ParameterError(
                    file, key, f"{key!r} must be a table, got {type(value).__name__}",
                    f"write it as a [{key}] table",
                )
        elif key in PARAMETER_GROUPS:
            raise ParameterError(
                file, key, f"parameter {key!r} is outside any table",
                f"put it under [{PARAMETER_GROUPS[key]}]",
            )
        else:
            hint = _closest(key, _TABLES)
            fix = f"did you mean [{hint}]?" if hint else "remove it"
            raise ParameterError(
                file, key, f"unknown table [{key}]",
                f"{fix} valid tables are {', '.join(_TABLES)}",
            )
    for key in data.get("checks", {}):
        if key not in _CHECK_KEYS:
            raise ParameterError(
                file, f"checks.{key}", f"unknown key {key!r} in [checks]",
                f"remove it; valid keys in [checks] are {', '.join(_CHECK_KEYS)}",
            )
    for key in data.get("model", {}):
        if key not in _MODEL_KEYS:
            hint = _closest(key, _MODEL_KEYS)
            raise ParameterError(
                file, f"model.{key}", f"unknown key {key!r} in [model]",
                (f"did you mean {hint!r}? " if hint else "remove it; ")
                + f"valid keys in [model] are {', '.join(_MODEL_KEYS)}",
            )
    for table in _TABLE_MEMBERS:
        for key in data.get(table, {}):
            home = PARAMETER_GROUPS.get(key)
            if home == table:
                continue
            if home is not None:
                raise ParameterError(
                    file, f"{table}.{key}", f"{key!r} belongs in [{home}], not in [{table}]",
                    f"move it to [{home}]",
                )
            raise _unknown_key_error(file, table, key)
    for table, names in _TABLE_MEMBERS.items():
        if table not in data:
            raise ParameterError(
                file, table, f"table [{table}] is missing",
                f"add a [{table}] table with {', '.join(names)}",
            )
        for name in names:
            if name not in data[table]:
                raise ParameterError(
                    file, _qualified(name),
                    f"required key {name!r} is missing ({PARAMETER_DESCRIPTIONS[name]})",
                    f"add {_template(name)} to [{table}]",
                )


def _read_model_table(file: str, model: Mapping[str, Any]) -> dict[str, str]:
    for key, value in model.items():
        if not isinstance(value, str):
            raise ParameterError(
                file, f"model.{key}", f"value {value!r} is not a string",
                f'write it in quotes, e.g. {key} = "..."',
            )
    return dict(model)


def _read_value(file: str, name: str, raw: object) -> float:
    """One parameter entry, ``{ value, unit }`` or a plain number, in canonical units."""
    key = _qualified(name)
    canonical = PARAMETER_UNITS[name]
    if not isinstance(raw, dict):
        return _as_real(file, key, raw)
    for field in raw:
        if field not in _VALUE_KEYS:
            hint = _closest(field, _VALUE_KEYS)
            raise ParameterError(
                file, key, f"unknown field {field!r} in the entry of {name}",
                (f"did you mean {hint!r}? " if hint else "")
                + f"write {_template(name)}",
            )
    if "value" not in raw:
        raise ParameterError(
            file, key, "the entry has no 'value'", f"write {_template(name)}"
        )
    value = _as_real(file, key, raw["value"])
    if "unit" not in raw:
        raise ParameterError(
            file, key, "unit missing",
            f'add unit = "{canonical}", or write a plain number, which means {canonical}',
        )
    unit = raw["unit"]
    accepted = _UNIT_FACTORS[canonical]
    factor = accepted.get(unit.strip()) if isinstance(unit, str) else None
    if factor is None:
        raise ParameterError(
            file, key,
            f"unit {unit!r} is not an accepted {_UNIT_KIND[canonical]} unit",
            "use one of " + ", ".join(repr(u) for u in accepted),
        )
    return value * factor


def parameters_from_mapping(
    data: Mapping[str, Any],
    *,
    source: str = MEMORY_SOURCE,
    contact: str | None = None,
    name: str | None = None,
    default_name: str = "custom",
    allow_triangle_violation: bool = False,
) -> Parameters:
    """Validate an already-parsed parameter document (the TOML layout as nested dicts).

    ``contact`` and ``name``, when given, override ``[model]``; without either, the name is
    ``[model].name`` or ``default_name`` and the contact ``[model].contact`` or "thesis".
    ``allow_triangle_violation=True`` overrides ``[checks] triangle`` with "warn".
    """
    file = str(source)
    _check_structure(file, data)
    model = _read_model_table(file, data.get("model", {}))
    triangle = data.get("checks", {}).get("triangle", "strict")
    _check_triangle_mode(file, triangle)
    if allow_triangle_violation:
        triangle = "warn"
    values = {
        n: _read_value(file, n, data[PARAMETER_GROUPS[n]][n]) for n in PARAMETER_NAMES
    }
    params = Parameters(
        **values,
        name=name if name is not None else model.get("name", default_name),
        contact=contact if contact is not None else model.get("contact", "thesis"),
        source=file,
        triangle=triangle,
    )
    if "benchmark" in data:
        from .benchmark import attach_benchmark  # benchmark.py imports this module

        params = attach_benchmark(params, data["benchmark"], key="benchmark")
    return params


_BENCHMARK_SUFFIXES = (".txt", ".json")


def _is_benchmark_layout(data: Mapping[str, Any]) -> bool:
    """A flat mapping of Table 1 names (not the model's tables)."""
    from .benchmark import BENCHMARK_NAMES

    if any(k in BENCHMARK_NAMES and k not in PARAMETER_GROUPS for k in data):
        return True
    return bool(data) and not any(isinstance(v, dict) for v in data.values()) and not any(
        k in PARAMETER_GROUPS for k in data
    )


def load_parameters(
    path: str | os.PathLike[str],
    contact: str | None = None,
    name: str | None = None,
    *,
    allow_triangle_violation: bool = False,
) -> Parameters:
    """Read and validate a TOML parameter file (format in the module docstring), or a file of
    Meijaard et al. (2007) benchmark parameters (``.txt`` in BicycleParameters' format,
    ``.json``, or a flat ``.toml`` of Table 1 names; see ``reference_model.benchmark_files``).

    ``contact`` and ``name`` override the file's ``[model]`` entries (a benchmark file has
    contact "disc" and its file name without extension as name).
    ``allow_triangle_violation=True`` turns the triangle-inequality check into a warning.
    Every problem raises one :class:`ParameterError`.
    """
    file = os.fspath(path)
    named = ", ".join(NAMED_MODELS)
    try:
        raw = Path(file).read_bytes()
    except FileNotFoundError:
        raise ParameterError(
            file, "(file)", "no such file",
            f"give the path of an existing .toml parameter file (named models: {named})",
        ) from None
    except OSError as exc:
        raise ParameterError(
            file, "(file)", f"cannot read the file: {exc.strerror or exc}",
            "give the path of a readable .toml parameter file",
        ) from None
    try:
        text = raw.decode("utf-8").removeprefix("\ufeff")   # a UTF-8 BOM (some editors) is accepted
    except UnicodeDecodeError as exc:
        raise ParameterError(
            file, "(file)", f"not UTF-8 text (byte {exc.start})", "save the file as UTF-8"
        ) from None
    if Path(file).suffix.lower() in _BENCHMARK_SUFFIXES:
        from .benchmark_files import parse_benchmark_text

        data = parse_benchmark_text(text, file).values
    else:
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise _syntax_error(file, text, exc) from None
    if Path(file).suffix.lower() in _BENCHMARK_SUFFIXES or _is_benchmark_layout(data):
        from .benchmark import parameters_from_benchmark

        params = parameters_from_benchmark(
            data, name=name if name is not None else Path(file).stem, source=file,
            allow_triangle_violation=allow_triangle_violation,
        )
        return params if contact is None else params.with_contact(contact)
    return parameters_from_mapping(
        data, source=file, contact=contact, name=name, default_name=Path(file).stem,
        allow_triangle_violation=allow_triangle_violation,
    )


def resolve_model(
    name_or_path: str | os.PathLike[str] | Parameters, *, allow_triangle_violation: bool = False
) -> Parameters:
    """A named model from :data:`NAMED_MODELS`, or the parameters in a file (a .toml parameter
    file, or benchmark parameters in .txt/.json/.toml: see :func:`load_parameters`).

    A :class:`Parameters` instance is returned unchanged.
    """
    if isinstance(name_or_path, Parameters):
        return name_or_path
    if isinstance(name_or_path, str) and name_or_path in NAMED_MODELS:
        path, contact = NAMED_MODELS[name_or_path]
        return load_parameters(path, contact=contact, name=name_or_path,
                               allow_triangle_violation=allow_triangle_violation)
    candidate = Path(name_or_path)
    if candidate.suffix.lower() in (".toml", *_BENCHMARK_SUFFIXES) or candidate.is_file():
        return load_parameters(candidate, allow_triangle_violation=allow_triangle_violation)
    text = os.fspath(name_or_path)
    hint = _closest(text, NAMED_MODELS)
    raise ParameterError(
        text,
        "model",
        f"unknown model {text!r}" + (f" (did you mean {hint!r}?)" if hint else ""),
        f"use a named model ({', '.join(NAMED_MODELS)}) or a path to a .toml parameter file",
    )
