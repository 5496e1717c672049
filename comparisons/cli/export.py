"""``bicycle-xval export``: a model written in another description.

    bicycle-xval export --model NAME|FILE --format benchmark|urdf|mjcf|json --out PATH

Formats are rows of `EXPORT_FORMATS`: a name, what it writes, and the writer
``(model, out) -> str`` (one line for the terminal). ``benchmark`` writes Meijaard et al.
(2007) Table 1 names (`reference_model.benchmark_files.write_benchmark`), as TOML, JSON or
BicycleParameters' .txt by the suffix of ``--out``; a model without a benchmark counterpart
(thesis contact, drag, wheels with Izz != Ixx) is refused with the list of what has none.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .errors import EXIT_OK, UsageError


@dataclass(frozen=True)
class ExportFormat:
    """One row of the format table."""

    name: str
    help: str
    suffixes: tuple[str, ...]          # accepted suffixes of --out
    write: Callable[[object, Path], str]


def _write_benchmark(model, out: Path) -> str:
    from reference_model.benchmark_files import write_benchmark
    values = write_benchmark(model.params, out)
    return f"{len(values)} Table 1 values of {model.name!r} -> {out}"


def _write_description(fmt: str):
    def write(model, out: Path) -> str:
        from reference_model.export import export_model
        path = export_model(model.params, fmt, out)
        return f"{model.name!r} as {fmt.upper()} -> {path}"
    return write


def _write_fmu(model, out: Path) -> str:
    from reference_model.exports.fmu import FmuExportError, write_fmu
    try:
        write_fmu(model, out)
    except FmuExportError as exc:
        raise UsageError(str(exc)) from None
    return f"{model.name!r} as a Model-Exchange FMU (FMI 2.0) -> {out}"


def _write_fmu_mapping(model, out: Path) -> str:
    from reference_model.exports.fmu import mapping_text
    from reference_model.parameters.benchmark_files import _write_atomically
    _write_atomically(out, mapping_text(None), parents=False)
    return f"the fmu engine's mapping template (the names bicycle-xval's FMU uses) -> {out}"


EXPORT_FORMATS: dict[str, ExportFormat] = {f.name: f for f in (
    ExportFormat("benchmark", "Meijaard et al. (2007) Table 1 names (.toml, .json or "
                 "BicycleParameters' .txt by the suffix of --out)", (".toml", ".json", ".txt"),
                 _write_benchmark),
    ExportFormat("urdf", "the four bodies and the thesis's joint chain for robotics engines "
                 "(URDF cannot express the rolling contact; the file says so)", (".urdf",),
                 _write_description("urdf")),
    ExportFormat("mjcf", "the thesis's joint chain for MuJoCo, wheels as thin cylinders on a "
                 "ground plane with MuJoCo's soft contact (a declared approximation of rolling; "
                 "the file says so)", (".xml", ".mjcf"), _write_description("mjcf")),
    ExportFormat("json", "everything, the rolling-contact constraints included, for any engine",
                 (".json",), _write_description("json")),
    ExportFormat("fmu", "a Model-Exchange FMU (FMI 2.0) of the reference, its generated C "
                 "compiled with gcc; Baumgarte a1 = a2 = 10 as parameters (docs/engines.md)",
                 (".fmu",), _write_fmu),
    ExportFormat("fmu-mapping", "the fmu engine's mapping template: FMU variable names -> the "
                 "thesis's coordinates, torques and units, to edit for another tool's FMU",
                 (".toml",), _write_fmu_mapping),
)}


def add_export_parser(subparsers) -> None:
    """Register ``export`` on the CLI's subparsers."""
    s = subparsers.add_parser("export", help="write a model in another description "
                                             f"({', '.join(EXPORT_FORMATS)})")
    s.add_argument("--model", default="thesis",
                   help="named model (thesis, thesis-disc, benchmark) or a parameter file [thesis]")
    s.add_argument("--format", required=True, choices=tuple(EXPORT_FORMATS),
                   help="; ".join(f"{f.name}: {f.help}" for f in EXPORT_FORMATS.values()))
    s.add_argument("--out", required=True, type=Path, help="the file to write")
    s.set_defaults(func=run_export)


def run_export(args) -> int:
    """The ``export`` command: writes ``--out`` (atomically) and prints one line."""
    from reference_model import load_model

    fmt = EXPORT_FORMATS[args.format]
    if not args.out.name or args.out.name in (".", ".."):   # '' and '.' are Path('.')
        raise UsageError(f"--out {str(args.out)!r} names no file; give a file name, e.g. "
                         f"--out {args.model if '/' not in args.model else 'bicycle'}"
                         f"{fmt.suffixes[0]}")
    if args.out.suffix.lower() not in fmt.suffixes:
        raise UsageError(f"--out {args.out}: --format {fmt.name} writes "
                         f"{', '.join(fmt.suffixes)} files; name it e.g. "
                         f"{args.out.with_suffix(fmt.suffixes[0]).name}")
    if args.out.is_dir():
        raise UsageError(f"--out {args.out} is a folder; give a file name")
    model = load_model(args.model)
    print(fmt.write(model, args.out))
    for w in model.warnings:
        print(f"  warning: {w}")
    return EXIT_OK
