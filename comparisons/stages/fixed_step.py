"""The fixed-step integrators' study: every engine that declares `engines.facts.FixedStep` gets
its trajectories reported up to the meaningful horizon, and judged by their convergence order.

* **trajectories** (the thesis's forward scenarios on `thesis-disc`): each declared variant at
  the declared step against the reference (DOP853, rtol 1e-11, projection), up to the horizon
  where two reference runs 1e-9 rad/s apart still agree (the bike is unstable: beyond it nothing
  is meaningful). Reported, not judged: a fixed-step integrator's error is judged by its order.
* **convergence order** (stability-psid10 up to `CONVERGENCE_HORIZON`, four steps spanning 8x):
  a matched model must converge at the solver's order (verdict 'converges'); the disc-contact
  variant against the thesis-contact reference is a declared, expected model difference (the
  scenario's ``expected_differences``), reported as unexpected if it ever stops differing. On a
  ``--model``: the first variant against the reference on the same file, which must converge.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from engines import load_engine
from reference_model import COORDINATES, load_model
from reference_model.scenarios import SCENARIOS

from ..judgments.convergence import (DEFAULT_STEPS, convergence_study, error_vs_time,
                                     reference_horizon, reference_run)
from ..judgments.rows import Comparison
from .results import Figure, Section
from .stage import Assembled, Plan, Stage

__all__ = ["CONVERGENCE_HORIZON", "FORWARD", "QUICK_FORWARD", "FixedStepStage",
           "convergence_section", "convergence_steps", "first_past", "merge_trajectories",
           "trajectory_part"]

CONVERGENCE_HORIZON = 0.5   # s: psid10 before its steer runs away (asymptotic regime of the errors)
FORWARD = ("stability-psid0", "stability-psid1", "stability-psid5", "stability-psid10", "replay")
QUICK_FORWARD = ("stability-psid5",)
#: --quick's convergence steps: the full study's halvings shifted one up, the same 8x span the
#: verdict needs (`convergence.MIN_SPAN`) at half the steps (the finest costs as much as the
#: other three together)
QUICK_CONVERGENCE_STEPS = tuple(2 * h for h in DEFAULT_STEPS)
DIVERGED = 1e-6             # rad or m: 'first past' threshold of the trajectory tables
#: the trajectory stages' cost per variant (s, for the scheduler's order), set by their
#: horizons: replay 1.5 s and stability-psid10 2.86 s against about 1 s for the others (whose
#: runs end in a fall); the reference and its twin run the whole scenario
TRAJECTORY_COSTS = {"replay": 2.4, "stability-psid10": 2.0}


def convergence_steps(quick: bool, fixed=None) -> tuple[float, ...]:
    """The convergence study's steps in a quick or a full run: the engine's declared step times
    the standard 1/2-spaced factors (for 1e-3 s: 5e-3, 2.5e-3, 1.25e-3, 6.25e-4 s,
    `DEFAULT_STEPS`; twice those in a quick run)."""
    scale = 1.0 if fixed is None else fixed.step / 1e-3
    return tuple(h * scale for h in (QUICK_CONVERGENCE_STEPS if quick else DEFAULT_STEPS))


def first_past(err: dict, threshold: float = DIVERGED) -> str:
    """'theta at 0.89 s': the first coordinate past ``threshold`` and when; '' if none."""
    over = np.flatnonzero(err["max"] > threshold)
    if not over.size:
        return ""
    k = int(over[0])
    return f"{max(COORDINATES, key=lambda c: err[c][k])} at {err['t'][k]:.2f} s"


def _build(spec: str, model, fixed, variant: str, **more):
    return load_engine(spec, model, **fixed.variant_options(variant, **more))


@dataclass
class TrajectoryPart:
    """One scenario's share of the trajectory section (a stage of its own, run in parallel)."""

    rows: list[tuple]
    comparisons: list[dict]
    figure: Figure
    correction: str


def trajectory_part(spec: str, name: str) -> TrajectoryPart:
    """One forward scenario on every declared variant of ``spec`` against the reference
    `thesis-disc` (a stage)."""
    from engines.facts import engine_facts
    facts = engine_facts(spec)
    fixed = facts.fixed_step
    comparisons: list[dict] = []
    model = load_model("thesis-disc")
    sc = SCENARIOS[name]
    ref = reference_run(model, sc)
    hor = reference_horizon(model, sc, reference=ref)
    # nothing beyond the horizon is compared, so the engines run only to it (and two samples)
    start, step, n = sc.grid
    cut = dataclasses.replace(sc, grid=(start, step, min(n, int(np.ceil((hor.t - start) / step)) + 3)))
    rows, curves = [], {}
    for label, opts in fixed.runs(facts.name):
        traj = load_engine(spec, model, **opts).simulate(cut)
        err = error_vs_time(ref, traj, coords=COORDINATES, horizon=hor.t)
        worst = float(err["max"].max())
        first = first_past(err)
        rows.append((name, f"{hor.t:.2f}", hor.limited_by, label, f"{worst:.2e}",
                     first or f"none (all below {DIVERGED:g})",
                     f"{traj.t_end:.3f} s ({traj.status}{', run to the horizon' if cut.grid[2] < n else ''})"))
        comparisons.append(Comparison.of({
            "quantity": "trajectory (disc builds)", "scenario": name,
            "model": "thesis-disc", "engines": ["reference", label],
            "max_error": worst, "tolerance": None, "passed": None,
            "horizon": hor.t, "horizon_reason": hor.reason, "localized_to": first or "-",
            "note": f"reported, not judged: the convergence study judges {facts.label}'s "
                    "trajectories"}))
        curves[label] = {"t": err["t"], "theta": err["theta"], "xc": err["xc"]}
    fig = Figure(f"{_slug(facts.name)}_error_{name}.png", "error_vs_time",
                 dict(curves=curves, horizon=hor.t, threshold=DIVERGED, engine_label=facts.label,
                      title=f"{name}: {facts.label} against the reference up to the horizon "
                            f"({hor.t:.2f} s)"))
    return TrajectoryPart(rows, comparisons, fig, f"{name}: {ref.settings['initial_correction']}")


def merge_trajectories(parts: list[TrajectoryPart], facts) -> Section:
    """The per-scenario trajectory stages of one engine as one section."""
    fixed = facts.fixed_step
    sec = Section(f"Reference vs {facts.label}, forward trajectories (disc contact)")
    sec.text(f"Every declared variant of {facts.label} ({', '.join(fixed.variant_names)}) at "
             f"{fixed.option} = {fixed.step:g} s against the reference `thesis-disc` "
             "(DOP853, rtol 1e-11, projection). The *horizon* is where two reference runs "
             "1e-9 rad/s apart in theta_dot(0) separate by more than 1e-6 (the bike is unstable: "
             "beyond it no comparison means anything), or the end of the shorter run; the "
             "variants run only to it. These errors are reported, not judged: a fixed-step "
             "integrator's error is judged by its convergence order (next section).")
    rows = [row for p in parts for row in p.rows]
    sec.comparisons = [c for p in parts for c in p.comparisons]
    sec.table(("scenario", "horizon [s]", "horizon set by", "variant",
               "max error, 8 coordinates, to the horizon [rad, m]",
               f"first coordinate past {DIVERGED:g}", "end (status)"), rows)
    sec.text("Initial state of each run, projected once on `thesis-disc` and used by the "
             "reference and every variant: " + "; ".join(p.correction for p in parts) + ".")
    sec.blocks += [p.figure for p in parts]
    return sec


def _convergence_row(sec: Section, label: str, eng_model, ref_model, study, expected: str,
                     why: str, scenario: str, rows: list, curves: list) -> None:
    ok = study.verdict == expected
    rows.append((f"{label}, {eng_model.contact} contact", ref_model.name,
                 ", ".join(f"{e:.2e}" for e in study.errors), f"{study.order:.2f}",
                 study.verdict, expected + (f" ({why})" if why else ""), "yes" if ok else "NO"))
    sec.comparisons.append(Comparison.of({
        "quantity": "convergence order", "scenario": scenario, "model": ref_model.name,
        "engines": ["reference", f"{label.replace(' ', '-')}-{eng_model.contact}"],
        "max_error": study.difference, "tolerance": None, "order": study.order,
        "steps": list(study.steps), "errors": list(study.errors), "verdict": study.verdict,
        "expected": expected, "passed": ok, "reason": study.verdict_reason,
        "localized_to": f"order {study.order:.2f}: {study.verdict}"
                        + (" (expected: declared model difference)" if why else "")}))
    curves.append({"label": f"{label} ({eng_model.contact}) vs reference {ref_model.name}: "
                            f"order {study.order:.2f}",
                   "steps": list(study.steps), "errors": list(study.errors)})


CONVERGENCE_HEADER = ("engine", "reference", "errors by step [rad, m]", "fitted order",
                      "verdict", "expected", "as expected")


def convergence_section(spec: str, quick: bool, model: str | None = None) -> Section:
    """The convergence study of ``spec`` on the thesis bicycle, or on ``model`` (a user's
    disc-contact bicycle: the first variant against the reference on the same model, which
    must converge). A stage."""
    from engines.facts import engine_facts
    from .cases import model_spec, on_model
    facts = engine_facts(spec)
    fixed = facts.fixed_step
    steps = convergence_steps(quick, fixed)
    build = lambda m, v: (lambda h: _build(spec, m, fixed, v, **{fixed.option: h}))
    rows, curves = [], []
    base = SCENARIOS["stability-psid10"]
    if model is None:
        sc = base
        sec = Section(f"{facts.label} convergence: integrator error or model difference?")
        sec.text(f"{sc.name} up to {CONVERGENCE_HORIZON} s at four steps"
                 + (" (`--quick`: each twice the full run's, and without the thesis-contact run)"
                    if quick else "") + f". An error that shrinks at the solver's order (about "
                 f"{fixed.order:g}) is the integrator's; one that does not is a difference "
                 "between the models. The disc-contact variant against the thesis-contact "
                 "reference is declared as an expected model difference (the two front contact "
                 "points differ when lean and steer are both non-zero): its 'does not converge' "
                 "is the expected verdict, and it would be reported as unexpected if it ever "
                 "converged.")
        disc, thesis = load_model("thesis-disc"), load_model("thesis")
        mismatch = next(e for e in sc.expected_differences if e.quantity == "convergence order")
        cases = [(v, disc, disc, "converges") for v in fixed.variant_names]
        if fixed.thesis_variant is not None:
            cases.append((fixed.thesis_variant, disc, thesis, mismatch.expected))
            if not quick:   # the variant's own thesis contact
                cases.append((fixed.thesis_variant, thesis, thesis, "converges"))
        fig_name = f"{_slug(facts.name)}_convergence.png"
    else:
        m = model_spec(model)
        sc = on_model(base, m)
        one = load_model(model)
        sec = Section(f"{facts.label} convergence on {m.name}: integrator error or model "
                      "difference?")
        sec.text(f"{sc.name} up to {CONVERGENCE_HORIZON} s at four steps (h = "
                 + ", ".join(f"{h:g}" for h in steps) + f" s): {facts.label} built from "
                 f"{m.name} against the reference built from the same file, the same "
                 f"{one.contact} front contact. An error that shrinks at the solver's order is "
                 "the integrator's; one that does not is a difference between the models, and "
                 "here none is declared: the expected verdict is 'converges'.")
        cases = [(fixed.variant_names[0], one, one, "converges")]
        mismatch = None
        fig_name = f"{_slug(facts.name)}_convergence_{_slug(m.name)}.png"
    made = {}   # (variant, engine model) -> its runs at the steps: one set per pair, however
    for variant, eng_model, ref_model, expected in cases:   # many references judge it
        factory = build(eng_model, variant)
        key = (variant, eng_model.name)
        if key not in made:
            made[key] = [factory(h).simulate(sc, t_end=CONVERGENCE_HORIZON) for h in steps]
        study = convergence_study(ref_model, factory, sc, steps=steps,
                                  horizon=CONVERGENCE_HORIZON, runs=made[key])
        why = ("declared model difference: " + mismatch.reason) if expected != "converges" else ""
        _convergence_row(sec, " ".join(x for x in (facts.name, variant) if x), eng_model,
                         ref_model, study, expected, why, sc.name, rows, curves)
    sec.table(CONVERGENCE_HEADER, rows,
              note="Errors: max over the eight coordinates up to "
                   f"{CONVERGENCE_HORIZON} s, at h = " + ", ".join(f"{h:g}" for h in steps)
                   + " s. The 'order' column is the fitted slope of log error against log h.")
    sec.figure(fig_name, "convergence", curves=curves, horizon=CONVERGENCE_HORIZON,
               title=f"{facts.label} against the reference, {sc.name}")
    return sec


def _slug(name: str) -> str:
    from .cases import slug
    return slug(name)


class FixedStepStage(Stage):
    """Trajectories and convergence order of every engine declaring a fixed-step integrator."""

    name, section = "fixed-step", "fixed-step"

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        out = []
        for f in plan.engines(lambda f: f.fixed_step is not None):
            if not plan.opts.models:
                for n in (QUICK_FORWARD if plan.quick else FORWARD):
                    out.append(Task(("trajectory", f.spec, n), trajectory_part, (f.spec, n),
                                    TRAJECTORY_COSTS.get(n, 0.5) * len(f.fixed_step.variants),
                                    f"{f.label} trajectories: {n}", f.spec))
                out.append(Task(("convergence", f.spec, None), convergence_section,
                                (f.spec, plan.quick), 3.0 if plan.quick else 5.0,
                                f"{f.label} convergence order", f.spec))
            for m in plan.opts.models:
                out.append(Task(("convergence", f.spec, m.spec), convergence_section,
                                (f.spec, plan.quick, m.spec), 3.0,
                                f"{m.name}: {f.label} convergence order", f.spec))
        return out

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        for spec, f in plan.facts.items():
            keys = [k for k in results if k[0] == "trajectory" and k[1] == spec]
            if keys:
                parts, failures = [], []
                for k in keys:
                    v, failed = self.value(results, k, f"{f.label} trajectories: {k[2]}")
                    (parts.append(v) if failed is None else failures.append(failed))
                if parts:
                    out.sections.append(merge_trajectories(parts, f))
                out.sections += failures
            for k in results:
                if k[0] == "convergence" and k[1] == spec:
                    v, failed = self.value(results, k, f"{f.label} convergence")
                    out.sections.append(failed or v)
        return out
