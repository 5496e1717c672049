"""The reference bicycle's parameters: their names, units, meanings and bounds, and the
checks every parameter set passes (the schema and its validation; no file, no dataclass).

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

Every problem raises one :class:`ParameterError` whose one-line message names the file, the
key (``table.key``), the problem and the fix. The value checks here (run on every
:class:`reference_model.parameters.values.Parameters`, however it was made): values that are
not finite real numbers (booleans and strings are not numbers), non-positive masses, radii or
``g``, negative ``cv``, magnitudes outside the range of any bicycle (:data:`PARAMETER_BOUNDS`,
stated per parameter: 1e300 kg is an error naming the range; a plausible but unusual value,
e.g. the Moon's g, is a :class:`ParameterWarning` in the same one-line format), inertia tensors
that are not positive definite or whose principal moments violate the triangle inequality
(:class:`TriangleInequalityError`; an error or a warning by :data:`TRIANGLE_MODES`), unknown
contact models. The checks of a file's layout (tables, keys, units) are the file format's
(``reference_model.parameters.model_file``).
"""

from __future__ import annotations

import difflib
import math
import numbers
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "BODY_NAMES", "Bounds", "CONTACT_MODELS", "INERTIA_KEYS", "MEMORY_SOURCE",
    "PARAMETER_BOUNDS", "PARAMETER_DESCRIPTIONS", "PARAMETER_GROUPS", "PARAMETER_NAMES",
    "PARAMETER_UNITS", "ParameterError", "ParameterWarning", "TABLE_MEMBERS", "TRIANGLE_MODES",
    "TRIANGLE_RTOL", "TriangleInequalityError", "as_real", "check_bounds", "check_contact",
    "check_inertia", "check_signs", "check_triangle_mode", "closest", "one_line",
    "principal_moments", "qualified",
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

#: TOML table -> the parameters it holds (:data:`PARAMETER_NAMES` order).
TABLE_MEMBERS: dict[str, tuple[str, ...]] = {
    "geometry": PARAMETER_NAMES[0:10],
    "mass": PARAMETER_NAMES[10:14],
    "inertia": PARAMETER_NAMES[14:28],
    "environment": PARAMETER_NAMES[28:30],
}

#: Parameter name -> the TOML table it lives in.
PARAMETER_GROUPS: dict[str, str] = {
    name: table for table, names in TABLE_MEMBERS.items() for name in names
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

#: Body -> (xx, yy, zz, xz or None) parameter names of its inertia tensor.
INERTIA_KEYS: dict[int, tuple[str, str, str, str | None]] = {
    2: ("I2xx", "I2yy", "I2zz", None),
    3: ("I3xx", "I3yy", "I3zz", "I3xz"),
    4: ("I4xx", "I4yy", "I4zz", "I4xz"),
    5: ("I5xx", "I5yy", "I5zz", None),
}
#: Relative tolerance of the triangle inequality (of the largest moment): rounding, not physics.
TRIANGLE_RTOL = 1e-12
#: ``[checks] triangle``: "strict" refuses a triangle-inequality violation, "warn" records it.
TRIANGLE_MODES: tuple[str, ...] = ("strict", "warn")

#: The source named by a parameter set built in code (not read from a file).
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
        super().__init__(one_line(f"{self.file}: {key}: {problem}; fix: {fix}"))

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.file, self.key, self.problem, self.fix))


class TriangleInequalityError(ParameterError):
    """An inertia tensor whose principal moments violate the triangle inequality (positive
    definite, but not a real body's). Refused in "strict" mode, a warning in "warn" mode."""


def one_line(text: str) -> str:
    return " ".join(text.split())


def qualified(name: str) -> str:
    """``table.key`` of a parameter name."""
    return f"{PARAMETER_GROUPS[name]}.{name}"


def closest(word: str, candidates: Iterable[str]) -> str | None:
    pool = list(candidates)
    lowered = {c.lower(): c for c in pool}
    match = difflib.get_close_matches(word.lower(), list(lowered), n=1, cutoff=0.6)
    return lowered[match[0]] if match else None


# --------------------------------------------------------------------------------------------
# Value checks (shared by the loader and Parameters.__post_init__)
# --------------------------------------------------------------------------------------------


def _is_finite_number_text(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def as_real(file: str, key: str, value: object, *, python_literals: bool = False) -> float:
    """Return ``value`` as a finite float or raise a ParameterError naming ``key``.

    The message speaks the input's language: a parameter file's TOML by default (``value
    true``, fix ``value = 1.0``), or with ``python_literals`` a mapping of numbers given in
    code or a Table 1 file (``value True``, fix ``1.02``; ``reference_model.parameters
    .benchmark``)."""
    example = "1.02" if python_literals else "value = 1.0"
    fix = f"write a finite real number, e.g. {example}"
    if isinstance(value, (bool, np.bool_)):
        spelled = repr(value) if python_literals else ("true" if value else "false")
        raise ParameterError(file, key, f"value {spelled} is a boolean, not a number", fix)
    if isinstance(value, str):
        if _is_finite_number_text(value):
            fix = ("remove the quotes" if python_literals
                   else f"remove the quotes: value = {value.strip()}")
        raise ParameterError(file, key, f"value {value!r} is a string, not a number", fix)
    if not isinstance(value, numbers.Real):
        problem = f"value {value!r} of type {type(value).__name__} is not a real number"
        raise ParameterError(file, key, problem, fix)
    number = float(value)
    if not math.isfinite(number):
        raise ParameterError(file, key, f"value {number!r} is not a finite real number", fix)
    return number


def check_signs(file: str, values: Mapping[str, float]) -> None:
    for name in _POSITIVE:
        if not values[name] > 0.0:
            raise ParameterError(
                file,
                qualified(name),
                f"{name} = {values[name]!r} {PARAMETER_UNITS[name]} must be > 0 "
                f"({PARAMETER_DESCRIPTIONS[name]})",
                f"use a positive value in {PARAMETER_UNITS[name]}",
            )
    for name in _NON_NEGATIVE:
        if not values[name] >= 0.0:
            raise ParameterError(
                file,
                qualified(name),
                f"{name} = {values[name]!r} {PARAMETER_UNITS[name]} must be >= 0 "
                f"({PARAMETER_DESCRIPTIONS[name]})",
                f"use a non-negative value in {PARAMETER_UNITS[name]} (0 disables drag)",
            )


def check_bounds(file: str, values: Mapping[str, float]) -> None:
    """Absurd magnitudes are errors naming the range; unusual ones warnings (PARAMETER_BOUNDS)."""
    for name, b in PARAMETER_BOUNDS.items():
        value = values[name]
        if b is _MOMENT and not value > 0.0:
            continue     # a non-positive moment: check_inertia names the tensor not positive definite
        x = abs(value) if b.magnitude else value
        unit = PARAMETER_UNITS[name]
        span = (f"|{name}| <= {b.high:g} {unit}" if b.magnitude and b.low == 0.0
                else f"{b.low:g} to {b.high:g} {unit}")
        if not b.low <= x <= b.high:
            raise ParameterError(
                file, qualified(name),
                f"{name} = {value!r} {unit} is outside the range of {b.reason} ({span}; "
                f"{PARAMETER_DESCRIPTIONS[name]})",
                f"check the value and its unit (the range is in {unit}, after unit conversion)",
            )
        if not b.usual_low <= x <= b.usual_high:
            usual = (f"|{name}| <= {b.usual_high:g} {unit}" if b.magnitude and b.usual_low == 0.0
                     else f"{b.usual_low:g} to {b.usual_high:g} {unit}")
            warnings.warn(ParameterWarning(one_line(
                f"{file}: {qualified(name)}: {name} = {value!r} {unit} is unusual for "
                f"{b.reason} (usual: {usual}); fix: check the value and its unit, or ignore this "
                "warning if it is intended")), stacklevel=4)


def principal_moments(xx: float, yy: float, zz: float, xz: float) -> tuple[float, float, float]:
    """Principal moments of ``[[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]``, one per body axis.

    y is a principal axis; the x-z block is diagonalised in closed form (exact when xz == 0).
    """
    if xz == 0.0:
        return (xx, yy, zz)
    mean = 0.5 * (xx + zz)
    radius = math.hypot(0.5 * (xx - zz), xz)
    return (mean + radius, yy, mean - radius)


def check_inertia(file: str, body: int, values: Mapping[str, float]) -> None:
    """Positive definiteness and triangle inequality of the inertia tensor of ``body``."""
    kxx, kyy, kzz, kxz = INERTIA_KEYS[body]
    xx, yy, zz = values[kxx], values[kyy], values[kzz]
    xz = values[kxz] if kxz is not None else 0.0
    what = f"inertia of body {body} ({BODY_NAMES[body]})"
    unit = PARAMETER_UNITS[kxx]

    bad = [k for k in (kxx, kyy, kzz) if not values[k] > 0.0]
    if bad:
        listed = ", ".join(f"{k} = {values[k]!r}" for k in bad)
        raise ParameterError(
            file,
            ", ".join(qualified(k) for k in bad),
            f"{what} is not positive definite: {listed} {unit} (moments must be > 0)",
            f"use positive moments of inertia in {unit}",
        )
    if kxz is not None and not xx * zz - xz * xz > 0.0:
        limit = math.sqrt(xx * zz)
        raise ParameterError(
            file,
            ", ".join(qualified(k) for k in (kxz, kxx, kzz)),
            f"{what} is not positive definite: {kxz}^2 = {xz * xz!r} >= "
            f"{kxx}*{kzz} = {xx * zz!r} ({unit})^2",
            f"make |{kxz}| < sqrt({kxx}*{kzz}) = {limit:.6g} {unit} (check its sign and units)",
        )

    moments = principal_moments(xx, yy, zz, xz)
    tolerance = TRIANGLE_RTOL * max(moments)
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
            ", ".join(qualified(k) for k in keys),
            f"{what} violates the triangle inequality of principal moments "
            f"(I1 + I2 >= I3 for a real body): {detail}",
            f"check the values and units of {', '.join((kxx, kyy, kzz) + ((kxz,) if kxz else ()))}",
        )


def check_triangle_mode(file: str, mode: object) -> None:
    if mode not in TRIANGLE_MODES:
        raise ParameterError(
            file, "checks.triangle", f"unknown triangle-inequality check mode {mode!r}",
            'use "strict" (refuse, the default) or "warn" (load and record a warning)',
        )


def check_contact(file: str, contact: object) -> None:
    if contact not in CONTACT_MODELS:
        raise ParameterError(
            file,
            "model.contact",
            f"unknown front contact model {contact!r}",
            "use one of " + ", ".join(repr(c) for c in CONTACT_MODELS)
            + " ('thesis': rim point along the fork z axis; 'disc': lowest point of the disc)",
        )
