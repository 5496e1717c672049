"""The mapping file of the ``fmu`` engine: which FMU variable holds which thesis coordinate,
rate, torque, Baumgarte parameter, term and residual, with a scale to SI (docs/engines.md,
"The fmu engine"; ``bicycle-xval export --format fmu-mapping`` writes the template). Pure: a
TOML text and the FMU's variable names in, a typed `FmuMapping` out; every problem one
`MappingError` line naming the field and the fix."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass

from reference_model.model import CONSTRAINT_NAMES
from reference_model.names import COORDINATES, TORQUE_NAMES
from reference_model.parameters.schema import PARAMETER_NAMES

__all__ = ["FmuMapping", "MappingError", "Ref", "TERM_SHAPES", "parse_mapping"]

#: the [terms] keys: (rows, columns; 0 for a vector)
TERM_SHAPES = {"M": (8, 8), "F": (8, 0), "S": (8, 3), "Qgrav": (8, 0), "D": (5, 8), "dDdq": (5, 0)}


class MappingError(ValueError):
    """A mapping file that cannot be used (one line: the field and the fix)."""


@dataclass(frozen=True)
class Ref:
    """An FMU variable and its scale: thesis value (SI) = scale * FMU value."""

    name: str
    scale: float = 1.0


@dataclass(frozen=True)
class FmuMapping:
    contact: str
    coordinates: tuple[Ref, ...]            # the thesis's order
    rates: tuple[Ref, ...]
    torques: tuple[Ref, ...]                # Mdir, Mped, Mvue
    baumgarte: tuple[str, str] | None       # parameters a1, a2
    terms: dict[str, tuple[tuple[str, ...], ...]]   # term -> rows of variable names
    residual: tuple[str, ...] | None        # C outputs, CONSTRAINT_NAMES order
    parameters: dict[str, Ref]              # thesis parameter -> FMU parameter (SI = scale * FMU)


def _ref(where: str, field: str, value, names: frozenset[str]) -> Ref:
    if isinstance(value, str):
        ref = Ref(value)
    elif isinstance(value, dict) and isinstance(value.get("name"), str) and \
            isinstance(value.get("scale", 1.0), (int, float)) and not isinstance(value.get("scale"), bool):
        ref = Ref(value["name"], float(value.get("scale", 1.0)))
    else:
        raise MappingError(f"{where}: {field} must be an FMU variable name or {{name = \"...\", "
                           f"scale = s}}; got {value!r}")
    if ref.name not in names:
        raise MappingError(f"{where}: {field} names {ref.name!r}, which the FMU does not have; "
                           "fix: use one of its variables (fmpy dump FILE.fmu lists them)")
    return ref


def _table(data: dict, key: str, where: str, required: bool) -> dict | None:
    value = data.get(key)
    if value is None:
        if required:
            raise MappingError(f"{where}: no [{key}] table; fix: add it (bicycle-xval export "
                               "--format fmu-mapping writes the template)")
        return None
    if not isinstance(value, dict):
        raise MappingError(f"{where}: {key} must be a table; got {value!r}; fix: write [{key}] "
                           "on a line of its own, its keys on the lines below")
    return value


def _exact_keys(table: dict, key: str, keys: tuple[str, ...], where: str) -> None:
    """Refuse a table [key] that lacks one of ``keys`` or has another key."""
    missing = [k for k in keys if k not in table]
    if missing:
        raise MappingError(f"{where}: [{key}] lacks {', '.join(missing)}; fix: map each of "
                           f"{', '.join(keys)} to an FMU variable")
    extra = sorted(set(table) - set(keys))
    if extra:
        raise MappingError(f"{where}: [{key}] has unknown keys {', '.join(extra)}; fix: use "
                           f"{', '.join(keys)}")


def _refs(data: dict, key: str, keys: tuple[str, ...], where: str, names) -> tuple[Ref, ...]:
    table = _table(data, key, where, True)
    _exact_keys(table, key, keys, where)
    return tuple(_ref(where, f"{key}.{k}", table[k], names) for k in keys)


def _pattern_names(where: str, term: str, pattern, names) -> tuple[tuple[str, ...], ...]:
    """The variable names of term ``term``'s pattern: rows of columns, {i} and {j} 1-based."""
    rows, cols = TERM_SHAPES[term]
    example = f"term.{term}[{{i}},{{j}}]" if cols else f"term.{term}[{{i}}]"
    if not isinstance(pattern, str):
        raise MappingError(f"{where}: terms.{term} must be a name pattern; got {pattern!r}; "
                           f"fix: e.g. {term} = \"{example}\"")
    try:
        return tuple(
            tuple(_names(where, f"terms.{term}", pattern.format(i=i + 1, j=j + 1), names)
                  for j in range(max(cols, 1))) for i in range(rows))
    except (KeyError, IndexError, ValueError) as exc:
        if isinstance(exc, MappingError):
            raise
        raise MappingError(f"{where}: terms.{term} = {pattern!r} is not a name pattern "
                           f"({type(exc).__name__}: {exc}); fix: use only {{i}} (the row) and "
                           f"{{j}} (the column), 1-based, and {{{{ }}}} for a literal brace, "
                           f"e.g. {term} = \"{example}\"") from None


def _names(where: str, field: str, value, names) -> str:
    if not isinstance(value, str):
        raise MappingError(f"{where}: {field} must be an FMU variable name (text); got {value!r}")
    if value not in names:
        raise MappingError(f"{where}: {field} names {value!r}, which the FMU does not have; fix: "
                           "use one of its variables (fmpy dump FILE.fmu lists them)")
    return value


def parse_mapping(text: str, names: frozenset[str], where: str) -> FmuMapping:
    """The mapping in ``text`` (``where`` names it in errors), checked against ``names``, the
    FMU's variables."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise MappingError(f"{where}: not TOML ({exc}); fix: see docs/engines.md, "
                           "\"The fmu engine\"") from None
    contact = data.get("contact", "disc")
    if contact not in ("thesis", "disc"):
        raise MappingError(f"{where}: contact = {contact!r}; fix: thesis or disc (the front "
                           "contact the FMU models)")
    coordinates = _refs(data, "coordinates", COORDINATES, where, names)
    rates = _refs(data, "rates", COORDINATES, where, names)
    torques = _refs(data, "torques", TORQUE_NAMES, where, names)
    baumgarte = None
    if (table := _table(data, "baumgarte", where, False)) is not None:
        _exact_keys(table, "baumgarte", ("a1", "a2"), where)
        baumgarte = tuple(_names(where, f"baumgarte.{k}", table[k], names) for k in ("a1", "a2"))
    terms: dict[str, tuple[tuple[str, ...], ...]] = {}
    for term, pattern in (_table(data, "terms", where, False) or {}).items():
        if term not in TERM_SHAPES:
            raise MappingError(f"{where}: terms.{term} is not a term; fix: use "
                               f"{', '.join(TERM_SHAPES)}")
        terms[term] = _pattern_names(where, term, pattern, names)
    residual = None
    if (table := _table(data, "residual", where, False)) is not None:
        _exact_keys(table, "residual", CONSTRAINT_NAMES, where)
        residual = tuple(_names(where, f"residual.{k}", table[k], names) for k in CONSTRAINT_NAMES)
    parameters = {}
    for key, value in (_table(data, "parameters", where, False) or {}).items():
        if key not in PARAMETER_NAMES:
            raise MappingError(f"{where}: parameters.{key} is not a thesis parameter; fix: use "
                               "the names of docs/model.md (R_rear, m3, I3xz, ...)")
        parameters[key] = _ref(where, f"parameters.{key}", value, names)
    return FmuMapping(contact, coordinates, rates, torques, baumgarte, terms, residual, parameters)
