"""``bicycle-xval diagnose``: a parameter file's reference model against the engines, with the
difference localized (term, entries, parameter, body). The machinery is
`comparisons.judgments.diagnose`."""

from __future__ import annotations

import json
from pathlib import Path

from ..judgments.diagnose import COMPARED_ENGINES, DEFAULT_STATES, diagnose
from ..report.files import write_text
from .errors import EXIT_FAIL, EXIT_OK, UsageError

MAX_STATES = 2000


def add_diagnose_parser(subparsers) -> None:
    """Add ``diagnose FILE [--against MODEL] [--engines ...] [--states N] [--json OUT]``."""
    s = subparsers.add_parser(
        "diagnose", help="check a parameter file's reference model against the engines and "
                         "localize any difference (term, entries, parameter, body)")
    s.add_argument("file", help="parameter .toml file (or a named model) of the model under test")
    s.add_argument("--against", default=None,
                   help="build the engines from this named model or file instead [the same file]")
    s.add_argument("--engines", default="pinocchio",
                   help=f"comma-separated engines to compare with: {','.join(COMPARED_ENGINES)} "
                        "[pinocchio]")
    s.add_argument("--states", type=int, default=DEFAULT_STATES,
                   help=f"number of deterministic random states [{DEFAULT_STATES}]")
    s.add_argument("--json", type=Path, default=None, help="also write the diagnosis as JSON")
    s.set_defaults(func=run_diagnose)


def run_diagnose(args) -> int:
    """The ``diagnose`` command: prints the table, 0 when everything agrees, 1 otherwise.
    Bad options raise `comparisons.cli.UsageError`; bad files `ParameterError`."""
    names = tuple(e.strip() for e in str(args.engines).split(",") if e.strip())
    bad = [e for e in names if e not in COMPARED_ENGINES]
    if not names or bad:
        what = f"unknown engine {bad[0]!r}" if bad else "no engine given"
        raise UsageError(f"--engines: {what}; use a comma-separated subset of "
                         f"{','.join(COMPARED_ENGINES)} (the reference is the model under test)")
    if not 4 <= args.states <= MAX_STATES:
        raise UsageError(f"--states must be an integer from 4 to {MAX_STATES} (the least-squares "
                         f"fit's matrix grows with it); got {args.states}")
    if args.json is not None and args.json.is_dir():
        raise UsageError(f"--json {args.json} is a folder; give a file name, e.g. diagnosis.json")
    result = diagnose(args.file, args.against, names, args.states)
    print(result.describe())
    if args.json is not None:
        write_text(args.json, json.dumps(result.to_dict(), indent=1) + "\n")
    return EXIT_OK if result.agrees else EXIT_FAIL
