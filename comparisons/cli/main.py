"""`bicycle-xval`: the command line.

    bicycle-xval models
    bicycle-xval scenarios
    bicycle-xval inverse-dynamics --model thesis --scenario zigzag --out FILE.csv
    bicycle-xval simulate --model thesis --scenario stability-psid10 --out FILE.csv
    bicycle-xval run [--out DIR] [--force] [--scenarios a,b] [--engines e,f] [--quick] [--jobs N]
                     [--tolerances FILE] [--model NAME|FILE ...] [--scenario-file FILE ...]
    bicycle-xval diagnose FILE [--against MODEL] [--engines e,f] [--json OUT]
                          [--tolerances FILE]
    bicycle-xval eigenvalues --model benchmark --speeds 0:10:0.01 --out FILE.csv
    bicycle-xval import FILE --from benchmark --out my.toml [--name NAME]
                        [--allow-triangle-violation]
    bicycle-xval export --model NAME|FILE --format benchmark --out PATH
    bicycle-xval sweep --model NAME|FILE --vary NAME=LOW:HIGH:N ... | --sample N --spread P
                       [--seed S] [--engines ...] [--checks terms,eigen,runs] --out DIR
                       [--tolerances FILE] [--scheduler ADDRESS | --workers N]

Exit status: 0 success, 1 a run failed (solver failure) or a check did not hold,
2 usage error (bad option, unknown model or scenario, bad parameter file), always with a
one-line message.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

from ..report import frames
from ..stages.files import write_csv
from .errors import EXIT_FAIL, EXIT_INTERRUPTED, EXIT_OK, EXIT_TERMINATED, EXIT_USAGE, UsageError


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2 (argparse prints usage + message otherwise)
        raise UsageError(f"{message} (see '{self.prog} --help')")


def _load(model_name: str, contact: str | None):
    from reference_model import load_model
    return load_model(model_name, contact=contact)


def _scenario(name: str, kind: str):
    from reference_model.scenarios import get_scenario
    sc = get_scenario(name)
    if sc.kind != kind:
        other = "simulate" if sc.kind == "forward" else "inverse-dynamics"
        article = "an" if sc.kind[0] in "aeiou" else "a"
        raise UsageError(f"scenario {name!r} is {article} {sc.kind} scenario; run it with '{other}'")
    return sc


def cmd_models(args) -> int:
    from reference_model import NAMED_MODELS
    for name, (path, contact) in NAMED_MODELS.items():
        print(f"{name:14s} contact={contact:7s} {path}")
    return EXIT_OK


def cmd_scenarios(args) -> int:
    from reference_model.scenarios import SCENARIOS
    for sc in SCENARIOS.values():
        print(f"{sc.name:18s} {sc.kind:8s} {sc.description}")
    return EXIT_OK


def cmd_inverse_dynamics(args) -> int:
    sc = _scenario(args.scenario, "inverse")
    model = _load(args.model, args.contact)
    from reference_model.scenarios import run_inverse
    res = run_inverse(model, sc, reproject=args.reproject)
    frame = frames.inverse_frame(res)
    write_csv(frame, args.out)
    C = model.constraint_residual(res.motion.q, res.motion.dq)
    print(f"{sc.name} on {model.name} ({model.contact} contact): {len(frame)} samples -> {args.out}")
    print(f"  max |T| = [{', '.join(f'{v:.6g}' for v in np.abs(res.T).max(0))}] N m "
          f"(Mdir, Mped, Mvue); max |C| = {np.abs(C).max():.2e}")
    if res.motion.info.get("initial_correction"):
        print(f"  initial state: {res.motion.info['initial_correction']}")
    return EXIT_OK


def cmd_simulate(args) -> int:
    if not RTOL_MIN <= args.rtol < 1:
        raise UsageError(f"--rtol must be in [{RTOL_MIN:g}, 1) (scipy's DOP853 cannot go below "
                         f"about 100 machine epsilons); got {args.rtol}")
    if not args.atol > 0:
        raise UsageError(f"--atol must be positive; got {args.atol}")
    if not 0 < args.fall_limit <= np.pi:
        raise UsageError(f"--fall-limit must be an angle in (0, pi] rad; got {args.fall_limit}")
    from engines.facts import engine_facts
    fixed = engine_facts(args.engine).fixed_step
    options = _fixed_step_options(args, fixed)
    sc = _scenario(args.scenario, "forward")
    model = _load(args.model, args.contact)
    from engines import load_engine, split_options

    from .engines import engine_options
    options = {**engine_options(args.engine, args.engine_options), **options}
    engine = load_engine(args.engine, model, **options)
    settings = {"fall_limit": args.fall_limit}
    if fixed is None:   # the reference's integrator settings, where the engine takes them
        settings.update(constraints=args.constraints, rtol=args.rtol, atol=args.atol)
    taken, ignored = split_options(engine.simulate, settings)
    ignored = {k: v for k, v in ignored.items() if v is not None}
    from ..stages.pool import call_in_worker
    traj = call_in_worker(engine.simulate, sc, **taken)   # a worker: stoppable even in C++
    write_csv(frames.simulation_frame(traj), args.out)
    how = ", ".join(f"{k}: {v}" for k, v in traj.settings.items()
                    if k in ("constraints", "build", "step", "solver") and v is not None)
    print(f"{sc.name} on {args.engine} / {model.name} ({model.contact} contact, {how}): "
          f"{traj.status}: {traj.message}")
    if ignored:
        print(f"  not applied (the engine's simulate does not take them): "
              f"{', '.join(f'{k} = {v}' for k, v in ignored.items())}")
    if "initial_correction" in traj.settings:
        print(f"  initial state: {traj.settings['initial_correction']}")
    print(f"  {len(traj.t)} samples to t = {traj.t_end:.4f} s -> {args.out}; "
          f"max |C| = {np.abs(traj.C).max():.2e}")
    return EXIT_FAIL if traj.status == "failed" else EXIT_OK


def _fixed_step_options(args, fixed) -> dict:
    """The engine options of ``--build`` and ``--step``: a variant the engine's fixed-step
    integrator declares (its option set) and its step option (`engines.facts.FixedStep`). An
    engine that declares no fixed-step integrator takes neither (a usage error)."""
    if args.build is None and args.step is None:
        return {}
    if fixed is None:
        raise UsageError(f"--build and --step apply to an engine with a fixed-step integrator; "
                         f"engine {args.engine!r} declares none (its options: --engine-option "
                         "key=value, see 'bicycle-xval engines')")
    options = {}
    if args.build is not None:
        if args.build not in fixed.variant_names:
            raise UsageError(f"--build {args.build}: engine {args.engine!r} has no such variant; "
                             f"choose one of: {', '.join(fixed.variant_names)}")
        options.update(fixed.variant_options(args.build))
    if args.step is not None:
        # the engine checks that the step divides the scenario's output grid, before the run
        if not 0 < args.step <= 0.1:
            raise UsageError(f"--step must be in (0, 0.1] s; got {args.step}")
        options[fixed.option] = args.step
    return options


def cmd_run(args) -> int:
    from ..report.figure_cache import FigureCache
    from ..report.writer import write_report
    from ..stages.pipeline import SelectionError, run_comparison, select
    from ..stages.pool import MAX_WORKERS
    if args.jobs is not None and not 1 <= args.jobs <= MAX_WORKERS:
        raise UsageError(f"--jobs must be between 1 and {MAX_WORKERS}; got {args.jobs}")
    if args.stage_timeout is not None and not 0 < args.stage_timeout < float("inf"):
        raise UsageError(f"--stage-timeout must be a positive number of seconds; got "
                         f"{args.stage_timeout:g}")
    from .tolerance_option import tolerances_from
    tolerances = tolerances_from(args)     # read once, checked before the runs
    from ..stages.ownership import OutFolderError, check_out_folder
    try:
        check_out_folder(args.out, args.force)     # before the runs, and again at the swap
    except OutFolderError as exc:
        raise UsageError(str(exc)) from None
    try:
        opts = select(args.scenarios, args.quick, args.engines)
    except SelectionError as exc:
        raise UsageError(str(exc)) from None
    from ..stages.pipeline import SECTIONS
    sections = tuple(x.strip() for x in (args.sections or ",".join(SECTIONS)).split(",") if x.strip())
    if sections == ("none",):
        sections = ()
    unknown = [x for x in sections if x not in SECTIONS]
    if unknown:
        raise UsageError(f"--sections: unknown section {unknown[0]!r}; choose from "
                         f"{', '.join(SECTIONS)} (comma-separated), or none for the scenarios only")
    opts = dataclasses.replace(opts, workers=args.jobs, sections=sections,
                               figures=args.figures or "", tolerances=tolerances,
                               stage_timeout=args.stage_timeout,
                               engine_options=_run_engine_options(opts.engines, args.engine_options))
    from .bicycles import with_models
    opts = with_models(opts, args.model, args.scenario_file)
    result = run_comparison(opts, _progress)   # opts.tolerances goes to every stage's args
    _progress("writing the report ...")
    try:
        # --redraw: nothing read back, every figure drawn and stored afresh
        cache = FigureCache.default(read=not args.redraw)
        path = write_report(result, args.out, data=not args.no_data, html=not args.no_html,
                            progress=_progress, force=args.force, figure_cache=cache)
    except OutFolderError as exc:                  # the folder changed during the runs
        raise UsageError(str(exc)) from None
    passed = result.summary["passed"]
    _progress(f"report written to {path} and report.html in "
              f"{result.timings['total_seconds']:.1f} s of runs: "
              f"{'all within tolerance' if passed else 'SOMETHING FAILED'}")
    return EXIT_OK if passed else EXIT_FAIL


def _run_engine_options(engines, pairs) -> tuple:
    """``--engine-option key=value`` of ``run``: each pair goes to every selected engine (other
    than the reference) that takes that option; a pair no selected engine takes is an error."""
    if not pairs:
        return ()
    from engines import EngineSpecError, parse_engine_options
    out, used = {}, set()
    for spec in engines:
        if spec == "reference":
            continue
        for pair in pairs:
            try:
                value = parse_engine_options(spec, [pair])
            except EngineSpecError:
                continue
            out.setdefault(spec, {}).update(value)
            used.add(pair)
    unused = [p for p in pairs if p not in used]
    if unused:
        raise UsageError(f"--engine-option {unused[0]}: no selected engine takes it; see "
                         "'bicycle-xval engines' for each engine's options")
    return tuple((spec, tuple(sorted(o.items()))) for spec, o in out.items())


def _progress(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


class _Version(argparse.Action):
    """``--version``: asked of git only when given (not on every start, as argparse's own)."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        from ..provenance import guide_path, package_provenance, version_line
        guide = guide_path()
        print(version_line(package_provenance()))
        print(f"reading guide: {guide or 'not found (docs/report.md)'}")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    from reference_model.solvers import CONSTRAINT_HANDLING, DEFAULT_FALL_LIMIT

    p = _Parser(prog="bicycle-xval", description="Cross-validation harness for the thesis bicycle.")
    p.add_argument("--version", action=_Version, help="print the version (and the git commit of "
                   "a checkout) and where the reading guide docs/report.md is, and exit")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    def model_opts(sp):
        sp.add_argument("--model", default="thesis",
                        help="named model (thesis, thesis-disc, benchmark) or a parameter .toml file [thesis]")
        sp.add_argument("--contact", choices=("thesis", "disc"), default=None,
                        help="override the model's front-contact model")

    s = sub.add_parser("models", help="list the named models")
    s.set_defaults(func=cmd_models)
    s = sub.add_parser("scenarios", help="list the scenarios with one-line descriptions")
    s.set_defaults(func=cmd_scenarios)

    s = sub.add_parser("inverse-dynamics", help="inverse kinematics + the thesis's 13x13 inverse dynamics")
    model_opts(s)
    s.add_argument("--scenario", required=True, help="an inverse scenario (check, zigzag)")
    s.add_argument("--out", required=True, type=Path, help="CSV file to write")
    s.add_argument("--reproject", action="store_true",
                   help="solve beta from [rD]_z = 0 at every step instead of integrating it")
    s.set_defaults(func=cmd_inverse_dynamics)

    s = sub.add_parser("simulate", help="forward dynamics of a scenario")
    model_opts(s)
    s.add_argument("--scenario", required=True, help="a forward scenario (replay, stability-psid*)")
    s.add_argument("--out", required=True, type=Path, help="CSV file to write")
    s.add_argument("--engine", default="reference",
                   help="engine to run the scenario on: a name (see 'bicycle-xval engines'), "
                        "package.module:Class or path/file.py:Class [reference]")
    from .engines import add_engine_option_argument
    add_engine_option_argument(s)
    s.add_argument("--build", default=None, metavar="VARIANT",
                   help="an engine with a fixed-step integrator only: one of the model variants "
                        "it declares (e.g. a kinematic tree or redundant bodies + joints) "
                        "[engine default]")
    s.add_argument("--step", type=float, default=None,
                   help="an engine with a fixed-step integrator only: its time step, s; it must "
                        "divide the scenario's output interval [engine default]")
    s.add_argument("--constraints", choices=CONSTRAINT_HANDLING, default=None,
                   help="constraint handling [the scenario's: baumgarte a1 = a2 = 10, as the thesis]")
    s.add_argument("--rtol", type=float, default=1e-10, help="relative tolerance [1e-10]")
    s.add_argument("--atol", type=float, default=1e-12, help="absolute tolerance [1e-12]")
    s.add_argument("--fall-limit", type=float, default=DEFAULT_FALL_LIMIT,
                   help=f"stop when |theta| reaches this angle, rad [{DEFAULT_FALL_LIMIT}]")
    s.set_defaults(func=cmd_simulate)

    s = sub.add_parser("run", help="run every scenario and write the report")
    s.add_argument("--out", type=Path, default=Path("reports/latest"), help="output folder [reports/latest]")
    s.add_argument("--force", action="store_true",
                   help="write into a non-empty --out that holds no earlier report: only the "
                        "files the report writes are replaced, the rest stays")
    s.add_argument("--scenarios", default=None, help="comma-separated subset of scenarios")
    s.add_argument("--engines", default=None,
                   help="comma-separated engines to compare with the reference: names (see "
                        "'bicycle-xval engines') or specs package.module:Class, path/file.py:Class "
                        "[every installed engine]")
    from .engines import add_engine_option_argument as _add_opt
    _add_opt(s)
    s.add_argument("--quick", action="store_true", help="a fast subset")
    from ..stages.pipeline import SECTIONS
    s.add_argument("--sections", default=None,
                   help=f"engine sections besides the scenarios, comma-separated: "
                        f"{', '.join(SECTIONS)}, or none [all]")
    s.add_argument("--no-data", action="store_true",
                   help="do not write data/<scenario>_<engine>.csv (the runs' samples)")
    s.add_argument("--no-html", action="store_true",
                   help="do not write report.html (report.md and summary.json only)")
    from ..stages.results import FIGURE_POLICIES
    s.add_argument("--figures", choices=FIGURE_POLICIES, default=None,
                   help="which figures to draw: all, those of the sections where something "
                        "failed, or none [failing with --quick, else all]")
    s.add_argument("--redraw", action="store_true",
                   help="draw every figure anew instead of reading back the ones whose drawing "
                        "code and data are unchanged since an earlier run (kept in "
                        "~/.cache/bicycle-xval/figures, or $BICYCLE_XVAL_CACHE/figures)")
    s.add_argument("--jobs", type=int, default=None,
                   help="worker processes [the machine's cores, never more than the stages]")
    s.add_argument("--stage-timeout", type=float, default=None, metavar="SECONDS",
                   help="time limit of every stage; a stage past it is cancelled and reported "
                        "as timed out [each stage's expected time x 20, at least 60 s]")
    from .tolerance_option import add_tolerances_argument
    add_tolerances_argument(s)
    from .bicycles import add_run_model_options
    add_run_model_options(s)
    s.set_defaults(func=cmd_run)

    from .bicycles import add_import_parser
    from .diagnose import add_diagnose_parser
    from .eigenvalues import add_eigenvalues_parser
    from .compare_trajectory import add_compare_trajectory_parser
    from .engines import add_engines_parser
    add_engines_parser(sub)
    add_compare_trajectory_parser(sub)
    from .export import add_export_parser
    add_diagnose_parser(sub)
    add_eigenvalues_parser(sub)
    add_import_parser(sub)
    add_export_parser(sub)
    __import__("comparisons.cli.sweep", fromlist=["x"]).add_sweep_parser(sub)
    return p


#: scipy's DOP853 raises a smaller rtol to 100 eps (2.2e-14), with a warning
RTOL_MIN = 2.3e-14

#: options whose value may start with a minus sign (a negative speed): argparse would read
#: ``--speeds -5:5:1`` as two options, so the pair is joined into ``--speeds=-5:5:1``
SIGNED_VALUE_OPTIONS = ("--speeds",)


def _join_signed_values(argv: list[str]) -> list[str]:
    out, k = [], 0
    while k < len(argv):
        a = argv[k]
        if a in SIGNED_VALUE_OPTIONS and k + 1 < len(argv) and argv[k + 1][:2] in {
                f"-{d}" for d in "0123456789."}:
            out.append(f"{a}={argv[k + 1]}")
            k += 2
            continue
        out.append(a)
        k += 1
    return out


def main(argv: list[str] | None = None) -> int:
    from reference_model import ModelEvaluationError, ParameterError
    from reference_model.scenarios import UnknownScenarioError
    from engines import EngineError, EngineSpecError
    from reference_model.codegen import CodegenError
    from reference_model.solvers import ConstraintSolveError

    import warnings

    def _one_line_warning(message, category, filename, lineno, file=None, line=None):
        print(f"bicycle-xval: warning: {message}", file=sys.stderr)
    show = warnings.showwarning

    from ..stages.signals import Terminated, exit_at_once, install_handlers, restore_handlers
    as_program = argv is None
    # SIGTERM and Ctrl-C unwind like an exception (staging folders go, workers are killed); a
    # second one during the unwind ends the process at once
    previous = install_handlers("bicycle-xval")
    warnings.showwarning = _one_line_warning   # a ParameterWarning is one line, like an error
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        args = build_parser().parse_args(_join_signed_values(argv))
        args.as_program = as_program      # a command that ends on an interrupt may exit at once
        return args.func(args)
    except (UsageError, ParameterError, UnknownScenarioError, EngineSpecError) as exc:
        print(f"bicycle-xval: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except (ModelEvaluationError, ConstraintSolveError, EngineError, CodegenError) as exc:
        print(f"bicycle-xval: failed: {exc}", file=sys.stderr)
        return EXIT_FAIL
    except OSError as exc:
        print(f"bicycle-xval: error: {exc.strerror or exc}: {exc.filename or ''}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt as exc:
        what = "terminated" if isinstance(exc, Terminated) else "interrupted"
        print(f"bicycle-xval: {what}; nothing written (an existing report is as it was)",
              file=sys.stderr)
        code = EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED
        if as_program:   # workers reaped, staging removed: skip the interpreter's shutdown
            exit_at_once(code)
        return code
    finally:
        restore_handlers(previous)
        warnings.showwarning = show


if __name__ == "__main__":
    # Under `python -m comparisons.cli` this file runs as __main__; re-enter through the package
    # module so exception classes are the ones the other modules import.
    from comparisons.cli.main import main as _main
    sys.exit(_main())
