"""`bicycle-xval run` as a computation: every stage, in parallel where independent, judged.

Stages (each a top-level call, run in worker processes by `pool.run_tasks`, longest first):

* every selected scenario on every engine setup (`runs.run_one`), the reference included, and
  the meaningful horizon of each forward scenario (two reference runs 1e-9 rad/s apart): the
  pipeline's own core;
* the stages of `catalog.STAGES`, each one module that says what tasks it needs and how it
  assembles their results (`stage.Stage`): the stability picture of each ``--model``, every
  engine term by term, the fixed-step engines' trajectories and convergence order, the energy
  drift, the soft-contact engines' study, the benchmark bicycle, each model's linearization
  against the closed form, and fault injection. Which engines each concerns comes from their
  declared facts (`engines.facts`): no stage names an engine.

With ``--model`` (`Options.models`) the scenarios run as cases bound to each model
(`cases.build_cases`: what makes sense on another bicycle, and why the rest is not run), and
every stage runs on each model; the thesis's and the benchmark's own sections are the run
without --model. ``--scenario-file`` adds cases to either run. Without them the run is exactly
the thesis's.

Then, in this process, what depends on them: each scenario's comparisons, the thesis's claims,
the localization of anything that failed, the summary table. `run_comparison` returns a
`ComparisonResult` of plain data; `comparisons.report` writes it. Run times are kept apart
(``timings``) so identical inputs give byte-identical reports.
"""

from __future__ import annotations

import dataclasses
import os
import platform
import sys
import time
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Callable

from engines.runs import Run

from .. import provenance
from ..judgments.claims import judge_claims
from ..judgments.rows import Comparison
from ..judgments.tolerances import Tolerances, load_tolerances
from ..judgments.summary import summary_table
from .catalog import SECTIONS as _SECTIONS, STAGES
from .isolated import isolated
from .pool import Limits, Task, run_tasks
from .results import FIGURE_POLICIES, Figure, Section, Text
from .stage import Plan, failed_section

QUICK = ("check", "zigzag", "check-forward", "stability-psid10")
#: the parts of a run besides the scenarios, selectable with --sections (all by default)
SECTIONS = _SECTIONS


class SelectionError(ValueError):
    """A scenario or engine selection that cannot be run (the CLI reports it as a usage error)."""


@dataclass(frozen=True)
class Options:
    """What `bicycle-xval run` was asked to do."""

    scenarios: tuple[str, ...]
    engines: tuple[str, ...]          # engine names or specs, reference first
    quick: bool = False
    workers: int | None = None
    models: tuple = ()                # cases.ModelSpec of each --model (none: the thesis's run)
    scenario_files: tuple[str, ...] = ()   # --scenario-file paths
    engine_options: tuple[tuple[str, tuple[tuple[str, object], ...]], ...] = ()   # spec -> options
    sections: tuple[str, ...] = SECTIONS   # which engine sections run besides the scenarios
    figures: str = ""                 # FIGURE_POLICIES; "" = 'failing' with --quick, else 'all'
    not_installed: tuple[tuple[str, str], ...] = ()   # default engines whose extra is missing: why
    #: what every stage judges by (--tolerances, read once by the CLI): passed, as a value, in
    #: each Task's args, so a worker process never reads a file or an environment variable
    tolerances: Tolerances = field(default_factory=load_tolerances)
    stage_timeout: float | None = None   # --stage-timeout (s); None: each stage's from its cost

    @property
    def figure_policy(self) -> str:
        return self.figures or ("failing" if self.quick else "all")

    def options_for(self) -> dict:
        return {spec: dict(opts) for spec, opts in self.engine_options}


@dataclass
class ComparisonResult:
    """Everything the report shows: summary.json's content, the sections in report order, the
    localization of failures, the runs (for the data files) and the run times."""

    options: Options
    summary: dict
    sections: list[Section]
    localization: list[tuple[str, str]]
    runs: dict[tuple[str, str], Run]
    timings: dict = field(default_factory=dict)


def select(scenarios: str | None, quick: bool, engines: str | None) -> Options:
    """The scenario and engine names from the command line's comma-separated lists."""
    from reference_model.scenarios import SCENARIOS
    thesis = [n for n, sc in SCENARIOS.items() if "benchmark" not in sc.tags]
    names = thesis if scenarios is None else [s.strip() for s in scenarios.split(",") if s.strip()]
    if quick and scenarios is None:
        names = list(QUICK)
    if not names:
        raise SelectionError("--scenarios is empty; give a comma-separated list, e.g. check,zigzag")
    for n in names:
        if n not in SCENARIOS:
            raise SelectionError(f"unknown scenario {n!r} in --scenarios; choose from "
                                 f"{', '.join(SCENARIOS)}")
    from engines import default_engines
    chosen = list(default_engines()) if engines is None else [e.strip() for e in engines.split(",")
                                                              if e.strip()]
    from engines import EngineNotInstalled, EngineSpecError, available_engines, not_installed
    from engines.registry import resolve
    # the default list: the engines installed; one whose extra is missing is listed, not run
    absent = tuple((e, r) for e in (chosen if engines is None else ())
                   if (r := not_installed(e)) is not None)
    chosen = [e for e in chosen if e not in dict(absent)]
    for e in chosen:
        if ":" in e:
            try:
                resolve(e)
            except (EngineSpecError, EngineNotInstalled) as exc:
                raise SelectionError(f"--engines: {exc}") from None
        elif e not in available_engines():
            raise SelectionError(f"unknown engine {e!r} in --engines; choose from "
                                 f"{', '.join(available_engines())} or give a spec "
                                 "package.module:Class or path/file.py:Class")
        elif (reason := not_installed(e)) is not None:    # asked for by name: it must run
            raise SelectionError(f"--engines: engine {e!r} is {reason}")
    if "reference" not in chosen:
        chosen.insert(0, "reference")   # everything is compared against it
    return Options(tuple(names), tuple(dict.fromkeys(chosen)), quick, not_installed=absent)


# -- environment -------------------------------------------------------------------------------

def _versions(modules=()) -> dict:
    """The versions of the core's packages and of the modules the engines declare they need
    (``REQUIRES``): the version of the distribution named like the module, else of the one
    that installs it (the module ``pydrake`` comes with the distribution ``drake``, which the
    report called "not installed" while Drake ran), else the module's ``__version__``."""
    out = {"python": sys.version.split()[0]}
    providers = None
    for pkg in ("numpy", "scipy", "sympy", "pandas", "matplotlib", *modules):
        try:
            out[pkg] = metadata.version(pkg)
            continue
        except metadata.PackageNotFoundError:
            pass
        if providers is None:
            providers = metadata.packages_distributions()
        try:
            out[pkg] = metadata.version(providers[pkg][0])
        except (KeyError, IndexError, metadata.PackageNotFoundError):
            mod = sys.modules.get(pkg)
            out[pkg] = str(getattr(mod, "__version__", "not installed")) if mod else "not installed"
    return out


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return " ".join(line.split(":", 1)[1].split())
    except OSError:
        pass
    return platform.processor() or platform.machine()


def environment(setups, plan: Plan | None = None) -> dict:
    """What the numbers depend on (no times, no dates: those are in timings.json)."""
    from ..judgments.convergence import REFERENCE_RTOL
    from . import soft_contact as sc
    from .fixed_step import CONVERGENCE_HORIZON, convergence_steps
    facts = plan.facts if plan is not None else {}
    quick = plan.quick if plan is not None else False
    return {
        "packages": _versions(_engine_modules(facts.values())),
        "machine": {"cpu": _cpu(), "cores": os.cpu_count(), "arch": platform.machine(),
                    "platform": platform.platform(terse=True)},
        "solvers": {s.label: s.settings for s in setups},
        "steps": {"fixed_step": {f.name: {"option": f.fixed_step.option, "step": f.fixed_step.step,
                                          "convergence": list(convergence_steps(quick, f.fixed_step))}
                                 for f in facts.values() if f.fixed_step is not None},
                  "convergence_horizon_s": CONVERGENCE_HORIZON,
                  "reference_horizon_runs_rtol": REFERENCE_RTOL, "output_grid_s": 0.01,
                  "soft_contact_study": {"scenario": sc.SCENARIO, "model": sc.MODEL,
                                         "at_time_s": sc.STUDY_TIME, "window_s": sc.window(quick),
                                         "engines": [f.name for f in facts.values()
                                                     if f.soft_contact is not None]}},
        "run_times": "timings.json (kept apart: they vary from run to run)",
    }


def _engine_modules(facts) -> tuple[str, ...]:
    """The top-level modules the engines declare they need, each once."""
    return tuple(dict.fromkeys(m.split(".")[0] for f in facts for m in f.requires))


# -- the stages ----------------------------------------------------------------------------------

def _core_tasks(opts: Options, setups, cases) -> list[Task]:
    """The scenario runs on every setup and the meaningful horizon of each forward scenario."""
    from . import scenarios
    from .runs import cost, run_one
    # the built-in scenarios by name (today's run, unchanged); the others as objects + model
    tasks = [Task(("run", s.label, c.name), run_one,
                  (s, c.name) if c.origin == "built-in" and not opts.models
                  else (s, c.scenario, c.model),
                  cost(s, c.name), f"{c.name} on {s.label}",
                  None if s.engine == "reference" else s.engine)
             for c in cases for s in setups]
    for c in cases:
        sc = c.scenario
        if sc.kind == "forward" and "trajectory" in sc.compared:
            tasks.append(Task(("horizon", c.name), scenarios.horizon_of,
                              (c.name,) if c.origin == "built-in" and not opts.models
                              else (sc,), 0.3, f"{c.name}: meaningful horizon"))
    return tasks


def _stage_tasks(plan: Plan) -> list[Task]:
    """Every selected stage's tasks, their keys namespaced by the stage's name."""
    out = []
    for stage in STAGES:
        if plan.wants(stage.section):
            stage.prepare(plan)    # its shared work once, here, before the workers fork
            out += [dataclasses.replace(t, key=(stage.name, t.key)) for t in stage.tasks(plan)]
    return out


def _buildable(opts: Options):
    """The setups of the selected engines and the engines that cannot be built (each tried on
    the thesis model in a worker): (setups, [(engine, reason)])."""
    from reference_model import load_model
    from .runs import setups_for
    setups = setups_for(opts.engines, opts.options_for())
    dropped = []
    model = load_model("thesis")
    for s in setups:
        if ":" not in s.engine and not opts.options_for().get(s.engine):
            continue   # a registered engine at its declared setups: its stages say what fails
        try:
            isolated(s).build(model)   # in a worker: its __init__ cannot end this process
        except Exception as exc:   # noqa: BLE001 - any failure drops the engine
            dropped.append((s.engine, f"{type(exc).__name__}: {' '.join(str(exc).split())}"))
    return setups, dropped


def run_comparison(opts: Options, progress: Callable[[str], None] = lambda s: None
                   ) -> ComparisonResult:
    """Every stage of the run (module docstring), judged; nothing written."""
    from engines.facts import engine_facts

    from . import faults, scenarios
    from .cases import build_cases
    from .stability import applies, critical as critical_speeds

    t_start = time.perf_counter()
    setups, dropped = _buildable(opts)
    if dropped:
        opts = dataclasses.replace(opts, engines=tuple(e for e in opts.engines
                                                       if e not in {d[0] for d in dropped}))
        setups = [s for s in setups if s.engine not in {d[0] for d in dropped}]
        for name, reason in dropped:
            progress(f"engine {name} dropped: {reason}")
    for name, reason in opts.not_installed:   # not a failure: an extra the user did not install
        progress(f"engine {name} not run: {reason}")
    labels = [s.label for s in setups]
    from engines.registry import resolve
    for spec in opts.engines:   # shared work (e.g. generated code) once, inherited by the workers
        try:
            resolve(spec)[0].prepare()
        except Exception as exc:   # noqa: BLE001 - the engine's stages then say what fails
            progress(f"engine {spec}: preparing failed ({type(exc).__name__}: {exc})")
    case_list, not_run = build_cases(opts.scenarios, opts.models, opts.scenario_files)
    cases = {c.name: c.scenario for c in case_list}
    names = list(cases)
    critical = {m.spec: critical_speeds(m.spec) for m in opts.models if applies(m.contact) is None}
    plan = Plan(opts, tuple(setups), {spec: engine_facts(spec) for spec in opts.engines},
                tuple(case_list), critical)
    tasks = _core_tasks(opts, setups, case_list) + _stage_tasks(plan)
    progress(f"{len(tasks)} stages on {opts.workers or 'all'} worker(s): "
             f"{len(names)} scenario(s) on {', '.join(labels)}"
             + (", engine sections, faults ..." if not opts.models else
                f", the stability of {len(critical)} model(s) ..."))
    done = run_tasks(tasks, opts.workers, progress, limits=Limits(opts.stage_timeout))
    timings = {"stages": {t.label: round(done[t.key].seconds, 3) for t in tasks}}

    runs = {}
    for n in names:
        for lab in labels:
            r = done[("run", lab, n)]
            runs[(lab, n)] = r.value if r.error is None else Run(
                lab, n, "-", "-", "failed", r.error, 0.0)
    t0 = time.perf_counter()
    horizons = {c.name: done[("horizon", c.name)].value for c in case_list
                if ("horizon", c.name) in done and done[("horizon", c.name)].error is None}
    rows, checks, corrections = scenarios.reference_rows(names, runs, cases)
    from reference_model import load_model
    by_label = {s.label: isolated(s, opts.stage_timeout) for s in setups}   # main-process calls in workers
    sections = [scenarios.compare_scenarios(opts.tolerances, names, by_label, runs, horizons,
                                              cases)]
    # the thesis's claims are about the thesis bicycle: judged on its scenarios only
    thesis_names = [n for n in names if n in opts.scenarios and cases[n].model == "thesis"]
    claims = judge_claims(runs, labels, load_model("thesis"),
                          opts.scenarios if not opts.models else thesis_names)
    if opts.models:
        sections.insert(0, _models_section(opts, not_run))
    fault_rows, stage_keys, extra_summary = [], {}, {}
    for stage in STAGES:   # each stage's results, keyed as it gave them, in task order
        mine = {t.key[1]: done[t.key] for t in tasks
                if isinstance(t.key, tuple) and len(t.key) == 2 and t.key[0] == stage.name}
        if not plan.wants(stage.section):
            continue
        try:
            part = stage.assemble(plan, mine)
            claims = stage.revise_claims(plan, mine, claims)
        except Exception as exc:   # noqa: BLE001 - one stage's assembly fails alone
            sections.append(failed_section(f"{stage.name}: assembling its section",
                                           f"{type(exc).__name__}: {' '.join(str(exc).split())[:300]}"))
            continue
        sections += part.sections
        fault_rows += part.faults
        for k in part.summary:
            if k in stage_keys:
                raise ValueError(f"stages {stage_keys[k]} and {stage.name} both write "
                                 f"summary.json's {k!r}")
            stage_keys[k] = stage.name
        extra_summary.update(part.summary)
    # each claim says whether its engine's runs carry a declared model difference (a soft
    # contact): the report shows such a verdict as that, never as a failure
    difference = {st.label: plan.facts[st.engine].run_difference for st in setups}
    claims = [{**c, "model_difference": difference.get(c["engine"])} for c in claims]

    comparisons = [c for s in sections for c in s.comparisons]
    stray = [c for c in comparisons if not isinstance(c, Comparison)]
    if stray:   # every row is made typed where it is judged; a dict here is a bug to fix there
        raise TypeError(f"comparison rows must be judgments.rows.Comparison; got "
                        f"{type(stray[0]).__name__} for {stray[0].get('quantity')!r}")
    sections = [apply_figure_policy(sec, opts.figure_policy) for sec in sections]
    localization = faults.localization_lines(opts.tolerances, comparisons, by_label,
                                             {m.name: m.spec for m in opts.models})
    failed = (any(c["passed"] is False for c in checks)
              or any(r["status"] == "failed" for r in rows)
              or any(c["passed"] is False for c in comparisons)
              or any(f["verdict"] not in ("localized", "not observable", "not run")
                     for f in fault_rows)
              or bool(dropped))
    summary = {
        "passed": not failed,
        "engines": list(opts.engines),
        "dropped_engines": [{"engine": n, "reason": r} for n, r in dropped],
        "not_installed_engines": [{"engine": n, "reason": r} for n, r in opts.not_installed],
        "scenarios": rows,
        "engine_runs": [{"engine": r.engine, "scenario": r.scenario, "model": r.model,
                         "status": r.status, "t_end": round(r.t_end, 6), "message": r.message}
                        for (lab, name), r in sorted(runs.items(), key=lambda kv: (kv[0][1], kv[0][0]))],
        "summary_table": summary_table(comparisons),
        "comparisons": comparisons,
        "claims": claims,
        "faults": fault_rows,
        "checks": checks,
        "initial_corrections": corrections,
        "expected_differences": _expected_differences(names, cases),
        "environment": environment(setups, plan),
        "provenance": provenance.record(comparisons, runs.values()),
        "quick": opts.quick,
        "figures": opts.figure_policy,
        "sections": list(opts.sections),
    }
    clash = sorted(set(extra_summary) & set(summary))
    if clash:   # a stage extends summary.json, never replaces the pipeline's keys
        raise ValueError(f"a stage writes summary.json keys the pipeline owns: {clash}")
    summary.update(extra_summary)
    if opts.models:
        # the weave and capsize speeds (m/s) of each disc-contact --model, by its name
        summary["critical_speeds"] = {m.name: critical[m.spec] for m in opts.models
                                      if m.spec in critical}
    if opts.models or opts.scenario_files:
        summary["models"] = _models_used(opts, case_list)
        summary["not_run"] = [{"scenario": r.scenario, "model": r.model, "reason": r.reason}
                              for r in not_run]
    timings["judging in the main process"] = round(time.perf_counter() - t0, 3)
    timings["engine_run_seconds"] = {f"{n} on {lab}": round(r.seconds, 3)
                                     for (lab, n), r in sorted(runs.items())}
    timings["total_seconds"] = round(time.perf_counter() - t_start, 3)
    return ComparisonResult(opts, summary, sections, localization, runs, timings)


def apply_figure_policy(sec: Section, policy: str) -> Section:
    """``sec`` with the figures ``policy`` does not draw replaced by one line naming them, where
    the first stood (the reader learns what exists and how to get it; nothing is left out
    silently)."""
    if policy not in FIGURE_POLICIES:
        raise ValueError(f"figure policy {policy!r}: choose one of {', '.join(FIGURE_POLICIES)}")
    names = [f.name for f in sec.figures]
    if not names or policy == "all" or (
            policy == "failing" and any(c.get("passed") is False for c in sec.comparisons)):
        return sec
    why = ("`--figures failing`, the default of `--quick`, draws them where a comparison "
           "failed, and nothing failed here" if policy == "failing" else "`--figures none`")
    line = Text(f"*Not drawn ({why}; `--figures all` draws them): "
                f"{', '.join(f'`{n}`' for n in names)}.*")
    blocks, said = [], False
    for b in sec.blocks:
        if isinstance(b, Figure):
            if not said:
                blocks.append(line)
                said = True
        else:
            blocks.append(b)
    return dataclasses.replace(sec, blocks=blocks)


def _expected_differences(names, cases) -> list[dict]:
    return [{"scenario": n, "quantity": e.quantity, "engines": e.engines, "expected": e.expected,
             "reason": e.reason} for n in names for e in cases[n].expected_differences]


def _models_used(opts: Options, case_list) -> list[dict]:
    """summary.json's ``models``: every model a case ran on (name, source, contact, warnings)."""
    from .cases import model_spec
    specs = {m.spec: m for m in opts.models}
    for c in case_list:
        if c.model not in specs:
            specs[c.model] = model_spec(c.model)
    return [m.as_dict() for m in specs.values()]


def _models_section(opts: Options, not_run) -> Section:
    """What a run with --model covers: its models, what was not run and why."""
    sec = Section("Models of this run")
    sec.table(("model", "source", "contact", "warnings"),
              [(m.name, m.source, m.contact, "; ".join(m.warnings) or "-") for m in opts.models])
    sec.text("Every built-in scenario that makes sense for a bicycle runs on each model as "
             "`<scenario>-on-<model>`; initial states written for the thesis geometry are made "
             "consistent for the model's (the corrections are listed with the reference's "
             "runs). The replay and check-forward torques are the model's own inverse dynamics "
             "of zigzag and check, fed forward. The thesis's claims are about the thesis "
             "bicycle: they are judged only on the thesis's scenarios (model `thesis`). Every "
             "engine section runs on each model: every engine term by term at random states, "
             "fault injection on that bicycle, the fixed-step engines' convergence order, "
             "the energy drift, the soft-contact engines' study, the eigenvalues with runs at its own critical "
             "speeds and the linearization against the benchmark's closed form (disc "
             "contact). An engine that cannot represent a model says so ('not run on this "
             "model', with the reason): a declared limitation, not a failure.")
    if not_run:
        sec.table(("scenario", "model", "not run because"),
                  [(r.scenario, r.model, r.reason) for r in not_run])
    return sec
