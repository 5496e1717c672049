"""`bicycle-xval run`: every scenario on every engine that can run it, compared and judged.

Stages, in report order:

1. the reference model on every selected scenario (CSV data, the analytic check);
2. the other engines on the same scenarios (`scenario_runs`, in worker processes);
3. what each scenario's registry entry says is compared (`scenario_compare`) with figures;
4. the thesis's claims, engine by engine (`claims`);
5. the engine sections: term by term at random states, Exudyn's disc-contact builds, its
   convergence order, the energy drift (`engine_report`);
6. the fault-injection suite (`faults`);

written as report.md (summary table first), a self-contained report.html, summary.json (the
machine-readable contract), data/*.csv and figures/*.png. Run times go to timings.json only,
so two runs on the same machine give byte-identical reports.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from importlib import metadata
from pathlib import Path

import numpy as np

from .cli import EXIT_FAIL, EXIT_OK, UsageError, inverse_dynamics_frame, simulation_frame

QUICK = ("check", "zigzag", "check-forward", "stability-psid10")


def _versions() -> dict:
    out = {"python": sys.version.split()[0]}
    for pkg in ("numpy", "scipy", "sympy", "pandas", "matplotlib", "pin", "exudyn"):
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


def environment(setups) -> dict:
    """What the numbers depend on (no times, no dates: those are in timings.json)."""
    from .engine_report import CONVERGENCE_HORIZON, EXUDYN_STEP
    from .convergence import DEFAULT_STEPS, REFERENCE_RTOL
    return {
        "packages": _versions(),
        "machine": {"cpu": _cpu(), "cores": os.cpu_count(), "arch": platform.machine(),
                    "platform": platform.platform(terse=True)},
        "solvers": {s.label: s.settings for s in setups},
        "steps": {"exudyn": EXUDYN_STEP, "exudyn_convergence": list(DEFAULT_STEPS),
                  "convergence_horizon_s": CONVERGENCE_HORIZON,
                  "reference_horizon_runs_rtol": REFERENCE_RTOL, "output_grid_s": 0.01},
        "run_times": "timings.json (kept apart: they vary from run to run)",
    }


def _md(text) -> str:
    """Text safe inside a markdown table cell."""
    return str(text).replace("|", "\\|")


def _progress(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _select(scenarios: str | None, quick: bool, engines: str | None):
    from engines import ENGINES
    from reference_model.scenarios import SCENARIOS
    thesis = [n for n, sc in SCENARIOS.items() if "benchmark" not in sc.tags]
    names = thesis if scenarios is None else [s.strip() for s in scenarios.split(",") if s.strip()]
    if quick and scenarios is None:
        names = list(QUICK)
    if not names:
        raise UsageError("--scenarios is empty; give a comma-separated list, e.g. check,zigzag")
    for n in names:
        if n not in SCENARIOS:
            raise UsageError(f"unknown scenario {n!r} in --scenarios; choose from {', '.join(SCENARIOS)}")
    chosen = list(ENGINES) if engines is None else [e.strip() for e in engines.split(",") if e.strip()]
    for e in chosen:
        if e not in ENGINES:
            raise UsageError(f"unknown engine {e!r} in --engines; choose from {', '.join(ENGINES)}")
    if "reference" not in chosen:
        chosen.insert(0, "reference")   # everything is compared against it
    return names, chosen


# -- stage 1: the reference ----------------------------------------------------------------------

def reference_stage(out: Path, names, progress):
    """Every selected scenario on the reference model: Runs, CSV data, the analytic check."""
    from reference_model import load_model
    from reference_model.scenarios import get_scenario, run_forward
    from .scenario_runs import Run

    runs, rows, checks, corrections, timings = {}, [], [], {}, {}
    for k, name in enumerate(names, 1):
        sc = get_scenario(name)
        model = load_model(sc.model)
        progress(f"[{k}/{len(names)}] {name} ({sc.kind}) on the reference model ({model.name}) ...")
        t0 = time.perf_counter()
        if sc.kind == "inverse":
            frame, res = inverse_dynamics_frame(model, sc)
            m = res.motion
            run = Run("reference", name, model.name, "inverse", "completed", "solved at every sample",
                      0.0, m.t, m.q, m.dq, res.T, res.lam)
            C = model.constraint_residual(m.q, m.dq)
            rows.append((name, "inverse", "completed", f"{m.t[-1]:.2f}", f"{np.abs(C).max():.1e}"))
            if name == "check":
                p = model.params
                expected = p.cv * (p.R_rear * 5.0) ** 2 * p.R_rear
                err = float(np.max(np.abs(res.T - [0.0, expected, 0.0])))
                checks.append({"check": "check: Mped = cv (R psi_dot)^2 R, Mdir = Mvue = 0",
                               "value": err, "tolerance": 1e-12 * expected,
                               "passed": err <= 1e-12 * expected,
                               "evidence": f"Mped = {expected:.12g} N m expected; max deviation "
                                           f"{err:.2e} N m over {len(frame)} samples"})
        else:
            traj = run_forward(model, sc)
            frame = simulation_frame(traj)
            run = Run("reference", name, model.name, "forward", traj.status, traj.message, 0.0,
                      traj.t, traj.q, traj.dq, trajectory=traj)
            rows.append((name, "forward", traj.status, f"{traj.t_end:.3f}", f"{np.abs(traj.C).max():.1e}"))
            corrections[name] = traj.settings["initial_correction"]
        timings[name] = run.seconds = time.perf_counter() - t0
        runs[("reference", name)] = run
        frame.to_csv(out / "data" / f"{name}_reference.csv", index=False, float_format="%.17g")
    return runs, rows, checks, corrections, timings


# -- stage 3: scenario comparisons -----------------------------------------------------------------

def scenario_stage(out: Path, names, labels, runs, progress):
    """What each scenario's registry entry says is compared; returns (comparisons, lines, figures)."""
    from reference_model import load_model
    from reference_model.scenarios import get_scenario
    from . import figures
    from .convergence import reference_horizon
    from .scenario_compare import (compare_constraints, compare_forward, compare_inverse,
                                   compare_mass_matrix)
    from .tolerances import load_tolerances

    tols = load_tolerances()
    comps, lines, figs = [], [], []
    forward_runs, stability, models = {}, {}, {}
    for name in names:
        sc = get_scenario(name)
        model = load_model(sc.model)
        ref = runs[("reference", name)]
        here = {lab: runs[(lab, name)] for lab in labels if (lab, name) in runs
                and runs[(lab, name)].status not in ("not run",)}
        if "mass_matrix" in sc.compared and ref.t.size:
            step = max(1, len(ref.t) // 100)   # ~100 states along the run
            comps += compare_mass_matrix(name, model, ref.q[::step], labels, tols)
        if sc.kind == "inverse":
            for lab, r in here.items():
                if lab != "reference" and r.status == "completed":
                    comps += compare_inverse(ref, r, tols)
            figs.append(figures.torque_overlay(out, name, {k: r for k, r in here.items() if r.T is not None}))
            continue
        progress(f"  {name}: meaningful horizon (two reference runs 1e-9 rad/s apart) ...")
        hor = reference_horizon(model, sc)
        errors = {}
        for lab, r in here.items():
            if "constraint_residual" in sc.compared:
                comps.append(compare_constraints(model, r, tols))
            if lab == "reference" or "trajectory" not in sc.compared or not r.t.size:
                continue
            c, te = compare_forward(model, ref, r, hor, tols)
            comps += c
            errors[lab] = te
        figs.append(figures.trajectory_overlay(out, name, here, errors, hor.t))
        forward_runs[name], models[name] = here, model
        if "stability" in sc.tags:
            for lab, r in here.items():
                stability.setdefault(lab, {})[name] = r
    if forward_runs:
        figs.append(figures.constraint_residuals(out, models, forward_runs))
    if stability:
        figs.append(figures.stability_study(out, stability))
    zig = runs.get(("reference", "zigzag"))
    replays = {lab: runs[(lab, "replay")] for lab in labels if (lab, "replay") in runs
               and runs[(lab, "replay")].t.size}
    if zig is not None and replays:
        figs.append(figures.replay_vs_zigzag(out, zig, replays))
    lines += ["| quantity | scenario | engines | max error | tolerance | verdict | localized to |",
              "|---|---|---|---|---|---|---|"]
    for c in comps:
        lines.append(f"| {c['quantity']} | {c['scenario']} | {' vs '.join(c['engines'])} | "
                     f"{_num(c['max_error'])} | {_num(c['tolerance'])} | {_verdict(c)} | "
                     f"{_md(c.get('localized_to', '-'))} |")
    return comps, lines, figs


def _num(x) -> str:
    return "-" if x is None else f"{x:.1e}"


def _verdict(c) -> str:
    if c.get("passed") is None:
        return "reported"
    return "pass" if c["passed"] else "FAIL"


# -- the summary table ---------------------------------------------------------------------------

def summary_table(comparisons) -> list[dict]:
    """quantity x engine pair: the worst error over scenarios, the tolerance, the verdict."""
    groups: dict[tuple[str, str], list[dict]] = {}
    for c in comparisons:
        groups.setdefault((c["quantity"], " vs ".join(c["engines"])), []).append(c)
    rows = []
    for (quantity, pair), cs in groups.items():
        judged = [c for c in cs if c.get("passed") is not None]
        errs = [c["max_error"] for c in cs if c.get("max_error") is not None]
        worst = max(cs, key=lambda c: -np.inf if c.get("max_error") is None else c["max_error"])
        tol = sorted({c["tolerance"] for c in cs if c.get("tolerance") is not None})
        rows.append({
            "quantity": quantity, "engines": pair, "n": len(cs),
            "max_error": max(errs) if errs else None,
            "tolerance": tol[0] if len(tol) == 1 else (None if not tol else f"{tol[0]:.0e}..{tol[-1]:.0e}"),
            "verdict": ("reported" if not judged else
                        "pass" if all(c["passed"] for c in judged) else
                        f"FAIL ({sum(not c['passed'] for c in judged)} of {len(judged)})"),
            "worst": f"{worst['scenario']}: {worst.get('localized_to', '-')}",
        })
    return rows


# -- the report ------------------------------------------------------------------------------------

def run_report(out: Path, scenarios: str | None = None, quick: bool = False,
               engines: str | None = None, workers: int | None = None) -> int:
    names, chosen = _select(scenarios, quick, engines)
    from reference_model import load_model
    from .claims import judge_claims
    from .engine_report import run_engine_stage
    from .html import write_html
    from .scenario_runs import run_all, setups_for

    out = Path(out)
    (out / "data").mkdir(parents=True, exist_ok=True)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    for stale in list((out / "figures").glob("*.png")) + list((out / "data").glob("*.csv")):
        stale.unlink()   # a report folder holds exactly one run
    t_start = time.perf_counter()
    setups = setups_for(chosen)
    labels = [s.label for s in setups]

    runs, rows, checks, corrections, timings = reference_stage(out, names, _progress)
    others = [lab for lab in labels if lab != "reference"]
    if others:
        _progress(f"engines: {len(names)} scenario(s) on {', '.join(others)} ...")
        t0 = time.perf_counter()
        runs = run_all(others, names, _progress, workers=workers, done=runs)
        timings["engine runs"] = time.perf_counter() - t0
        for (lab, name), r in runs.items():
            if lab != "reference" and r.t.size:
                _run_frame(r).to_csv(out / "data" / f"{name}_{lab}.csv", index=False,
                                     float_format="%.17g")
    _progress("comparing the runs ...")
    t0 = time.perf_counter()
    scen_comps, scen_lines, scen_figs = scenario_stage(out, names, labels, runs, _progress)
    claims = judge_claims(runs, labels, load_model("thesis"), names)
    timings["scenario comparisons"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    sections = run_engine_stage(out, chosen, quick, _progress)
    timings["engine sections"] = time.perf_counter() - t0
    faults, fault_lines = [], []
    if "pinocchio" in chosen:
        t0 = time.perf_counter()
        _progress("fault injection: broken copies of the reference against Pinocchio ...")
        faults, fault_lines = fault_stage(chosen)
        timings["fault injection"] = time.perf_counter() - t0

    comparisons = scen_comps + [c for sec in sections for c in sec.comparisons]
    localization = localization_stage(comparisons)
    failed = (any(c["passed"] is False for c in checks) or any(r[2] == "failed" for r in rows)
              or any(c["passed"] is False for c in comparisons)
              or any(f["verdict"] not in ("localized", "not observable") for f in faults))
    table = summary_table(comparisons)
    summary = {
        "passed": not failed,
        "engines": chosen,
        "scenarios": [dict(zip(("scenario", "kind", "status", "t_end", "max_abs_C"), r)) for r in rows],
        "engine_runs": [{"engine": r.engine, "scenario": r.scenario, "model": r.model,
                         "status": r.status, "t_end": round(r.t_end, 6), "message": r.message}
                        for (lab, name), r in sorted(runs.items(), key=lambda kv: (kv[0][1], kv[0][0]))],
        "summary_table": table,
        "comparisons": comparisons,
        "claims": claims,
        "faults": faults,
        "checks": checks,
        "initial_corrections": corrections,
        "expected_differences": _expected_differences(names),
        "environment": environment(setups),
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=_json_default) + "\n")
    timings["total"] = time.perf_counter() - t_start
    (out / "timings.json").write_text(json.dumps(
        {"total_seconds": timings.pop("total"), "per_stage_seconds": timings,
         "engine_run_seconds": {f"{name} on {lab}": r.seconds for (lab, name), r in sorted(runs.items())}},
        indent=1) + "\n")
    md = _markdown(summary, rows, corrections, scen_lines, scen_figs, sections, fault_lines, quick,
                   localization)
    (out / "report.md").write_text(md)
    write_html(out / "report.md")
    _progress(f"report written to {out / 'report.md'} and report.html in "
              f"{time.perf_counter() - t_start:.1f} s: {'all within tolerance' if not failed else 'SOMETHING FAILED'}")
    return EXIT_FAIL if failed else EXIT_OK


def _json_default(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.bool_):
        return bool(x)
    return str(x)


def _run_frame(r):
    from .cli import _csv_frame
    extra = {}
    if r.T is not None:
        extra = {n: r.T[:, i] for i, n in enumerate(("Mdir", "Mped", "Mvue"))}
        extra.update({f"lambda_{k + 1}": r.lam[:, k] for k in range(5)})
    ddq = r.trajectory.ddq if r.trajectory is not None else np.full_like(r.q, np.nan)
    return _csv_frame(r.t, r.q, r.dq, ddq, extra)


def _expected_differences(names) -> list[dict]:
    from reference_model.scenarios import get_scenario
    return [{"scenario": n, "quantity": e.quantity, "engines": e.engines, "expected": e.expected,
             "reason": e.reason} for n in names for e in get_scenario(n).expected_differences]


def fault_stage(engines):
    """The fault-injection suite against each engine that computes terms: (entries, lines).
    Pinocchio computes every term, so every fault must be detected and localized on it; the
    Exudyn tree gives only M and the generalized forces, so a fault confined to D and dD dq
    (the contact switch) is not observable there and is listed as such, not counted as missed."""
    from .faults import run_fault_suite
    entries = []
    for engine in [e for e in ("pinocchio", "exudyn") if e in engines]:
        for r in run_fault_suite(engines=(engine,)):
            d = r.to_dict()
            d["engine"] = engine
            d["verdict"] = ("localized" if r.correct else "not observable" if not r.observable
                            else "detected, mislocalized" if r.detected else "missed")
            entries.append(d)
    lines = ["Broken copies of the reference model are run against engines built from the "
             "correct parameters (16 deterministic states). Each fault must be detected (a term "
             "fails its tolerance) and localized: the differing terms, and the parameter or "
             "structural cause, with its body, that explains at least 99 % of the difference "
             "(least squares over the sensitivities of all 30 parameters and the structural "
             "causes; see `comparisons/diagnose.py`). The same machinery is `bicycle-xval "
             "diagnose FILE` for your own parameter file.", "",
             "| fault | engine | detected | localized to | expected | verdict | evidence |",
             "|---|---|---|---|---|---|---|"]
    for e in entries:
        lines.append(f"| {e['fault']} | {e['engine']} | {'yes' if e['detected'] else 'no'} | "
                     f"{_md(e['localized_to'])} | {_md(e['expected'])} | {e['verdict']} | "
                     f"{_md(e['evidence'])} |")
    return entries, lines


TERM_QUANTITIES = ("mass_matrix", "inverse_dynamics", "gravity", "generalized_forces",
                   "constraint_jacobian", "constraint_bias", "forward_acceleration", "torques",
                   "multipliers")


def localization_stage(comparisons) -> list[str]:
    """For every (model, engine) whose terms or inverse dynamics failed a tolerance: which
    terms, which entries, and the parameter or structural cause (with its body) that best
    explains the difference (`diagnose.localize`). Empty when everything agrees."""
    from reference_model import load_model
    from .diagnose import localize
    from .scenario_runs import SETUPS
    from .terms import random_states
    pairs = sorted({(c.get("model", "thesis"), c["engines"][1]) for c in comparisons
                    if c["passed"] is False and c["quantity"] in TERM_QUANTITIES
                    and len(c["engines"]) == 2})
    lines = []
    for model_name, engine in pairs:
        if engine not in SETUPS:
            continue
        model = load_model(model_name)
        loc = localize(model, random_states(16, seed=11), [SETUPS[engine].build(model)])
        lines += [f"### {model_name}: reference vs {engine}", ""]
        lines += [f"- {_md(ln.strip())}" for ln in loc.describe().splitlines() if ln.strip()] + [""]
    return lines


def _unobservable(faults) -> str:
    n = sum(f["verdict"] == "not observable" for f in faults)
    return f" ({n} not observable by the engine)" if n else ""


def _markdown(summary, rows, corrections, scen_lines, scen_figs, sections, fault_lines, quick,
              localization) -> str:
    n_comp = len(summary["comparisons"])
    n_fail = sum(c["passed"] is False for c in summary["comparisons"])
    n_judged = sum(c["passed"] is not None for c in summary["comparisons"])
    verdicts = {}
    for c in summary["claims"]:
        verdicts[c["verdict"]] = verdicts.get(c["verdict"], 0) + 1
    L = ["# bicycle-xval report", "",
         f"**{'All judged comparisons within tolerance' if summary['passed'] else 'Something is out of tolerance'}.** "
         f"Engines: {', '.join(summary['engines'])}{' (quick subset)' if quick else ''}. "
         f"{n_comp} comparisons, {n_judged} judged against a tolerance, {n_fail} failed; "
         f"{len(summary['faults'])} fault-engine pairs, "
         f"{sum(f['verdict'] == 'localized' for f in summary['faults'])} detected and localized"
         f"{_unobservable(summary['faults'])}; "
         f"thesis claims: " + ", ".join(f"{v} {k}" for k, v in sorted(verdicts.items())) + ".",
         "", "Tolerances and their reasons: `comparisons/tolerances.toml`. Machine-readable: "
         "`summary.json`. Data: `data/<scenario>_<engine>.csv`.", "",
         "## Summary: quantity x engine pair", "",
         "| quantity | engines | comparisons | max error | tolerance | verdict | worst at |",
         "|---|---|---|---|---|---|---|"]
    for r in summary["summary_table"]:
        tol = r["tolerance"] if isinstance(r["tolerance"], str) else _num(r["tolerance"])
        L.append(f"| {r['quantity']} | {r['engines']} | {r['n']} | {_num(r['max_error'])} | {tol} | "
                 f"{r['verdict']} | {_md(r['worst'])} |")
    L += ["", "Errors are relative to the scale each tolerance names (absolute for trajectories "
          "and constraint residuals, in rad, m or m/s); 'reported' rows are judged elsewhere "
          "(Exudyn's trajectories by its convergence order).", ""]
    if localization:
        L += ["## Where the engines disagree", "",
              "Each failing term comparison localized: the terms that differ, their worst entries, "
              "and the single parameter or structural cause (with its body) that best explains the "
              "difference, by least squares over the sensitivities of all 30 parameters.", ""]
        L += localization
    L += ["## The thesis's claims, engine by engine", "",
          "| claim | engine | verdict | evidence |", "|---|---|---|---|"]
    L += [f"| {_md(c['claim'])} | {c['engine']} | {c['verdict']} | {_md(c['evidence'])} |"
          for c in summary["claims"]]
    if fault_lines:
        L += ["", "## Fault injection: does the harness catch a broken model?", ""] + fault_lines
    L += ["", "## Scenarios on the reference model", "",
          "| scenario | kind | status | t_end [s] | max abs C |", "|---|---|---|---|---|"]
    L += [f"| {' | '.join(r)} |" for r in rows]
    L += ["", "Engine runs:", "", "| scenario | engine | status | end [s] | message |", "|---|---|---|---|---|"]
    L += [f"| {r['scenario']} | {r['engine']} | {r['status']} | {r['t_end']:.3f} | {_md(r['message'])} |"
          for r in summary["engine_runs"]]
    if corrections:
        L += ["", "Initial states: every engine starts from the same projected state (beta from "
              "[rD]_z = 0, dependent rates from D dq = 0). Corrections applied:", ""]
        L += [f"- {name}: {_md(text)}" for name, text in corrections.items()]
    if summary["checks"]:
        L += ["", "Analytic check: " + "; ".join(
            f"{c['check']}: {'holds' if c['passed'] else 'FAILS'} ({c['evidence']})" for c in summary["checks"])]
    L += ["", "## Every engine on every scenario", "",
          "What each scenario's registry entry (`reference_model/scenarios.py`) lists as compared: "
          "M at ~100 of the reference's states, torques and multipliers along the inverse "
          "scenarios, all eight coordinates up to the meaningful horizon and the constraint "
          "residual of every run.", ""] + scen_lines + [""]
    L += [f"![{f[:-4]}](figures/{f})" for f in scen_figs]
    for sec in sections:
        L += ["", f"## {sec.title}", ""] + sec.lines + [""]
        L += [f"![{f[:-4]}](figures/{f})" for f in sec.figures]
    if summary["expected_differences"]:
        L += ["", "## Expected differences (declared in the scenario registry)", ""]
        L += [f"- {e['scenario']}, {e['quantity']}, {e['engines']}: expected '{e['expected']}' "
              f"because {e['reason']}" for e in summary["expected_differences"]]
    env = summary["environment"]
    L += ["", "## Environment", "",
          f"Machine: {env['machine']['cpu']}, {env['machine']['cores']} cores, {env['machine']['platform']}.", "",
          "Packages: " + ", ".join(f"{k} {v}" for k, v in env["packages"].items()) + ".", "",
          "Solver settings:", ""]
    L += [f"- {k}: {v}" for k, v in env["solvers"].items()]
    L += ["", "Steps: " + ", ".join(f"{k} = {v}" for k, v in env["steps"].items()) + ".", "",
          "Run times are in `timings.json` (kept apart so the report is identical run to run)."]
    return "\n".join(L) + "\n"
