"""``bicycle-xval import``: a bicycle described by other parameters, as a parameter file.

    bicycle-xval import FILE --from benchmark --out my.toml [--name NAME]
                        [--allow-triangle-violation]

``--from benchmark``: Meijaard et al. (2007) Table 1 names in BicycleParameters' ``.txt``
(``w = 1.07+/-0.002``), ``.json`` or flat ``.toml`` (`reference_model.benchmark_files`). The
written file names the bicycle (``--name``, default the input's stem), its source and contact
"disc", and loads back to the same model before it is written (atomically). Every user mistake
is one line, exit status 2.
"""

from __future__ import annotations

from pathlib import Path

from .errors import EXIT_OK, UsageError

#: --from value -> what it reads
IMPORT_FORMATS = {
    "benchmark": "Meijaard et al. (2007) Table 1 names: BicycleParameters' <Name>Benchmark.txt, "
                 ".json or flat .toml",
}


def add_import_parser(subparsers) -> None:
    """Register ``import`` on the CLI's subparsers."""
    s = subparsers.add_parser(
        "import", help="turn a bicycle's published parameters (e.g. the benchmark's Table 1 "
                       "names) into a parameter .toml file")
    s.add_argument("file", type=Path, help="the parameter file to import")
    s.add_argument("--from", dest="source_format", required=True, choices=tuple(IMPORT_FORMATS),
                   help="what the file holds: " + "; ".join(f"{k}: {v}"
                                                            for k, v in IMPORT_FORMATS.items()))
    s.add_argument("--out", required=True, type=Path, help="the parameter .toml file to write")
    s.add_argument("--name", default=None, help="the bicycle's name [the input file's stem]")
    s.add_argument("--allow-triangle-violation", action="store_true",
                   help="accept inertias that break the triangle inequality (measured ones "
                        "often do by a few per cent); the file then says triangle = \"warn\" "
                        "and every report using it says so")
    s.set_defaults(func=run_import)


def _printable_name(name: str, what: str) -> None:
    """A bicycle's name is one printable line: it is written into the parameter file, the
    reports and the data files' names."""
    import unicodedata
    for k, ch in enumerate(name):
        if unicodedata.category(ch)[0] == "C":
            raise UsageError(f"{what} holds the control character U+{ord(ch):04X} at position "
                             f"{k + 1}; a bicycle's name is one printable line, e.g. --name my-bike")


def run_import(args) -> int:
    """The ``import`` command: writes ``--out`` and prints one line about it."""
    from reference_model.benchmark_files import read_benchmark_file, write_import
    from reference_model.params import TriangleInequalityError

    if args.name is not None and not args.name.strip():
        raise UsageError("--name is empty; give the bicycle a name, e.g. --name my-bike")
    _printable_name(args.name if args.name is not None else args.file.stem,
                    "--name" if args.name is not None else f"the file name {args.file.name!r}")
    if args.out.exists() and args.file.exists() and args.out.resolve() == args.file.resolve():
        raise UsageError(f"--out {args.out} is the input file; write the parameter file "
                         "elsewhere, e.g. --out " + args.out.with_name(
                             args.out.stem + "-model.toml").name)
    if args.out.is_dir():
        raise UsageError(f"--out {args.out} is a folder; give a .toml file name")
    try:
        params = write_import(args.file, args.out, name=args.name,
                              allow_triangle_violation=args.allow_triangle_violation)
    except TriangleInequalityError as exc:
        raise UsageError(f"{exc.file}: {exc.key}: {exc.problem}; fix: check the values and "
                         "units; if they are measured and right, add "
                         "--allow-triangle-violation") from None
    print(f"imported {args.file} as {params.name!r} (contact {params.contact}) -> {args.out}")
    for note in read_benchmark_file(args.file).notes:
        print(f"  not stored: {note}")
    for w in params.warnings:
        print(f"  warning: {w}")
    return EXIT_OK


# -- run --model / --scenario-file ------------------------------------------------------------

def add_run_model_options(parser) -> None:
    """``run``'s --model and --scenario-file (both repeatable; --model also comma-separated)."""
    parser.add_argument("--model", action="append", default=None, metavar="NAME|FILE",
                        help="run every scenario that makes sense for this bicycle (named model "
                             "or parameter/benchmark file) on every engine, with its stability "
                             "picture; repeatable or comma-separated [the thesis's full run]")
    parser.add_argument("--scenario-file", action="append", default=None, type=Path,
                        metavar="FILE", help="also run this scenario file (repeatable) on the "
                                             "model it names and on every --model")


def with_models(opts, models: list[str] | None, files: list[Path] | None):
    """``opts`` carrying the models and scenario files of the command line, each checked here
    (a bad file or name is one line, exit 2, before any run)."""
    import dataclasses

    from reference_model.scenario_files import ScenarioFileError
    from ..stages.cases import build_cases, model_spec

    names = [s.strip() for raw in (models or []) for s in raw.split(",")]
    if models is not None and not all(names):
        raise UsageError("--model has an empty entry; give a named model or a file, e.g. "
                         "--model thesis,my.toml")
    specs = []
    for n in dict.fromkeys(names):
        m = model_spec(n)              # ParameterError: one line, exit 2
        if m.spec in {s.spec for s in specs}:
            continue
        specs.append(m)
    paths = []
    for f in files or []:
        if not f.is_file():
            raise UsageError(f"--scenario-file: no file {str(f)!r}; give a scenario .toml file "
                             "(format: reference_model/scenario_files.py)")
        paths.append(str(f))
    opts = dataclasses.replace(opts, models=tuple(specs), scenario_files=tuple(paths))
    try:
        build_cases(opts.scenarios, opts.models, opts.scenario_files)
    except ScenarioFileError as exc:
        raise UsageError(f"--scenario-file: {exc}") from None
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    return opts
