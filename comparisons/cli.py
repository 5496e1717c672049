"""`bicycle-xval`: the command line.

    bicycle-xval models
    bicycle-xval scenarios
    bicycle-xval inverse-dynamics --model thesis --scenario zigzag --out FILE.csv
    bicycle-xval simulate --model thesis --scenario stability-psid10 --out FILE.csv
    bicycle-xval run [--out DIR] [--scenarios a,b] [--engines e,f] [--quick] [--jobs N]
                     [--tolerances FILE]
    bicycle-xval diagnose FILE [--against MODEL] [--engines pinocchio,exudyn] [--json OUT]
    bicycle-xval eigenvalues --model benchmark --speeds 0:10:0.01 --out FILE.csv

Exit status: 0 success, 1 a run failed (solver failure) or a check did not hold,
2 usage error (bad option, unknown model or scenario, bad parameter file), always with a
one-line message.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

EXIT_OK, EXIT_FAIL, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    """A user mistake: reported on one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2 (argparse prints usage + message otherwise)
        raise UsageError(f"{message} (see '{self.prog} --help')")


def _csv_frame(t, q, dq, ddq, extra: dict):
    import pandas as pd

    from reference_model import COORDINATES

    cols = {"t": t}
    cols.update({n: q[:, i] for i, n in enumerate(COORDINATES)})
    cols.update({f"d_{n}": dq[:, i] for i, n in enumerate(COORDINATES)})
    cols.update({f"dd_{n}": ddq[:, i] for i, n in enumerate(COORDINATES)})
    cols.update(extra)
    return pd.DataFrame(cols)


def _write_csv(frame, out: Path) -> None:
    out.parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(out, index=False, float_format="%.17g")


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


def inverse_dynamics_frame(model, sc, reproject: bool = False):
    from reference_model.scenarios import run_inverse
    res = run_inverse(model, sc, reproject=reproject)
    m = res.motion
    extra = {n: res.T[:, i] for i, n in enumerate(("Mdir", "Mped", "Mvue"))}
    extra.update({f"lambda_{k + 1}": res.lam[:, k] for k in range(5)})
    return _csv_frame(m.t, m.q, m.dq, res.ddq, extra), res


def simulation_frame(traj):
    extra = {f"C_{k + 1}": traj.C[:, k] for k in range(5)}
    return _csv_frame(traj.t, traj.q, traj.dq, traj.ddq, extra)


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
    frame, res = inverse_dynamics_frame(model, sc, args.reproject)
    _write_csv(frame, args.out)
    C = model.constraint_residual(res.motion.q, res.motion.dq)
    print(f"{sc.name} on {model.name} ({model.contact} contact): {len(frame)} samples -> {args.out}")
    print(f"  max |T| = [{', '.join(f'{v:.6g}' for v in np.abs(res.T).max(0))}] N m "
          f"(Mdir, Mped, Mvue); max |C| = {np.abs(C).max():.2e}")
    return EXIT_OK


def cmd_simulate(args) -> int:
    if not 0 < args.rtol < 1:
        raise UsageError(f"--rtol must be in (0, 1); got {args.rtol}")
    if not args.atol > 0:
        raise UsageError(f"--atol must be positive; got {args.atol}")
    if not 0 < args.fall_limit <= np.pi:
        raise UsageError(f"--fall-limit must be an angle in (0, pi] rad; got {args.fall_limit}")
    if args.engine != "exudyn" and (args.build is not None or args.step is not None):
        raise UsageError("--build and --step apply to --engine exudyn only")
    if args.step is not None and not 0 < args.step <= 0.1:
        raise UsageError(f"--step must be in (0, 0.1] s; got {args.step}")
    sc = _scenario(args.scenario, "forward")
    model = _load(args.model, args.contact)
    from engines import load_engine
    if args.engine == "exudyn":
        options = {k: v for k, v in (("build", args.build), ("step", args.step)) if v is not None}
        engine = load_engine("exudyn", model, **options)
        traj = engine.simulate(sc, fall_limit=args.fall_limit)
    else:
        engine = load_engine(args.engine, model)
        traj = engine.simulate(sc, constraints=args.constraints, rtol=args.rtol, atol=args.atol,
                               fall_limit=args.fall_limit)
    _write_csv(simulation_frame(traj), args.out)
    how = ", ".join(f"{k}: {v}" for k, v in traj.settings.items()
                    if k in ("constraints", "build", "step", "solver") and v is not None)
    print(f"{sc.name} on {args.engine} / {model.name} ({model.contact} contact, {how}): "
          f"{traj.status}: {traj.message}")
    if "initial_correction" in traj.settings:
        print(f"  initial state: {traj.settings['initial_correction']}")
    print(f"  {len(traj.t)} samples to t = {traj.t_end:.4f} s -> {args.out}; "
          f"max |C| = {np.abs(traj.C).max():.2e}")
    return EXIT_FAIL if traj.status == "failed" else EXIT_OK


def cmd_run(args) -> int:
    import os

    from .runner import run_report
    from .tolerances import TOLERANCES_ENV, ToleranceError, load_tolerances
    if args.jobs is not None and not 1 <= args.jobs <= 64:
        raise UsageError(f"--jobs must be between 1 and 64; got {args.jobs}")
    if args.tolerances is not None:
        if not args.tolerances.is_file():
            raise UsageError(f"--tolerances: no file {str(args.tolerances)!r}; copy "
                             "comparisons/tolerances.toml and edit it")
        try:
            from .tolerances import TOLERANCES_FILE
            shipped = load_tolerances(TOLERANCES_FILE)
            mine = load_tolerances(args.tolerances)
        except ToleranceError as exc:
            raise UsageError(f"--tolerances: {exc}") from None
        missing = sorted(set(shipped) - set(mine))
        if missing:
            raise UsageError(f"--tolerances: {args.tolerances} lacks [{missing[0]}]"
                             f"{f' (and {len(missing) - 1} more)' if len(missing) > 1 else ''}; "
                             "start from a copy of comparisons/tolerances.toml")
    before = os.environ.get(TOLERANCES_ENV)
    try:
        if args.tolerances is not None:   # worker processes inherit it
            os.environ[TOLERANCES_ENV] = str(args.tolerances.resolve())
        return run_report(args.out, scenarios=args.scenarios, quick=args.quick,
                          engines=args.engines, workers=args.jobs)
    finally:
        if before is None:
            os.environ.pop(TOLERANCES_ENV, None)
        else:
            os.environ[TOLERANCES_ENV] = before


def build_parser() -> argparse.ArgumentParser:
    from engines import ENGINES
    from reference_model.solvers import CONSTRAINT_HANDLING, DEFAULT_FALL_LIMIT

    p = _Parser(prog="bicycle-xval", description="Cross-validation harness for the thesis bicycle.")
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
    s.add_argument("--engine", choices=ENGINES, default="reference",
                   help="engine to run the scenario on [reference]")
    s.add_argument("--build", choices=("redundant", "tree"), default=None,
                   help="Exudyn only: redundant bodies + joints, or the kinematic tree [engine default]")
    s.add_argument("--step", type=float, default=None, help="Exudyn only: time step, s [engine default]")
    s.add_argument("--constraints", choices=CONSTRAINT_HANDLING, default=None,
                   help="constraint handling [the scenario's: baumgarte a1 = a2 = 10, as the thesis]")
    s.add_argument("--rtol", type=float, default=1e-10, help="relative tolerance [1e-10]")
    s.add_argument("--atol", type=float, default=1e-12, help="absolute tolerance [1e-12]")
    s.add_argument("--fall-limit", type=float, default=DEFAULT_FALL_LIMIT,
                   help=f"stop when |theta| reaches this angle, rad [{DEFAULT_FALL_LIMIT}]")
    s.set_defaults(func=cmd_simulate)

    s = sub.add_parser("run", help="run every scenario and write the report")
    s.add_argument("--out", type=Path, default=Path("reports/latest"), help="output folder [reports/latest]")
    s.add_argument("--scenarios", default=None, help="comma-separated subset of scenarios")
    s.add_argument("--engines", default=None,
                   help="comma-separated engines to compare with the reference [all: reference,pinocchio,exudyn]")
    s.add_argument("--quick", action="store_true", help="a fast subset")
    s.add_argument("--jobs", type=int, default=None,
                   help="worker processes for the engine runs [number of CPUs, at most 4]")
    s.add_argument("--tolerances", type=Path, default=None,
                   help="a tolerance file replacing comparisons/tolerances.toml (same tables)")
    s.set_defaults(func=cmd_run)

    from .diagnose import add_diagnose_parser
    from .eigenvalues import add_eigenvalues_parser
    add_diagnose_parser(sub)
    add_eigenvalues_parser(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    from reference_model import ModelEvaluationError, ParameterError
    from reference_model.scenarios import UnknownScenarioError
    from engines import EngineError
    from reference_model.solvers import ConstraintSolveError

    try:
        args = build_parser().parse_args(argv)
        return args.func(args)
    except (UsageError, ParameterError, UnknownScenarioError) as exc:
        print(f"bicycle-xval: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except (ModelEvaluationError, ConstraintSolveError, EngineError) as exc:
        print(f"bicycle-xval: failed: {exc}", file=sys.stderr)
        return EXIT_FAIL
    except OSError as exc:
        print(f"bicycle-xval: error: {exc.strerror or exc}: {exc.filename or ''}", file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":
    # Under `python -m comparisons.cli` this file runs as __main__; re-enter through the package
    # module so exception classes are the ones the other modules import.
    from comparisons.cli import main as _main
    sys.exit(_main())
