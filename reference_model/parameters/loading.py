"""Loading a model's parameters: the named models (:data:`NAMED_MODELS`, their files in this
folder), any file by what it holds (:func:`load_parameters`: the reference model's TOML
layout, ``reference_model.parameters.model_file``, or a file of Table 1 values,
``reference_model.parameters.benchmark_files``), :func:`resolve_model`, and the regeneration of
``benchmark.toml`` (:func:`main`, ``python -m reference_model.benchmark --write`` / ``--check``).

Named models (:data:`NAMED_MODELS`, used by :func:`resolve_model`): ``thesis`` and
``thesis-disc`` (same values, front contact at the true lowest point of the disc), ``benchmark``
(the Meijaard et al. 2007 benchmark bicycle, disc contact; see
``reference_model/parameters/benchmark.py``).
"""

from __future__ import annotations

import argparse
import os
import sys
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .benchmark import BENCHMARK_NAMES, TABLE1, model_values
from .benchmark_files import parse_benchmark_text
from .model_file import parameters_from_mapping, syntax_error, toml_text
from .schema import PARAMETER_GROUPS, PARAMETER_NAMES, ParameterError, closest
from .values import Parameters, parameters_from_benchmark

__all__ = [
    "BENCHMARK_FILE", "NAMED_MODELS", "PARAMETERS_DIR", "THESIS_FILE", "load_parameters",
    "main", "named_model_text", "resolve_model",
]

#: The folder of the named models' parameter files (package data: this package's folder).
PARAMETERS_DIR: Path = Path(__file__).resolve().parent
THESIS_FILE: Path = PARAMETERS_DIR / "thesis.toml"
BENCHMARK_FILE: Path = PARAMETERS_DIR / "benchmark.toml"  # generated: main() below

#: Model name -> (parameter file, front contact model).
NAMED_MODELS: dict[str, tuple[Path, str]] = {
    "thesis": (THESIS_FILE, "thesis"),
    "thesis-disc": (THESIS_FILE, "disc"),
    "benchmark": (BENCHMARK_FILE, "disc"),   # Meijaard et al. (2007), Table 1
}


_BENCHMARK_SUFFIXES = (".txt", ".json")


def _is_benchmark_layout(data: Mapping[str, Any]) -> bool:
    """A flat mapping of Table 1 names (not the model's tables)."""
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
    """Read and validate a TOML parameter file (format: ``reference_model.parameters.model_file``), or a file of
    Meijaard et al. (2007) benchmark parameters (``.txt`` in BicycleParameters' format,
    ``.json``, or a flat ``.toml`` of Table 1 names; see ``reference_model.parameters.benchmark_files``).

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
        data = parse_benchmark_text(text, file).values
    else:
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise syntax_error(file, text, exc) from None
    if Path(file).suffix.lower() in _BENCHMARK_SUFFIXES or _is_benchmark_layout(data):
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
    hint = closest(text, NAMED_MODELS)
    raise ParameterError(
        text,
        "model",
        f"unknown model {text!r}" + (f" (did you mean {hint!r}?)" if hint else ""),
        f"use a named model ({', '.join(NAMED_MODELS)}) or a path to a .toml parameter file",
    )


# -- benchmark.toml, the named model "benchmark" ---------------------------------------------

def _file_values(path) -> dict[str, float]:
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    return {n: data[PARAMETER_GROUPS[n]][n]["value"] for n in PARAMETER_NAMES}


_NAMED_SOURCE = "Meijaard, Papadopoulos, Ruina, Schwab, Proc. R. Soc. A 463 (2007) 1955-1982, Table 1"
_NAMED_DESCRIPTION = ("Meijaard et al. (2007) benchmark bicycle: raked steering axis "
                      "(lambda = pi/10), trail 0.08 m, wheels 0.3 m / 0.35 m, front assembly CoM "
                      "off the axis, no drag")


def named_model_text() -> str:
    """The text of ``benchmark.toml`` (the named model "benchmark": Table 1 itself)."""
    return toml_text(TABLE1, name="benchmark", source=_NAMED_SOURCE,
                     description=_NAMED_DESCRIPTION)


def main(argv: Sequence[str] | None = None) -> int:
    """``--write`` regenerates benchmark.toml; ``--check`` compares it with the formulas."""
    ap = argparse.ArgumentParser(prog="python -m reference_model.benchmark", description=main.__doc__)
    group = ap.add_mutually_exclusive_group(required=True)
    group.add_argument("--write", action="store_true", help=f"write {BENCHMARK_FILE}")
    group.add_argument("--check", action="store_true", help="exit 1 if the file's values differ")
    args = ap.parse_args(argv)
    if args.write:
        BENCHMARK_FILE.write_text(named_model_text(), encoding="utf-8")
        print(f"wrote {BENCHMARK_FILE}")
        return 0
    expected = model_values(TABLE1)
    found = _file_values(BENCHMARK_FILE)
    bad = [n for n in PARAMETER_NAMES if found[n] != expected[n]]
    for n in bad:
        print(f"{n}: file {found[n]!r}, formula {expected[n]!r}", file=sys.stderr)
    print(f"{BENCHMARK_FILE}: " + ("matches the formulas" if not bad else f"{len(bad)} value(s) differ"))
    return 1 if bad else 0
