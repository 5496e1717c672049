"""Files of Meijaard et al. (2007) benchmark parameters: read them, import them, write them.

A bicycle is often published by Table 1's 26 names (``w, c, lam, g, rR, mR, IRxx, IRyy, xB,
zB, mB, IBxx, IByy, IBzz, IBxz, xH, zH, mH, IHxx, IHyy, IHzz, IHxz, rF, mF, IFxx, IFyy``;
SI units, lam in rad, benchmark axes x forward, z down). Three spellings are read:

* **BicycleParameters' ``<Name>Benchmark.txt``**: one ``name = value`` per line, the value
  optionally with an uncertainty, ``1.07+/-0.002`` (also ``1.07 ± 0.002`` and the factored
  exponent ``(6.53+/-0.02)e-07``). Blank lines and ``#`` comments are ignored. The uncertainties
  are dropped (the model takes the nominal value) and kept in :attr:`BenchmarkFile.uncertainties`,
  which the importer writes as comments.
* Besides Table 1's names, BicycleParameters' files may carry values that Table 1 implies
  (``IRzz``/``IFzz``, equal to ``IRxx``/``IFxx`` for an axisymmetric wheel; ``yB``, ``yH``...,
  zero for a bicycle symmetric about its xz plane) and the handlebar ``G`` and fork ``S``
  measured apart (``mG, xG, zG, IGxx, ...``; ``H`` is their assembly, the body the model uses).
  These are checked (a wheel that is not axisymmetric or an off-plane centre of mass is an
  error: Table 1 cannot hold it), left out, and said in :attr:`BenchmarkFile.notes`, which the
  importer writes as comments and ``bicycle-xval import`` prints.
* **JSON**: one object ``{"w": 1.02, ...}`` of numbers.
* **TOML**: the same names as top-level keys, ``w = 1.02``.

:func:`import_benchmark` turns such a file into the reference model's parameter file (text),
:func:`write_import` writes it (atomically, after checking it loads back to the same model);
:func:`benchmark_text` / :func:`write_benchmark` are the reverse (export), from
:func:`reference_model.parameters.values.to_benchmark`. ``load_model`` reads all three formats
directly (``reference_model.parameters.loading.load_parameters``). Every problem is one :class:`ParameterError`
naming the file, the key (or line), the problem and the fix.
"""

from __future__ import annotations

import json
import math
import os
import re
import tempfile
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .benchmark import BENCHMARK_DESCRIPTIONS, BENCHMARK_NAMES
from .model_file import float_text, parameters_from_mapping, toml_text
from .schema import ParameterError
from .values import Parameters, parameters_from_benchmark, to_benchmark

__all__ = [
    "BENCHMARK_FORMATS", "BenchmarkFile", "ImportedBicycle", "benchmark_text", "import_benchmark",
    "parse_benchmark_text", "read_benchmark_file", "write_benchmark", "write_import",
]

#: file suffix -> format name
BENCHMARK_FORMATS: dict[str, str] = {".txt": "txt", ".json": "json", ".toml": "toml"}

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_PLAIN = re.compile(rf"^({_NUMBER})$")
_PLUS_MINUS = re.compile(rf"^({_NUMBER})\s*(?:\+/-|±)\s*({_NUMBER})$")
_FACTORED = re.compile(rf"^\(\s*({_NUMBER})\s*(?:\+/-|±)\s*({_NUMBER})\s*\)\s*[eE]([-+]?\d+)$")
_PAREN = re.compile(rf"^\(\s*({_NUMBER})\s*(?:\+/-|±)\s*({_NUMBER})\s*\)$")
_TXT_EXAMPLE = "w = 1.07+/-0.002"


@dataclass(frozen=True)
class BenchmarkFile:
    """What a benchmark-parameter file says: ``values`` (name -> number, as read; validated by
    :func:`reference_model.parameters.benchmark.table1_from_mapping` when used), ``uncertainties`` (name ->
    the ``+/-`` value, .txt only) and ``source`` (the path)."""

    values: dict[str, Any]
    source: str
    uncertainties: dict[str, float] = field(default_factory=dict)
    notes: tuple[str, ...] = ()   # what was read besides Table 1's names, checked and left out


def _format_of(file: str) -> str:
    suffix = Path(file).suffix.lower()
    if suffix not in BENCHMARK_FORMATS:
        raise ParameterError(file, "(file)", f"unknown benchmark file type {suffix or '(none)'!r}",
                             "use a .txt (BicycleParameters' <Name>Benchmark.txt), .json or "
                             ".toml file")
    return BENCHMARK_FORMATS[suffix]


def _parse_txt(text: str, file: str) -> BenchmarkFile:
    values: dict[str, Any] = {}
    uncertainties: dict[str, float] = {}
    lines: dict[str, int] = {}
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        where = f"line {number}"
        if "=" not in line:
            raise ParameterError(file, where, f"expected 'name = value', got {raw.strip()!r}",
                                 f"write one parameter per line, e.g. {_TXT_EXAMPLE}")
        name, value = (part.strip() for part in line.split("=", 1))
        if name in lines:
            raise ParameterError(file, f"{where}: {name}",
                                 f"{name} is given twice (lines {lines[name]} and {number})",
                                 "keep one of the two lines")
        lines[name] = number
        for pattern in (_PLAIN, _PLUS_MINUS, _PAREN, _FACTORED):
            match = pattern.match(value)
            if match:
                break
        else:
            raise ParameterError(file, f"{where}: {name}",
                                 f"value {value!r} is not a number or number+/-uncertainty",
                                 f"write e.g. {_TXT_EXAMPLE} (SI units, lam in rad)")
        groups = match.groups()
        scale = 10.0 ** int(groups[2]) if len(groups) == 3 else 1.0
        nominal = float(groups[0]) if scale == 1.0 else float(f"{groups[0]}e{groups[2]}")
        values[name] = nominal
        if len(groups) >= 2:
            uncertainty = float(groups[1]) * scale
            if not (math.isfinite(uncertainty) and uncertainty >= 0.0):
                raise ParameterError(file, f"{where}: {name}",
                                     f"uncertainty {groups[1]!r} is not a non-negative number",
                                     f"write e.g. {_TXT_EXAMPLE}")
            uncertainties[name] = uncertainty
    return BenchmarkFile(values, file, uncertainties)


def _no_duplicates(file: str):
    def hook(pairs):
        seen: dict[str, Any] = {}
        for key, value in pairs:
            if key in seen:
                raise ParameterError(file, key, f"{key!r} is given twice",
                                     "keep one of the two entries")
            seen[key] = value
        return seen
    return hook


# values BicycleParameters writes that Table 1 implies: name -> (what it must equal, why)
_IMPLIED = {
    "IRzz": ("IRxx", "the rear wheel is axisymmetric: IRzz = IRxx"),
    "IFzz": ("IFxx", "the front wheel is axisymmetric: IFzz = IFxx"),
    **{f"y{b}": (None, "the bicycle is symmetric about its xz plane: y of every centre of mass "
                       "is 0") for b in "RBHFGS"},
}
# the handlebar (G) and fork (S) measured apart; H, their assembly, is the model's body
_PARTS = {**{f"{q}{b}": b for b in "GS" for q in ("m", "x", "z")},
          **{f"I{b}{axes}": b for b in "GS" for axes in ("xx", "xy", "xz", "yy", "yz", "zz")}}
_PART_NAMES = {"G": "handlebar", "S": "fork"}
_RTOL_IMPLIED = 1e-12   # the same number written twice; only a real difference is refused


def _fold_extras(read: BenchmarkFile) -> BenchmarkFile:
    """Check and leave out the values besides Table 1's names that BicycleParameters writes
    (module docstring); anything else stays, for the validation to name it."""
    values = dict(read.values)
    notes = []
    for key, (same_as, why) in _IMPLIED.items():
        if key not in values:
            continue
        v = values[key]
        expected = 0.0 if same_as is None else values.get(same_as)
        ok = (isinstance(v, (int, float)) and not isinstance(v, bool) and expected is not None
              and isinstance(expected, (int, float))
              and abs(v - expected) <= _RTOL_IMPLIED * max(abs(expected), 1e-300))
        if not ok:
            target = "0" if same_as is None else f"{same_as} = {expected!r}"
            raise ParameterError(read.source, key, f"{key} = {v!r}, but {why}; Table 1 "
                                 "cannot hold a bicycle that differs", f"make {key} equal "
                                 f"{target} or remove it (the model implies it)")
        del values[key]
        notes.append(f"{key} = {v!r}: implied by Table 1 ({why}), checked and not stored")
    parts = sorted({b for k, b in _PARTS.items() if k in values})
    for b in parts:
        keys = [k for k in values if _PARTS.get(k) == b]
        for k in keys:
            del values[k]
        notes.append(f"{', '.join(keys)}: the {_PART_NAMES[b]} ({b}) measured apart, not used: "
                     "the model's front body is their assembly H (mH, xH, zH, IHxx, IHyy, IHzz, IHxz)")
    if {"G", "S"} <= set(parts) and all(isinstance(read.values.get(k), (int, float))
                                        for k in ("mG", "mS", "mH")):
        total = read.values["mG"] + read.values["mS"]
        notes.append(f"mG + mS = {total:.6g} kg against mH = {read.values['mH']:.6g} kg in "
                     "the source "
                     f"({100 * (total - read.values['mH']) / read.values['mH']:+.1f} %); "
                     "mH used as given")
    uncertainties = {k: u for k, u in read.uncertainties.items() if k in values}
    return BenchmarkFile(values, read.source, uncertainties, read.notes + tuple(notes))


def parse_benchmark_text(text: str, file: str | os.PathLike[str], fmt: str | None = None) -> BenchmarkFile:
    """Parse the text of a benchmark-parameter file; ``fmt`` ("txt", "json", "toml") defaults
    to the file's suffix. Values are not validated yet (see :class:`BenchmarkFile`), but the
    extras BicycleParameters writes besides Table 1 are checked and left out (``notes``)."""
    file = os.fspath(file)
    fmt = fmt or _format_of(file)
    return _fold_extras(_parse_any(text, file, fmt))


def _parse_any(text: str, file: str, fmt: str) -> BenchmarkFile:
    if fmt == "txt":
        return _parse_txt(text, file)
    if fmt == "json":
        try:
            data = json.loads(text, object_pairs_hook=_no_duplicates(file))
        except json.JSONDecodeError as exc:
            raise ParameterError(file, f"line {exc.lineno}", f"invalid JSON: {exc.msg}",
                                 'write one object of numbers, e.g. {"w": 1.02, "c": 0.08, ...}'
                                 ) from None
    elif fmt == "toml":
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ParameterError(file, "(syntax)", f"invalid TOML: {exc}",
                                 "write one 'name = number' per line, e.g. w = 1.02") from None
    else:
        raise ValueError(f"unknown benchmark format {fmt!r}; use one of txt, json, toml")
    if not isinstance(data, dict):
        raise ParameterError(file, "(file)", f"expected an object of Table 1 names, got "
                             f"{type(data).__name__}", 'write {"w": 1.02, "c": 0.08, ...}')
    return BenchmarkFile(dict(data), file)


def read_benchmark_file(path: str | os.PathLike[str]) -> BenchmarkFile:
    """Read a .txt/.json/.toml file of benchmark parameters (format by suffix)."""
    file = os.fspath(path)
    fmt = _format_of(file)
    try:
        text = Path(file).read_text(encoding="utf-8-sig")   # a BOM is accepted, as in TOML files
    except FileNotFoundError:
        raise ParameterError(file, "(file)", "no such file",
                             "give the path of an existing benchmark-parameter file") from None
    except UnicodeDecodeError as exc:
        raise ParameterError(file, "(file)", f"not UTF-8 text (byte {exc.start})",
                             "save the file as UTF-8") from None
    except OSError as exc:
        raise ParameterError(file, "(file)", f"cannot read the file: {exc.strerror or exc}",
                             "give the path of a readable file") from None
    return parse_benchmark_text(text, file, fmt)


@dataclass(frozen=True)
class ImportedBicycle:
    """An imported bicycle: its validated ``params`` (contact "disc") and ``text``, the
    parameter file to write (see :func:`reference_model.parameters.model_file.toml_text`)."""

    params: Parameters
    text: str
    notes: tuple[str, ...] = ()   # the source's extras, checked and left out (BenchmarkFile)


def import_benchmark(
    path: str | os.PathLike[str],
    *,
    name: str | None = None,
    allow_triangle_violation: bool = False,
    description: str | None = None,
) -> ImportedBicycle:
    """Import a benchmark-parameter file: the model's parameters and the parameter file's text.

    ``name`` defaults to the input file's stem; the file records the source path as given,
    the formulas' module, contact "disc", the Table 1 values with their uncertainties (as
    comments), and ``[checks] triangle = "warn"`` if ``allow_triangle_violation``.
    """
    read = read_benchmark_file(path)
    name = Path(read.source).stem if name is None else name
    params = parameters_from_benchmark(read.values, name=name, source=read.source,
                                       allow_triangle_violation=allow_triangle_violation)
    text = toml_text(params.benchmark, name=name, source=read.source, description=description,
                     generator="reference_model.benchmark_files.import_benchmark "
                               "(bicycle-xval import)",
                     uncertainties={k: v for k, v in read.uncertainties.items()},
                     allow_triangle_violation=allow_triangle_violation, notes=read.notes)
    return ImportedBicycle(params, text, read.notes)


def _write_atomically(out: Path, text: str | bytes, parents: bool = True) -> None:
    """Write ``text`` (or bytes) to ``out`` via a temporary file in the same folder and a
    rename, so a failure never leaves a half-written file. The file gets the mode of any new
    file (0666 less the umask), not the temporary's private 0600. ``parents``: create missing
    folders."""
    if parents:
        out.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    try:
        with (os.fdopen(fd, "wb") if isinstance(text, bytes) else
              os.fdopen(fd, "w", encoding="utf-8")) as handle:
            handle.write(text)
        mask = os.umask(0o022)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_import(
    path: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    name: str | None = None,
    allow_triangle_violation: bool = False,
    description: str | None = None,
) -> Parameters:
    """Import ``path`` and write the parameter file ``out`` (atomically). The written text is
    loaded back before it is written and must give the same model (values, name, contact,
    triangle mode, Table 1). Returns the loaded parameters (``source`` = ``out``)."""
    out = Path(out)
    if out.suffix.lower() != ".toml":
        raise ParameterError(str(out), "(output)", "the imported parameter file must be .toml "
                             f"(a {out.suffix or 'suffix-less'} file would not load as one)",
                             f"name it e.g. {out.with_suffix('.toml').name}")
    imported = import_benchmark(path, name=name, allow_triangle_violation=allow_triangle_violation,
                                description=description)
    loaded = parameters_from_mapping(tomllib.loads(imported.text), source=str(out),
                                     default_name=out.stem)
    expected = imported.params.replace(source=str(out))
    if loaded != expected or loaded.benchmark != expected.benchmark:
        raise AssertionError(f"{out}: the generated file does not load back to the imported model")
    _write_atomically(out, imported.text)
    return loaded


def benchmark_text(values: Mapping[str, float], fmt: str = "toml", *, comment: str = "") -> str:
    """Table 1 values as a file: "toml" (``w = 1.02`` lines), "json" (one object) or "txt"
    (BicycleParameters' format, ``w = 1.02+/-0.0``: no uncertainty known). Floats are written
    with repr (exact); ``comment`` (toml and txt only) heads the file."""
    missing = [n for n in BENCHMARK_NAMES if n not in values]
    if missing:
        raise ValueError(f"benchmark values missing: {', '.join(missing)}")
    numbers = {n: float(values[n]) for n in BENCHMARK_NAMES}
    head = [f"# {line}" for line in comment.splitlines()]
    if fmt == "json":
        return json.dumps(numbers, indent=2) + "\n"
    if fmt == "toml":
        body = [f"{f'{n} = {float_text(v)}':<30s} # {BENCHMARK_DESCRIPTIONS[n]}"
                for n, v in numbers.items()]
    elif fmt == "txt":
        body = [f"{n} = {float_text(v)}+/-0.0" for n, v in numbers.items()]
    else:
        raise ValueError(f"unknown benchmark format {fmt!r}; use one of toml, json, txt")
    return "\n".join(head + body) + "\n"


def write_benchmark(params: Parameters, out: str | os.PathLike[str], fmt: str | None = None) -> dict[str, float]:
    """Export: Table 1 values of ``params`` (:func:`to_benchmark`, which says which parameters
    have no counterpart) written to ``out`` atomically, format by ``fmt`` or the suffix."""
    out = Path(out)
    fmt = fmt or _format_of(str(out))
    values = to_benchmark(params)
    comment = (f"{params.name}: Meijaard et al. (2007) benchmark parameters (Table 1 names; SI, "
               f"lam in rad, x forward, z down)\nexported by reference_model.benchmark_files from "
               f"{params.source}")
    _write_atomically(out, benchmark_text(values, fmt, comment=comment))
    return values
