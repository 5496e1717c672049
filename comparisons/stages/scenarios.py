"""The scenario stages of `bicycle-xval run`: every selected scenario on the reference model,
then every engine's run of it compared with the reference's as its registry entry says
(`reference_model.scenarios`: ``compared``), and the thesis's claims judged engine by engine.

`reference_rows` is the table of the reference's own runs with the analytic check of the check
scenario; `compare_scenarios` returns the comparisons section with its figures' data.
"""

from __future__ import annotations

import numpy as np

from engines.facts import engine_facts
from engines.runs import Run
from reference_model import CONSTRAINT_NAMES, load_model
from reference_model.scenarios import get_scenario

from ..judgments.convergence import HORIZON_THRESHOLD, reference_horizon
from ..judgments.contact import declared_difference_rows
from ..judgments.scenario_compare import (compare_constraints, compare_forward, compare_inverse,
                                          compare_mass_matrix, constraint_series,
                                          trajectory_error)
from ..judgments.tolerances import Tolerances
from ..judgments.rows import Comparison
from .isolated import failures_as_rows, unjudgeable
from .results import Section, num, verdict_word

CHECK_RELATIVE = 1e-12   # check torques: round-off of the 13x13 solve, relative to Mped
M_STATES = 100           # states along a run at which M is compared


def horizon_of(scenario):
    """The meaningful horizon of a forward scenario (a built-in's name or a `Scenario`; two
    reference runs; a stage of its own)."""
    sc = get_scenario(scenario) if isinstance(scenario, str) else scenario
    return reference_horizon(load_model(sc.model), sc)


def analytic_check(run: Run, model) -> dict:
    """The check scenario's analytic torques: Mped = cv (R psi_dot)^2 R, Mdir = Mvue = 0."""
    p = model.params
    expected = p.cv * (p.R_rear * 5.0) ** 2 * p.R_rear
    err = float(np.max(np.abs(run.T - [0.0, expected, 0.0])))
    return {"check": "check: Mped = cv (R psi_dot)^2 R, Mdir = Mvue = 0",
            "value": err, "tolerance": CHECK_RELATIVE * expected,
            "passed": bool(err <= CHECK_RELATIVE * expected),
            "evidence": f"Mped = {expected:.12g} N m expected; max deviation {err:.2e} N m over "
                        f"{len(run.t)} samples"}


def reference_rows(names, runs: dict, cases: dict | None = None
                   ) -> tuple[list[dict], list[dict], dict[str, str]]:
    """(rows of the reference's runs, analytic checks, initial-state corrections by scenario);
    ``cases`` maps names that are not built-ins to their scenarios."""
    rows, checks, corrections = [], [], {}
    for name in names:
        run = runs[("reference", name)]
        model = load_model(_scenario(name, cases).model)
        C = model.constraint_residual(run.q, run.dq) if run.t.size else np.zeros((1, 5))
        rows.append({"scenario": name, "kind": run.kind, "status": run.status,
                     "t_end": f"{run.t_end:.3f}", "max_abs_C": f"{np.abs(C).max():.1e}"})
        if run.kind == "inverse" and name == "check" and run.T is not None:
            checks.append(analytic_check(run, model))
        if run.trajectory is not None and "initial_correction" in run.trajectory.settings:
            corrections[name] = run.trajectory.settings["initial_correction"]
        elif "beta corrected by" in run.message:   # an inverse run on another geometry
            corrections[name] = run.message.split("; ", 1)[1]
    return rows, checks, corrections


def _build_if_it_models(setup, model, failures: list[dict]):
    """The engine built from ``model``, or None when it cannot represent ``model`` (a declared
    limitation: a front contact it does not model, a body it cannot compile; its runs say
    'not run' with why) or raises while being built (a failure of that engine, appended to
    ``failures`` as a comparison row, so the verdict counts it and every other engine's
    results stay)."""
    from engines import UnsupportedModel
    try:
        return setup.build(model)
    except UnsupportedModel:
        return None
    except Exception as exc:   # noqa: BLE001 - an engine failure is a result, not a crash
        failures.append(Comparison.of({"quantity": "engine build", "scenario": "-", "model": model.name,
                         "engines": [setup.label], "max_error": None, "tolerance": None,
                         "passed": False,
                         "localized_to": f"{type(exc).__name__}: {' '.join(str(exc).split())[:300]}",
                         "note": f"{setup.label} raised while being built on {model.name}"}))
        return None


def run_difference(setup) -> str | None:
    """The model difference the setup's engine declares for its forward runs (a soft contact),
    or None (`engines.base.Engine.run_difference`)."""
    return engine_facts(setup.engine).run_difference


class _MassInOneCall:
    """An engine's M at the states of every scenario of one model, asked for in one call.

    In `compare_scenarios` each call of the main process costs a fork and a build of the
    engine (`isolated`): one call per engine and scenario made 40 of them, 1.1 s of the main
    process's 1.5 s after the runs (measured on the 2-core machine). ``blocks``: scenario name
    -> its states. ``at(name)`` is the engine as `compare_mass_matrix` sees it for that
    scenario; a failure of the one call is that engine's failure on every scenario, each
    reported as before (`failures_as_rows`)."""

    def __init__(self, engine, blocks: dict[str, np.ndarray]):
        self.engine, self.values, self.error = engine, {}, None
        if not blocks or not engine.supports("mass_matrix"):
            return
        try:
            total = sum(len(q) for q in blocks.values())
            M = np.asarray(engine.mass_matrix(np.concatenate(list(blocks.values()))), dtype=float)
            if len(M) != total:
                raise ValueError(f"mass_matrix returned {len(M)} matrices for {total} states")
            k = 0
            for name, q in blocks.items():
                self.values[name], k = M[k:k + len(q)], k + len(q)
        except Exception as exc:   # noqa: BLE001 - reported per scenario by failures_as_rows
            self.error = exc

    def at(self, name: str):
        return _MassOf(self, name)


class _MassOf:
    """One scenario's view of a `_MassInOneCall`: the engine's M at that scenario's states."""

    def __init__(self, batch: _MassInOneCall, scenario: str):
        self.batch, self.scenario = batch, scenario
        self.name, self.model = batch.engine.name, batch.engine.model

    def supports(self, capability: str) -> bool:
        return self.batch.engine.supports(capability)

    def mass_matrix(self, q):
        if self.batch.error is not None:
            raise self.batch.error
        return self.batch.values[self.scenario]


def _mass_states(names, cases, runs, horizons) -> dict[str, np.ndarray]:
    """The reference's states (about `M_STATES` of each run) at which M is compared, by
    scenario, for the scenarios that compare it and can be judged."""
    out = {}
    for name in names:
        sc, ref = _scenario(name, cases), runs[("reference", name)]
        if "mass_matrix" in sc.compared and ref.t.size and not unjudgeable(ref, sc, horizons):
            out[name] = ref.q[::max(1, len(ref.t) // M_STATES)]
    return out


def _scenario(name: str, cases: dict | None):
    return cases[name] if cases and name in cases else get_scenario(name)


def compare_scenarios(tolerances: Tolerances, names, setups: dict, runs: dict, horizons: dict,
                      cases: dict | None = None) -> Section:
    """What each scenario's registry entry says is compared (judged by ``tolerances``), with
    the figures' data."""
    tols = tolerances
    labels = list(setups)
    sec = Section("Every engine on every scenario")
    sec.text("What each scenario's file (`reference_model/scenario_data/`) lists as "
             f"compared: M at ~{M_STATES} of the reference's states, torques and multipliers "
             "along the inverse scenarios, all eight coordinates up to the *meaningful horizon* "
             "(where two reference runs 1e-9 rad/s apart in theta_dot(0) part by more than "
             f"{HORIZON_THRESHOLD:g}: the bike is unstable, beyond it no comparison means "
             "anything) and the constraint residual of every run, measured by the reference "
             "model.")
    comps: list[dict] = []
    residuals, stability = {}, {}
    figures = Section("figures")      # collected apart: they follow the table
    built: dict[tuple[str, str], object] = {}
    mass_states = _mass_states(names, cases, runs, horizons)
    for name in names:
        sc = _scenario(name, cases)
        model = load_model(sc.model)
        ref = runs[("reference", name)]
        here = {lab: runs[(lab, name)] for lab in labels
                if (lab, name) in runs and runs[(lab, name)].status != "not run"}
        for lab, r in here.items():   # asked for and not made: that engine's failure, counted
            if lab != "reference" and r.status == "failed":
                comps.append(Comparison.of({"quantity": "engine run", "scenario": name, "model": model.name,
                              "engines": [lab], "max_error": None, "tolerance": None,
                              "passed": False, "localized_to": r.message[:300],
                              "note": f"{lab} did not complete the run it was asked for"}))
        missing = unjudgeable(ref, sc, horizons)   # the yardstick itself failed: say so
        if missing:
            comps.append(Comparison.of({"quantity": "not compared", "scenario": name, "model": model.name,
                          "engines": [lab for lab in here if lab != "reference"] or ["-"],
                          "max_error": None, "tolerance": None, "passed": False,
                          "localized_to": missing}))
            continue
        if name in mass_states:
            engines = {}
            for lab in labels:
                if lab != "reference" and (lab, sc.model) not in built:
                    eng = _build_if_it_models(setups[lab], model, comps)
                    built[(lab, sc.model)] = None if eng is None else _MassInOneCall(
                        eng, {n: q for n, q in mass_states.items()
                              if _scenario(n, cases).model == sc.model})
                if lab != "reference" and built[(lab, sc.model)] is not None:
                    engines[lab] = built[(lab, sc.model)].at(name)
            comps += failures_as_rows(   # one engine's failure is its own row
                lambda e: compare_mass_matrix(name, model, mass_states[name], e, tols), engines,
                "mass_matrix", name, model.name)
        if sc.kind == "inverse":
            for lab, r in here.items():
                if lab != "reference" and r.status == "completed":
                    comps += compare_inverse(ref, r, tols)
            with_T = {k: r for k, r in here.items() if r.T is not None}
            if with_T:
                figures.figure(f"{name}_torques.png", "torque_overlay", scenario=name, runs=with_T)
            continue
        hor = horizons[name]
        errors, lines = {}, {}
        for lab, r in here.items():
            declared = run_difference(setups[lab]) if lab != "reference" else None
            if declared is not None:   # never judged by the ideal-rolling tolerances
                c = compare_constraints(model, r, tols)
                rows = declared_difference_rows(ref, r, hor, declared, c["max_error"],
                                                c["localized_to"])
                comps += [x for x in rows if x["quantity"] != "trajectory"
                          or "trajectory" in sc.compared]
            elif "constraint_residual" in sc.compared:
                comps.append(compare_constraints(model, r, tols))
            if r.t.size:
                C = constraint_series(model, r)
                lines[lab] = (r.t, C[:, 0], C[:, 1:].max(axis=1))
            if lab == "reference" or "trajectory" not in sc.compared or not r.t.size:
                continue
            if declared is not None:
                te = trajectory_error(ref, r, hor.t)
                errors[lab] = (te.t, te.errors.max(axis=1) if te.t.size else te.t)
                continue
            facts = engine_facts(setups[lab].engine)   # how the engine says its runs are judged
            c, te = compare_forward(model, ref, r, hor, tols, judged_by=facts.trajectory_tolerance,
                                    reported_because=facts.trajectory_judged_by or "a study")
            comps += c
            errors[lab] = (te.t, te.errors.max(axis=1) if te.t.size else te.t)
        figures.figure(f"{name}_trajectories.png", "trajectory_overlay", scenario=name, runs=here,
                   errors=errors, horizon=hor.t, threshold=HORIZON_THRESHOLD)
        residuals[name] = lines
        if "stability" in sc.tags:
            for lab, r in here.items():
                stability.setdefault(lab, {})[name] = (r.t, r.q[:, 3], r.status, r.t_end)
    if residuals:
        figures.figure("constraint_residuals.png", "constraint_residuals", panels=residuals,
                   bound=2e-3)
    if stability:
        figures.figure("stability_theta.png", "stability_study", runs=stability)
    zig = runs.get(("reference", "zigzag"))
    replays = {lab: (r.t, r.q[:, 3], r.q[:, 6]) for lab in labels
               if (r := runs.get((lab, "replay"))) is not None and r.t.size}
    if zig is not None and replays:
        figures.figure("replay_vs_zigzag.png", "replay_vs_zigzag",
                   zigzag=(zig.t, zig.q[:, 3], zig.q[:, 6]), replays=replays)
    sec.comparisons = comps
    rows = [(c["quantity"], c["scenario"], " vs ".join(c["engines"]), num(c["max_error"]),
             num(c["tolerance"]), verdict_word(c["passed"], c.get("why", "")),
             c.get("localized_to", "-")) for c in comps]
    sec.table(("quantity", "scenario", "engines", "max error", "tolerance", "verdict",
               "where"), rows,
              note="Errors are relative to the scale the tolerance names for terms, torques and "
                   "multipliers; absolute (rad or m) for trajectories; m or m/s for constraint "
                   f"residuals ({', '.join(CONSTRAINT_NAMES)}).")
    sec.blocks += figures.blocks
    return sec
