"""`bicycle-xval run` as a computation: every stage, in parallel where independent, judged.

Stages (each a top-level call, run in worker processes by `pool.run_tasks`, longest first):

* every selected scenario on every engine setup (`runs.run_one`), the reference included;
* the meaningful horizon of each forward scenario (two reference runs 1e-9 rad/s apart);
* the engine sections: Pinocchio and Exudyn's tree term by term, Exudyn's trajectories per
  scenario, its convergence order, the energy drift (`engines`); Kane's equations (disc
  contact only: on the thesis's scenarios 'not run', with why) and any plugin term by term
  through `engines.plugin_terms`;
* the benchmark bicycle: terms, each IFToMM manoeuvre, Exudyn's convergence (`benchmark`);
* MuJoCo's contact study on thesis-disc: slip, penetration, error against time, refinement
  against the contact's time constant and the timestep (`mujoco_contact`);
* the fault-injection suite, per engine (`faults`).

With ``--model`` (`Options.models`) the scenarios run as cases bound to each model
(`cases.build_cases`: what makes sense on another bicycle, and why the rest is not run), each
disc-contact model gets its stability stages (`stability`: eigenvalues against speed, runs
below and above each critical speed), and every engine section runs on each model
(`_model_section_tasks`: terms, faults, Exudyn's convergence, energy, the soft-contact study);
the thesis's and the benchmark's own sections are the run without --model.
``--scenario-file`` adds cases to either run.
Without them the run is exactly the thesis's.

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
from ..judgments.tolerances import Tolerances, load_tolerances
from ..judgments.summary import summary_table
from .isolated import isolated
from .pool import Limits, Task, run_tasks
from .results import FIGURE_POLICIES, Figure, Section, Text

QUICK = ("check", "zigzag", "check-forward", "stability-psid10")
#: the parts of a run besides the scenarios, selectable with --sections (all by default)
SECTIONS = ("terms", "exudyn", "benchmark", "faults", "contact")
ENGINE_NAMES = ("reference", "pinocchio", "exudyn", "kane", "mujoco")
#: the engines with term stages of their own; every other engine (kane, mujoco, a plugin) gets
#: its declared terms through `engines.plugin_terms`
OWN_TERM_STAGES = ("reference", "pinocchio", "exudyn")


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
    chosen = list(ENGINE_NAMES) if engines is None else [e.strip() for e in engines.split(",")
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

def _versions() -> dict:
    out = {"python": sys.version.split()[0]}
    for pkg in ("numpy", "scipy", "sympy", "pandas", "matplotlib", "pin", "exudyn", "mujoco"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return " ".join(line.split(":", 1)[1].split())
    except OSError:
        pass
    return platform.processor() or platform.machine()


def environment(setups, quick: bool = False) -> dict:
    """What the numbers depend on (no times, no dates: those are in timings.json)."""
    from ..judgments.convergence import REFERENCE_RTOL
    from .engines import CONVERGENCE_HORIZON, EXUDYN_STEP, convergence_steps
    from . import mujoco_contact as mc
    return {
        "packages": _versions(),
        "machine": {"cpu": _cpu(), "cores": os.cpu_count(), "arch": platform.machine(),
                    "platform": platform.platform(terse=True)},
        "solvers": {s.label: s.settings for s in setups},
        "steps": {"exudyn": EXUDYN_STEP, "exudyn_convergence": list(convergence_steps(quick)),
                  "convergence_horizon_s": CONVERGENCE_HORIZON,
                  "reference_horizon_runs_rtol": REFERENCE_RTOL, "output_grid_s": 0.01,
                  "mujoco_contact_study": {"scenario": mc.SCENARIO, "model": mc.MODEL,
                                           "at_time_s": mc.STUDY_TIME,
                                           "window_s": mc.window(quick)}},
        "run_times": "timings.json (kept apart: they vary from run to run)",
    }


# -- the stages ----------------------------------------------------------------------------------

def _tasks(opts: Options, labels: list[str], cases, critical: dict) -> list[Task]:
    from . import benchmark, engines, faults, mujoco_contact, scenarios, stability
    from .runs import cost, run_one, setups_for
    setups = {s.label: s for s in setups_for(opts.engines, opts.options_for())}
    # the built-in scenarios by name (today's run, unchanged); the others as objects + model
    tasks = [Task(("run", lab, c.name), run_one,
                  (setups[lab], c.name) if c.origin == "built-in" and not opts.models
                  else (setups[lab], c.scenario, c.model),
                  cost(lab, c.name), f"{c.name} on {lab}")
             for c in cases for lab in labels]
    for c in cases:
        sc = c.scenario
        if sc.kind == "forward" and "trajectory" in sc.compared:
            tasks.append(Task(("horizon", c.name), scenarios.horizon_of,
                              (c.name,) if c.origin == "built-in" and not opts.models
                              else (sc,), 0.3, f"{c.name}: meaningful horizon"))
    for m in opts.models:
        if m.spec not in critical:
            continue
        tasks.append(Task(("stability-curves", m.spec), stability.stability_curves, (m.spec,),
                          0.5, f"{m.name}: eigenvalues against speed"))
        for mode, factor, speed in stability.run_speeds(critical[m.spec]):
            for lab in labels:
                if lab in stability.ENGINE_LABELS:
                    tasks.append(Task(("stability-run", m.spec, mode, speed, lab),
                                      stability.stability_run, (m.spec, lab, speed),
                                      0.3 if lab == "reference" else 3.0,
                                      f"{m.name}: {factor:g} x {mode} speed on {lab}"))
    for m in opts.models:
        tasks += _model_section_tasks(opts, m)
    if opts.models:   # the thesis's and the benchmark's own sections: the run without --model
        return tasks
    quick, tols = opts.quick, opts.tolerances
    want = set(opts.sections)
    if "pinocchio" in opts.engines and "terms" in want:
        n = 50 if quick else 200
        tasks.append(Task("pinocchio-terms", engines.pinocchio_terms, (tols, n), 1.5,
                          "Pinocchio term by term"))
    if "faults" in want:
        for e in faults.FAULT_ENGINES:
            if e in opts.engines:
                tasks.append(Task(("faults", e), faults.fault_entries, (tols, e), faults.FAULT_COST[e],
                                  f"fault injection on {faults.FAULT_LABELS[e]}"))
    if "exudyn" in opts.engines and "terms" in want:
        tasks.append(Task("exudyn-terms", engines.exudyn_terms, (tols, 20 if quick else 100), 1.0,
                          "Exudyn tree term by term"))
    if "exudyn" in opts.engines and "exudyn" in want:
        for n in (engines.QUICK_FORWARD if quick else engines.FORWARD):
            tasks.append(Task(("exudyn-trajectory", n), engines.exudyn_trajectory, (n,),
                              6.0 if n == "replay" else 2.5, f"Exudyn trajectories: {n}"))
        tasks.append(Task("exudyn-convergence", engines.exudyn_convergence, (quick,),
                          5.0 if quick else 8.0, "Exudyn convergence order"))
        tasks.append(Task("energy", engines.energy_section, (tols,), 2.0, "energy drift"))
    for spec in opts.engines:
        if spec not in OWN_TERM_STAGES and "terms" in want:   # kane, mujoco, a plugin
            tasks.append(Task(("plugin-terms", spec), engines.plugin_terms,
                              (tols, spec, opts.options_for().get(spec, {}), 50 if quick else 200),
                              1.5,
                              f"{spec} term by term"))
    if "mujoco" in opts.engines and "contact" in want:
        tasks.append(Task("mujoco-contact", mujoco_contact.mujoco_contact, (quick,),
                          1.5 if quick else 3.0, "MuJoCo contact study"))
        stab = tuple(n for n in opts.scenarios if n.startswith("stability-"))
        if stab and not quick:   # ~2 s of runs: the full report only
            tasks.append(Task("mujoco-claims", mujoco_contact.claims_on_disc, (stab,),
                              0.4 * len(stab), "MuJoCo: the stability claims on thesis-disc"))
    if "pinocchio" in opts.engines and "exudyn" in opts.engines and "benchmark" in want:
        tasks.append(Task("benchmark-terms", benchmark.benchmark_terms, (tols, quick), 1.5,
                          "benchmark terms"))
        for n in benchmark.MANOEUVRES:
            builds = benchmark.quick_builds(n) if quick else benchmark.BUILDS
            tasks.append(Task(("benchmark", n), benchmark.benchmark_manoeuvre, (n, builds),
                              0.5 + 1.5 * len(builds), f"benchmark {n}"))
        if not quick:
            tasks.append(Task("benchmark-convergence", benchmark.benchmark_convergence, (), 6.0,
                              "benchmark: Exudyn convergence"))
    return tasks


def _engine_contacts(spec: str) -> tuple[str, ...]:
    from engines.registry import resolve
    return tuple(getattr(resolve(spec)[0], "contacts", ()))


def _model_section_tasks(opts: Options, m) -> list[Task]:
    """The engine sections on a user's bicycle ``m`` (a `cases.ModelSpec`): every engine term by
    term at random states, fault injection on that bicycle, Exudyn's convergence and the energy
    drift, the soft-contact study (disc contact), each at ``--quick``'s smaller size when asked.
    An engine that cannot represent the bicycle says so in its section ('not run on this
    model: <reason>')."""
    from . import engines, faults, linear_check, mujoco_contact
    quick, want = opts.quick, set(opts.sections)
    tols = opts.tolerances
    tasks = [Task(("linear-check", m.spec), linear_check.linear_check, (tols, m.spec), 0.1,
                  f"{m.name}: linearization vs the closed form")]
    if "terms" in want:
        for spec in opts.engines:
            if spec != "reference":
                tasks.append(Task(("model-terms", spec, m.spec), engines.plugin_terms,
                                  (tols, spec, opts.options_for().get(spec, {}),
                                   50 if quick else 200, (m.spec,)), 1.0,
                                  f"{m.name}: {spec} term by term"))
    if "faults" in want:
        for e in faults.FAULT_ENGINES:
            if e in opts.engines and m.contact in _engine_contacts(e):
                tasks.append(Task(("faults", e, m.spec), faults.fault_entries, (tols, e, m.spec),
                                  faults.FAULT_COST[e], f"{m.name}: fault injection on "
                                                        f"{faults.FAULT_LABELS[e]}"))
    if "exudyn" in opts.engines and "exudyn" in want:
        tasks.append(Task(("exudyn-convergence", m.spec), engines.exudyn_convergence,
                          (quick, m.spec), 3.0, f"{m.name}: Exudyn convergence order"))
        tasks.append(Task(("energy", m.spec), engines.energy_section, (tols, m.spec), 2.0,
                          f"{m.name}: energy drift"))
    if "mujoco" in opts.engines and "contact" in want and m.contact == "disc":
        tasks.append(Task(("mujoco-contact", m.spec), mujoco_contact.mujoco_contact,
                          (quick, m.spec), 1.5 if quick else 3.0,
                          f"{m.name}: MuJoCo contact study"))
    return tasks


def _buildable(opts: Options):
    """The setups of the selected engines and the engines that cannot be built (each tried on
    the thesis model in a worker): (setups, [(engine, reason)])."""
    from reference_model import load_model
    from .runs import setups_for
    setups = setups_for(opts.engines, opts.options_for())
    dropped = []
    model = load_model("thesis")
    for s in setups:
        if s.engine in ENGINE_NAMES and not s.options:
            continue
        try:
            isolated(s).build(model)   # in a worker: its __init__ cannot end this process
        except Exception as exc:   # noqa: BLE001 - any failure drops the engine
            dropped.append((s.engine, f"{type(exc).__name__}: {' '.join(str(exc).split())}"))
    return setups, dropped


def _failed_stage(title: str, error: str) -> Section:
    sec = Section(title)
    sec.text(f"**This stage failed**: {error}")
    sec.comparisons.append({"quantity": "stage", "scenario": title, "model": "-",
                            "engines": ["-"], "max_error": None, "tolerance": None,
                            "passed": False, "localized_to": error})
    return sec


def run_comparison(opts: Options, progress: Callable[[str], None] = lambda s: None
                   ) -> ComparisonResult:
    """Every stage of the run (module docstring), judged; nothing written."""
    from . import benchmark, engines, faults, scenarios

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
    tasks = _tasks(opts, labels, case_list, critical)
    progress(f"{len(tasks)} stages on {opts.workers or 'all'} worker(s): "
             f"{len(names)} scenario(s) on {', '.join(labels)}"
             + (", engine sections, faults ..." if not opts.models else
                f", the stability of {len(critical)} model(s) ..."))
    done = run_tasks(tasks, opts.workers, progress, limits=Limits(opts.stage_timeout))
    timings = {"stages": {t.label: round(done[t.key].seconds, 3) for t in tasks}}

    def value(key, title):
        r = done[key]
        return (r.value, None) if r.error is None else (None, _failed_stage(title, r.error))

    runs = {}
    for n in names:
        for lab in labels:
            r = done[("run", lab, n)]
            runs[(lab, n)] = r.value if r.error is None else Run(
                lab, n, "-", "-", "failed", r.error, 0.0)
    t0 = time.perf_counter()
    horizons = {key[1]: r.value for key, r in done.items()
                if isinstance(key, tuple) and key[0] == "horizon" and r.error is None}
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
        sections += _stability_sections(opts, critical, done)

    def add(key, title, build=lambda v: v):
        if key in done:
            v, failed = value(key, title)
            sections.append(failed or build(v))

    add("pinocchio-terms", "Reference vs Pinocchio, term by term")
    for spec in opts.engines:
        add(("plugin-terms", spec), f"Reference vs {spec}, term by term")
    add("exudyn-terms", "Reference vs Exudyn kinematic tree, term by term")
    traj_keys = [k for k in done if isinstance(k, tuple) and k[0] == "exudyn-trajectory"]
    if traj_keys:
        parts, failures = [], []
        for k in traj_keys:
            v, failed = value(k, f"Exudyn trajectories: {k[1]}")
            (parts.append(v) if failed is None else failures.append(failed))
        sections.append(engines.merge_trajectories(parts))
        sections += failures
    add("exudyn-convergence", "Exudyn convergence")
    add("energy", "Energy drift")
    add("mujoco-contact", "MuJoCo contact study")
    if "mujoco-claims" in done:
        from .mujoco_contact import merge_claims
        disc_claims, failed_claims = value("mujoco-claims", "MuJoCo claims on thesis-disc")
        if failed_claims is None:
            claims = merge_claims(claims, disc_claims)
        sections.append(failed_claims or disc_claims.section)
    if "benchmark-terms" in done:
        bench_runs = [value(("benchmark", n), f"benchmark {n}") for n in benchmark.MANOEUVRES]
        terms, failed_terms = value("benchmark-terms", "benchmark terms")
        conv = value("benchmark-convergence", "benchmark convergence")[0] \
            if "benchmark-convergence" in done else None
        broken = [f for _, f in bench_runs if f is not None] + ([failed_terms] if failed_terms else [])
        if broken:
            sections += broken
        else:
            sections.append(benchmark.benchmark_section(opts.tolerances, opts.quick,
                                                        [v for v, _ in bench_runs],
                                                        terms, conv))
    for m in opts.models:
        add(("linear-check", m.spec), f"{m.name}: linearization against the closed form")
        for spec in opts.engines:
            add(("model-terms", spec, m.spec), f"{m.name}: reference vs {spec}, term by term")
        add(("exudyn-convergence", m.spec), f"{m.name}: Exudyn convergence")
        add(("energy", m.spec), f"{m.name}: energy drift")
        add(("mujoco-contact", m.spec), f"{m.name}: MuJoCo contact study")
    fault_rows = []
    fault_keys = [("faults", e) for e in faults.FAULT_ENGINES] + [
        ("faults", e, m.spec) for m in opts.models for e in faults.FAULT_ENGINES]
    for key in fault_keys:
        if key in done:
            v, failed = value(key, f"fault injection on {key[1]}")
            if failed is None:
                fault_rows += v
            else:
                sections.append(failed)
    if fault_rows:
        sections.append(faults.fault_section(fault_rows))

    comparisons = [c for s in sections for c in s.comparisons]
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
        "environment": environment(setups, opts.quick),
        "provenance": provenance.record(comparisons, runs.values()),
        "quick": opts.quick,
        "figures": opts.figure_policy,
        "sections": list(opts.sections),
    }
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
             "fault injection on that bicycle, Exudyn's convergence order and the energy "
             "drift, the soft-contact study, the eigenvalues with runs at its own critical "
             "speeds and the linearization against the benchmark's closed form (disc "
             "contact). An engine that cannot represent a model says so ('not run on this "
             "model', with the reason): a declared limitation, not a failure.")
    if not_run:
        sec.table(("scenario", "model", "not run because"),
                  [(r.scenario, r.model, r.reason) for r in not_run])
    return sec


def _stability_sections(opts: Options, critical: dict, done: dict) -> list[Section]:
    from .stability import applies, stability_section
    out = []
    for m in opts.models:
        why = applies(m.contact)
        if why is not None:
            sec = Section(f"Stability of {m.name} ({m.source})")
            sec.text(f"Not computed: {why}.")
            out.append(sec)
            continue
        curves_r = done[("stability-curves", m.spec)]
        runs, errors = {}, {}
        for key, r in done.items():
            if isinstance(key, tuple) and key[0] == "stability-run" and key[1] == m.spec:
                if r.error is None:
                    runs[key[2:]] = r.value
                else:
                    errors[key[2:]] = r.error
        out.append(stability_section(m, critical[m.spec],
                                     curves_r.value if curves_r.error is None else None,
                                     runs, errors))
    return out
