"""``bicycle-xval diagnose``: a parameter file's reference model against the engines, with the
difference localized (term, entries, cause: a parameter or a structural mistake, body), or
'no single cause explains it' with the best candidates. The machinery is
`comparisons.judgments.diagnose`."""

from __future__ import annotations

import json
from pathlib import Path

from ..judgments.diagnose import DEFAULT_STATES, diagnose
from ..stages.files import write_text
from .errors import EXIT_FAIL, EXIT_OK, UsageError

MAX_STATES = 2000


def add_diagnose_parser(subparsers) -> None:
    """Add ``diagnose [FILE] [--model NAME|FILE] [--engine SPEC ...] [--engines a,b]
    [--engine-option k=v] [--against NAME|FILE] [--states N] [--json OUT]``."""
    s = subparsers.add_parser(
        "diagnose", help="compare engines term by term with the reference built from the same "
                         "parameters and localize any difference (term, entries, cause, body)")
    s.add_argument("file", nargs="?", default=None,
                   help="parameter file (or named model) of the model under test [--model]")
    s.add_argument("--model", default=None, help="the same as FILE: a named model or a file")
    s.add_argument("--engine", dest="engine_specs", action="append", default=[], metavar="SPEC",
                   help="an engine to check: a name, package.module:Class or path/file.py:Class "
                        "(repeatable)")
    s.add_argument("--engines", default=None,
                   help="comma-separated engine names, the same as --engine ('bicycle-xval "
                        "engines' lists them) [every installed engine with terms that models "
                        "the bicycle's front contact]")
    from .engines import add_engine_option_argument
    add_engine_option_argument(s)
    s.add_argument("--against", default=None,
                   help="a named model or file: build the engines from that bicycle instead; or "
                        "an engine (name or spec): compare with it instead of the reference "
                        "[the reference, same file]")
    s.add_argument("--states", type=int, default=DEFAULT_STATES,
                   help=f"number of deterministic random states [{DEFAULT_STATES}]")
    s.add_argument("--json", type=Path, default=None, help="also write the diagnosis as JSON")
    from .tolerance_option import add_tolerances_argument
    add_tolerances_argument(s)
    s.set_defaults(func=run_diagnose)


def run_diagnose(args) -> int:
    """The ``diagnose`` command: prints the table, 0 when everything agrees, 1 otherwise.
    Bad options raise `UsageError`; bad files `ParameterError`; bad specs `EngineSpecError`."""
    if args.file is not None and args.model is not None:
        raise UsageError("give the model once: FILE or --model, not both")
    model = args.file or args.model
    if model is None:
        raise UsageError("diagnose needs the model under test: a parameter file or a named "
                         "model, e.g. 'bicycle-xval diagnose --model thesis --engine my.py:Mine'")
    names = list(args.engine_specs)
    if args.engines is not None:
        names += [e.strip() for e in str(args.engines).split(",") if e.strip()]
        if not names:
            raise UsageError("--engines: no engine given; name at least one (see 'bicycle-xval "
                             "engines')")
    names = tuple(dict.fromkeys(names)) or _default_engines(model, args.against)
    if "reference" in names:
        raise UsageError("--engines: 'reference' is the model under test; name the engines to "
                         "compare with it (see 'bicycle-xval engines')")
    from engines import EngineSpecError
    from engines.registry import resolve
    for name in names:
        try:
            resolve(name)
        except EngineSpecError as exc:
            raise UsageError(f"--engines: {exc}") from None
    if not 4 <= args.states <= MAX_STATES:
        raise UsageError(f"--states must be an integer from 4 to {MAX_STATES} (the least-squares "
                         f"fit's matrix grows with it); got {args.states}")
    if args.json is not None and args.json.is_dir():
        raise UsageError(f"--json {args.json} is a folder; give a file name, e.g. diagnosis.json")
    from .engines import engine_options
    options = {n: engine_options(n, args.engine_options) for n in names} \
        if args.engine_options else None
    from .tolerance_option import tolerances_from
    result = diagnose(model, args.against, names, args.states, options=options,
                      tolerances=tolerances_from(args))
    print(result.describe())
    if args.json is not None:
        write_text(args.json, json.dumps(result.to_dict(), indent=1) + "\n")
    return EXIT_OK if result.agrees else EXIT_FAIL


def _default_engines(model, against) -> tuple[str, ...]:
    """Every installed engine with terms that models the front contact of the bicycle the
    engines are built from (``--against``'s when it names a bicycle, else the model's)."""
    from engines import term_engines
    from reference_model import resolve_model

    from ..judgments.diagnose import _engine_named
    bicycle = model if against is None or _engine_named(against) else against
    names = term_engines(resolve_model(bicycle).contact)
    if not names:
        raise UsageError("diagnose: no installed engine computes terms on this bicycle's front "
                         "contact; install one ('bicycle-xval engines') or name one with --engine")
    return names
