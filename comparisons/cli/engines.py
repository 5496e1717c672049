"""``bicycle-xval engines``: the engines the harness can find, and how engine specs and
``--engine-option key=value`` reach them from the command line.

An engine is named by a registered name (entry-point group ``bicycle_xval.engines``: the
built-ins and any installed third party's) or a spec, ``package.module:Class`` or
``path/to/file.py:Class``. The contract an engine fulfils: docs/engines.md.
"""

from __future__ import annotations

from .errors import EXIT_OK


def add_engines_parser(sub) -> None:
    s = sub.add_parser("engines", help="list the engines found (built-ins and plugins): source, "
                                       "capabilities, contact models, options")
    s.add_argument("spec", nargs="?", default=None,
                   help="show one engine (a name or package.module:Class or file.py:Class)")
    s.set_defaults(func=cmd_engines)


def cmd_engines(args) -> int:
    from engines import engine_info
    infos = engine_info(args.spec)
    for i in infos:
        print(f"{i.name}  ({i.source}; {i.spec})")
        if i.not_installed:    # an optional engine whose extra is missing: listed, not an error
            print(f"  {i.not_installed}")
            continue
        if i.error:
            print(f"  cannot be loaded: {i.error}")
            continue
        if i.doc:
            print(f"  {i.doc}")
        print(f"  capabilities: {', '.join(i.capabilities) or 'none'}")
        print(f"  contact models: {', '.join(i.contacts)}")
        print(f"  options: {', '.join(i.options) or 'none'}")
    return EXIT_OK


def add_engine_option_argument(parser) -> None:
    parser.add_argument("--engine-option", dest="engine_options", action="append", default=[],
                        metavar="KEY=VALUE",
                        help="an option for the engine, typed by its default (repeatable)")


def engine_options(spec: str, pairs) -> dict:
    """``--engine-option`` pairs as keyword arguments of ``spec`` (one-line errors)."""
    from engines import parse_engine_options
    return parse_engine_options(spec, list(pairs or ()))
