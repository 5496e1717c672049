"""The reference model's parameter file: reading its TOML layout (:func:`parameters_from_mapping`)
and writing it from Table 1 values (:func:`toml_text`, with the formulas as comments).

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
    w = 1.02                     # (parameters/benchmark.py; all 26 names, SI, lam in rad)

The optional ``[benchmark]`` table (written by :func:`toml_text`, the importer's writer) must
agree with the model's values through the formulas of ``reference_model/parameters/benchmark.py``
(to rounding); it makes :func:`reference_model.parameters.values.to_benchmark` exact to the last
digit. ``reference_model.parameters.loading.load_parameters`` also reads files in the
benchmark's own format (the 26 names of Table 1 as a flat TOML or JSON mapping, or
BicycleParameters' ``<Name>Benchmark.txt``: ``reference_model.parameters.benchmark_files``),
with contact ``disc`` (the benchmark's knife-edge wheel).

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
"""

from __future__ import annotations

import json
import re
import tomllib
from collections.abc import Mapping
from typing import Any

from .benchmark import BENCHMARK_DESCRIPTIONS, FORMULAS_MODULE, Table1, model_values
from .schema import (BODY_NAMES, INERTIA_KEYS, MEMORY_SOURCE, PARAMETER_DESCRIPTIONS,
                     PARAMETER_GROUPS, PARAMETER_NAMES, PARAMETER_UNITS, TABLE_MEMBERS,
                     ParameterError, as_real, check_triangle_mode, closest, qualified)
from .values import Parameters, attach_benchmark, parameters_from_benchmark

__all__ = ["float_text", "parameters_from_mapping", "syntax_error", "toml_string", "toml_text"]

# --------------------------------------------------------------------------------------------
# The layout: tables, keys, entries, units
# --------------------------------------------------------------------------------------------

_TABLES: tuple[str, ...] = ("model", *TABLE_MEMBERS, "checks", "benchmark")
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

def _template(name: str) -> str:
    return f'{name} = {{ value = ..., unit = "{PARAMETER_UNITS[name]}" }}'



# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------

_TOML_LOCATION = re.compile(r"\s*\(at line (\d+), column (\d+)\)\s*$")


def syntax_error(file: str, text: str, exc: tomllib.TOMLDecodeError) -> ParameterError:
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
    has = [k for k in INERTIA_KEYS[int(body)] if k is not None and k[2] != k[3]]
    if has:
        return (f"remove it: body {body} ({BODY_NAMES[int(body)]}) is symmetric about its x-z "
                f"plane, so {key} = 0; its only product of inertia is inertia.{has[0]}")
    return (f"remove it: body {body} ({BODY_NAMES[int(body)]}) is an axisymmetric wheel with "
            "no product of inertia")


def _unknown_key_error(file: str, table: str, key: str) -> ParameterError:
    local = TABLE_MEMBERS[table]
    hint = closest(key, local)
    tensor_fix = _tensor_entry_fix(table, key)
    if tensor_fix is not None:
        fix = tensor_fix
    elif hint is not None:
        fix = f"did you mean {hint!r}? rename it to {table}.{hint}"
    else:
        elsewhere = closest(key, PARAMETER_NAMES)
        if elsewhere is not None:
            fix = f"did you mean {qualified(elsewhere)!r}? rename it and put it in [{PARAMETER_GROUPS[elsewhere]}]"
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
            hint = closest(key, _TABLES)
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
            hint = closest(key, _MODEL_KEYS)
            raise ParameterError(
                file, f"model.{key}", f"unknown key {key!r} in [model]",
                (f"did you mean {hint!r}? " if hint else "remove it; ")
                + f"valid keys in [model] are {', '.join(_MODEL_KEYS)}",
            )
    for table in TABLE_MEMBERS:
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
    for table, names in TABLE_MEMBERS.items():
        if table not in data:
            raise ParameterError(
                file, table, f"table [{table}] is missing",
                f"add a [{table}] table with {', '.join(names)}",
            )
        for name in names:
            if name not in data[table]:
                raise ParameterError(
                    file, qualified(name),
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
    key = qualified(name)
    canonical = PARAMETER_UNITS[name]
    if not isinstance(raw, dict):
        return as_real(file, key, raw)
    for field in raw:
        if field not in _VALUE_KEYS:
            hint = closest(field, _VALUE_KEYS)
            raise ParameterError(
                file, key, f"unknown field {field!r} in the entry of {name}",
                (f"did you mean {hint!r}? " if hint else "")
                + f"write {_template(name)}",
            )
    if "value" not in raw:
        raise ParameterError(
            file, key, "the entry has no 'value'", f"write {_template(name)}"
        )
    value = as_real(file, key, raw["value"])
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
    check_triangle_mode(file, triangle)
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
        params = attach_benchmark(params, data["benchmark"], key="benchmark")
    return params


# --------------------------------------------------------------------------------------------
# Writing (from Table 1 values)
# --------------------------------------------------------------------------------------------

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


def toml_string(text: str) -> str:
    """A TOML basic string (JSON's escapes are TOML's)."""
    return json.dumps(str(text), ensure_ascii=False)


def float_text(value: float) -> str:
    """repr of the Python float: the shortest decimal that reads back as the same double."""
    return repr(float(value))


def toml_text(
    t: Table1 | Mapping[str, Any],
    *,
    name: str,
    source: str,
    description: str | None = None,
    generator: str = "`python -m reference_model.benchmark --write`",
    uncertainties: Mapping[str, float] | None = None,
    allow_triangle_violation: bool = False,
    notes: tuple[str, ...] = (),
) -> str:
    """The parameter file of the bicycle whose Table 1 values are ``t``: the model's values
    with the formulas as comments, contact "disc" written out, ``[checks] triangle = "warn"``
    if ``allow_triangle_violation``, and ``t`` itself in ``[benchmark]`` (with ``uncertainties``,
    dropped on import, as comments; ``notes``, what else the source said, too). ``name`` and ``source`` (a bibliographic source or the
    path of the file imported) are required (a file never takes another bicycle's name) and
    go into ``[model]``; nothing depends on the date.
    Raises like :func:`parameters_from_benchmark` for values it cannot load back."""
    params = parameters_from_benchmark(t, name=name, source=source,
                                       allow_triangle_violation=allow_triangle_violation)
    t = params.benchmark
    values = model_values(t)
    uncertainties = dict(uncertainties or {})
    unknown = [k for k in uncertainties if k not in BENCHMARK_DESCRIPTIONS]
    if unknown:
        raise ValueError(f"uncertainties for unknown benchmark names: {', '.join(unknown)}")
    if description is None:
        description = (f"bicycle given by Meijaard et al. (2007) benchmark parameters, from "
                       f"{source}; knife-edge front wheel (contact disc), no drag")
    lines = [
        f"# {name}: a bicycle given by Meijaard et al. (2007) benchmark parameters (Table 1's 26",
        "# names), in the reference model's parametrization.",
        f"# GENERATED by {generator}",
        f"# from: {source}",
        "# Formulas (Table 1 names -> the model's parameters, derived in its docstring):",
        f"# {FORMULAS_MODULE}.",
        "# Values are repr() of the doubles (shortest exact decimal, <= 17 significant digits).",
        "# [benchmark] holds the values the file was made from (benchmark axes: x forward, z DOWN;",
        "# SI, lam in rad); loading checks that the model's values follow from them.",
        "# Model axes: x forward, z UP; frame axes = global pitched by beta = -lambda (z3 = steering",
        "# axis); c = cos(lambda), s = sin(lambda). Going to z up flips the sign of each xz product.",
    ]
    if notes:
        lines += ["# The source also gave (checked, not stored):"] + [f"#   {n}" for n in notes]
    lines += [
        "",
        "[model]",
        f"name = {toml_string(name)}",
        f"description = {toml_string(description)}",
        f"source = {toml_string(source)}",
        'contact = "disc"                   # the benchmark\'s knife-edge front wheel',
    ]
    if allow_triangle_violation:
        lines += ["", "[checks]", 'triangle = "warn"                  # allowed on import:']
        lines += [f"# {w}" for w in params.warnings]
    table = None
    for n, value in values.items():
        if PARAMETER_GROUPS[n] != table:
            table = PARAMETER_GROUPS[n]
            lines += ["", f"[{table}]"]
        entry = f'{n} = {{ value = {float_text(value)}, unit = "{PARAMETER_UNITS[n]}" }}'
        lines.append(f"{entry:<58s} # {PARAMETER_DESCRIPTIONS[n]}: {_COMMENTS[n]}")
    lines += ["", "[benchmark]"]
    for n, value in t.as_dict().items():
        entry = f"{n} = {float_text(value)}"
        note = BENCHMARK_DESCRIPTIONS[n]
        if n in uncertainties:
            note += f"; +/- {float_text(uncertainties[n])} in the source (dropped)"
        lines.append(f"{entry:<30s} # {note}")
    return "\n".join(lines) + "\n"
