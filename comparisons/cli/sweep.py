"""``bicycle-xval sweep``: cross-validation and stability across a design space, on Dask.

    bicycle-xval sweep --model benchmark --vary trail=0:0.2:41 --checks terms,eigen --out DIR
    bicycle-xval sweep --model benchmark --sample 1000 --spread 20 --seed 1 --out DIR \\
                       [--engines e,f] [--workers N | --scheduler tcp://host:8786]

What each bicycle gets and the columns: `comparisons.stages.sweep_task`; the bicycles (grids,
samples, the spec hash): `comparisons.stages.sweep_spec`; chunks, Dask, Parquet, resume:
`comparisons.stages.sweep`; the summary report: `comparisons.report.sweep_report`.
Exit status: 0 every bicycle agrees, 1 some bicycle disagrees or failed (listed in the report),
2 a bad spec (one line naming the option and the fix).
"""

from __future__ import annotations

import sys
from pathlib import Path

from .errors import EXIT_FAIL, EXIT_INTERRUPTED, EXIT_OK, EXIT_TERMINATED, UsageError
from .sweep_limits import add_limit_arguments, check_limits

MAX_WORKERS = 1024
#: what the sweep imports beyond the core (its extra, pyproject.toml): Dask's distributed
#: scheduler, the progress bar, Parquet
SWEEP_MODULES = ("dask", "distributed", "tqdm", "pyarrow")


def add_sweep_parser(sub) -> None:
    s = sub.add_parser("sweep", help="cross-validate and map stability over many bicycles (Dask)")
    s.add_argument("--model", default="benchmark",
                   help="base model: a named model or a parameter .toml file [benchmark]")
    s.add_argument("--vary", action="append", default=[], metavar="NAME=LOW:HIGH:N",
                   help="a grid over a model parameter or trail, head_angle, wheelbase (SI, "
                        "rad); repeat for a product grid")
    s.add_argument("--sample", type=int, default=None, metavar="N",
                   help="N random bicycles around the base (with --spread)")
    s.add_argument("--spread", type=float, default=None, metavar="P",
                   help="per cent around the base for --sample (inertias kept physical)")
    s.add_argument("--seed", type=int, default=0, help="seed of samples and states [0]")
    s.add_argument("--engines", default=None,
                   help="engines compared with the reference, comma-separated ('bicycle-xval "
                        "engines' lists them) [every installed engine with terms that models "
                        "the base model's front contact]")
    s.add_argument("--checks", default="terms,eigen",
                   help="terms, eigen, runs (comma-separated) [terms,eigen]")
    s.add_argument("--states", type=int, default=8,
                   help="random states per bicycle for the terms [8]")
    from .tolerance_option import add_tolerances_argument
    add_tolerances_argument(s)
    s.add_argument("--out", type=Path, required=True, help="output folder")
    s.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="a running Dask scheduler, e.g. tcp://host:8786 [a local cluster]")
    s.add_argument("--workers", type=int, default=None,
                   help="local cluster workers [the machine's cores]")
    add_limit_arguments(s)
    s.add_argument("--no-progress", action="store_true", help="no progress bar")
    s.set_defaults(func=cmd_sweep)


def spec_from_args(args):
    """The `SweepSpec` of the options, or a `UsageError` (one line)."""
    from engines import EngineNotInstalled, EngineSpecError
    from engines.registry import resolve
    from reference_model import resolve_model, load_model

    from ..stages.sweep_spec import SpecError, make_spec
    resolve_model(args.model)        # unknown model: ParameterError (one line, exit 2)
    base = load_model(args.model).params
    engines = None if args.engines is None else \
        tuple(e.strip() for e in args.engines.split(",") if e.strip())
    if engines == ():
        raise UsageError("--engines: give at least one engine (see 'bicycle-xval engines')")
    for e in engines or ():       # None: make_spec's default, every installed term engine
        try:
            resolve(e)
        except (EngineSpecError, EngineNotInstalled) as exc:
            raise UsageError(f"--engines {e}: {exc}") from None
    checks = tuple(c.strip() for c in args.checks.split(",") if c.strip())
    from .tolerance_option import tolerances_from
    tolerances = tolerances_from(args)      # in the spec: every Dask task, and the hash
    try:
        return make_spec(base, varies=args.vary, sample=args.sample, spread=args.spread,
                         seed=args.seed, engines=engines, checks=checks, n_states=args.states,
                         tolerances=tolerances)
    except SpecError as exc:
        raise UsageError(str(exc)) from None


def cmd_sweep(args) -> int:
    from engines.registry import missing_modules
    missing = missing_modules(SWEEP_MODULES)
    if missing:
        raise UsageError(f"bicycle-xval sweep needs {', '.join(missing)} (not installed): "
                         "pip install 'bicycle-xval[sweep]'")
    if args.scheduler and args.workers is not None:
        raise UsageError("--scheduler and --workers: the workers of a running scheduler are "
                         "its own; give one of them")
    if args.workers is not None and not 1 <= args.workers <= MAX_WORKERS:
        raise UsageError(f"--workers must be between 1 and {MAX_WORKERS}; got {args.workers}")
    if args.scheduler and not args.scheduler.startswith(("tcp://", "tls://", "inproc://", "ws://",
                                                         "wss://", "ucx://")):
        raise UsageError(f"--scheduler {args.scheduler!r}: give an address like "
                         "tcp://host:8786 (what 'dask scheduler' prints)")
    if args.out.exists() and not args.out.is_dir():
        raise UsageError(f"--out {args.out} is a file; give a folder")
    check_limits(args)
    spec = spec_from_args(args)
    from ..report.sweep_report import write_sweep_report
    from ..stages.sweep import run_sweep
    try:
        result = run_sweep(spec, args.out, scheduler=args.scheduler, workers=args.workers,
                           progress=not args.no_progress, bicycle_timeout=args.bicycle_timeout,
                           notify=lambda line: print(line, file=sys.stderr, flush=True))
    except KeyboardInterrupt as exc:      # Ctrl-C or SIGTERM: the finished chunks stay
        from ..stages.pool import Terminated
        from ..stages.sweep_spec import spec_hash
        what = "terminated" if isinstance(exc, Terminated) else "interrupted"
        print(f"bicycle-xval: {what}; the finished chunks are kept in "
              f"{args.out / 'chunks' / spec_hash(spec)}: rerun the same command to resume",
              file=sys.stderr)
        code = EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED
        if getattr(args, "as_program", False):   # cluster closed, chunks on disk: skip the
            from ..stages.signals import exit_at_once   # interpreter's shutdown (~1.4 s here)
            exit_at_once(code)
        return code
    except OSError as exc:
        if args.scheduler and not isinstance(exc, (FileNotFoundError, PermissionError)):
            raise UsageError(f"--scheduler {args.scheduler}: cannot connect ({exc}); start one "
                             "with 'dask scheduler' or leave --scheduler out") from None
        raise
    summary = write_sweep_report(spec, result)
    print(f"sweep {result.hash}: {result.n_bicycles} bicycles in {result.chunks} chunks "
          f"({result.computed} computed, {result.skipped} already done) in {result.seconds:.1f} s; "
          f"{summary['agree']} agree, {summary['disagree']} disagree, {summary['failed']} failed, "
          f"{summary['invalid']} invalid -> {result.results}, {summary['report']}",
          file=sys.stderr)
    return EXIT_OK if summary["agree"] == result.n_bicycles else EXIT_FAIL
