"""The engine sections of `bicycle-xval run`: Pinocchio and Exudyn's tree term by term, Exudyn
trajectories up to their meaningful horizons, Exudyn's convergence order, the energy drift.

Each function is a stage: top-level (worker processes call it), returns a `Section` of data.
What passes or fails:

* terms: each quantity against its tolerance in `tolerances.toml`;
* trajectories (Exudyn): errors are *reported* against time up to the horizon where two
  reference runs 1e-9 rad/s apart still agree (the bike is unstable: beyond it nothing is
  meaningful); the verdict on them is the convergence study's;
* convergence: a matched model must converge at the solver's order (verdict 'converges'); the
  disc-contact build against the thesis-contact reference is a declared, expected model
  difference, and is reported as unexpected if it ever stops differing.
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
from ..judgments.energy import describe_drift, energy_drifts, free_roll_model
from ..judgments.terms import compare_terms, random_states
from ..judgments.tolerances import Tolerances
from .results import Figure, Section

EXUDYN_STEP = 1e-3
BUILDS = ("tree", "redundant")
CONVERGENCE_HORIZON = 0.5   # s: psid10 before its steer runs away (asymptotic regime of the errors)
FORWARD = ("stability-psid0", "stability-psid1", "stability-psid5", "stability-psid10", "replay")
QUICK_FORWARD = ("stability-psid5",)
#: --quick's convergence steps: the full study's halvings shifted one up, the same 8x span the
#: verdict needs (`convergence.MIN_SPAN`) at half the steps (the finest costs as much as the
#: other three together)
QUICK_CONVERGENCE_STEPS = tuple(2 * h for h in DEFAULT_STEPS)


def convergence_steps(quick: bool) -> tuple[float, ...]:
    """The Exudyn convergence study's steps in a quick or a full run."""
    return QUICK_CONVERGENCE_STEPS if quick else DEFAULT_STEPS
DIVERGED = 1e-6             # rad or m: 'first past' threshold of the trajectory tables


def _term_rows(sec: Section, results, model_name: str, engines: list[str], scenario: str,
               prefix: tuple = ()) -> list[tuple]:
    rows = []
    for r in results:
        rows.append(prefix + (r.quantity, f"{r.max_error:.1e}", f"{r.tolerance:.0e}",
                              "pass" if r.passed else "FAIL", r.worst_entry))
        sec.comparisons.append({
            "quantity": r.quantity, "scenario": scenario, "model": model_name,
            "engines": engines, "max_error": r.max_error, "tolerance": r.tolerance,
            "passed": r.passed, "localized_to": r.worst_entry})
    return rows


# -- Pinocchio: term by term -----------------------------------------------------------------

TERM_HEADER = ("model", "quantity", "max error", "tolerance", "verdict", "worst entry")


THESIS_MODELS = ("thesis", "thesis-disc")


def _terms_on_models(tolerances: Tolerances, sec: Section, spec: str, label: str, options: dict,
                     states, n_states: int, models=THESIS_MODELS) -> tuple[list[tuple], dict]:
    """``spec``'s declared terms against the reference on each of ``models`` (named models or
    parameter files; rows, comparisons into ``sec``). A model the engine cannot represent (a
    declared limitation) is a 'not run' row with the reason; an engine that raises otherwise
    is a FAIL row, counted in the verdict. Returns the rows and the engines built, by model."""
    from engines import UnsupportedModel
    rows, built = [], {}
    for name in models:
        model = load_model(name)
        try:
            eng = load_engine(spec, model, **options)
        except UnsupportedModel as exc:   # declared: not run, and why
            rows.append((model.name, "-", "-", "-", "not run", f"not run on this model: {exc}"))
            continue
        except Exception as exc:   # noqa: BLE001 - the engine failed: a result, counted
            why = f"{type(exc).__name__}: {' '.join(str(exc).split())[:300]}"
            rows.append((model.name, "-", "-", "-", "FAIL", why))
            sec.comparisons.append({"quantity": "engine build", "scenario": "-",
                                    "model": model.name, "engines": [label], "max_error": None,
                                    "tolerance": None, "passed": False, "localized_to": why})
            continue
        built[name] = ref, eng = load_engine("reference", model), eng
        rows += _term_rows(sec, compare_terms(ref, eng, states, tolerances), model.name, ["reference", label],
                           f"random-states-{n_states}", (model.name,))
    return rows, built


def pinocchio_terms(tolerances: Tolerances, n_states: int) -> Section:
    sec = Section("Reference vs Pinocchio, term by term")
    sec.text(f"At {n_states} deterministic states (large lean, steer near ±π/2, rates up to "
             "20 rad/s); errors relative to the scale each tolerance names "
             "(`comparisons/judgments/tolerances.toml`).")
    states = random_states(n_states, seed=7)
    rows, built = _terms_on_models(tolerances, sec, "pinocchio", "pinocchio", {}, states, n_states)
    sec.table(TERM_HEADER, rows)
    ref, pin = built["thesis"]
    M_ref = ref.mass_matrix(states.q)
    diff = np.abs(M_ref - pin.mass_matrix(states.q)).max(axis=0) / np.abs(M_ref).max()
    sec.figure("mass_matrix_error_pinocchio.png", "matrix_error", relative=diff,
               labels=list(COORDINATES), tolerance=tolerances["mass_matrix"].tolerance,
               title="mass matrix: reference vs Pinocchio, max over the states",
               colorbar="log10 max |M_ref - M_pin| / max|M|")
    return sec


def plugin_terms(tolerances: Tolerances, spec: str, options: dict, n_states: int,
                 models=THESIS_MODELS) -> Section:
    """An engine term by term on each of ``models`` (default: the thesis bicycle on both
    contact models; a user's bicycle with ``--model``) where it can represent them: the
    quantities it declares."""
    from .runs import label_of
    label = label_of(spec)
    on = "" if tuple(models) == THESIS_MODELS else f" on {', '.join(load_model(m).name for m in models)}"
    sec = Section(f"Reference vs {label}{on}, term by term")
    sec.text(f"`{spec}`{' with ' + str(options) if options else ''} at {n_states} deterministic "
             "states (large lean, steer near ±π/2, rates up to 20 rad/s), the quantities it "
             "declares; errors relative to the scale each tolerance names.")
    rows, _ = _terms_on_models(tolerances, sec, spec, label, options,
                               random_states(n_states, seed=7), n_states, models)
    sec.table(TERM_HEADER, rows)
    return sec


def exudyn_terms(tolerances: Tolerances, n_states: int) -> Section:
    """The terms Exudyn's kinematic tree provides (M, and Qv + Qgrav + Qaero + S T)."""
    sec = Section("Reference vs Exudyn kinematic tree, term by term")
    sec.text(f"At {n_states} deterministic states, `thesis-disc` (the terms do not depend on the "
             "contact model): M from Exudyn's ComputeMassMatrix in the thesis's joint coordinates.")
    model = load_model("thesis-disc")
    ref, exu = load_engine("reference", model), load_engine("exudyn", model, build="tree")
    rows = _term_rows(sec, compare_terms(ref, exu, random_states(n_states, seed=7), tolerances), model.name,
                      ["reference", "exudyn-tree"], f"random-states-{n_states}")
    sec.table(("quantity", "max error", "tolerance", "verdict", "worst entry"), rows)
    return sec


# -- Exudyn: trajectories up to the horizon --------------------------------------------------

def first_past(err: dict, threshold: float = DIVERGED) -> str:
    """'theta at 0.89 s': the first coordinate past ``threshold`` and when; '' if none."""
    over = np.flatnonzero(err["max"] > threshold)
    if not over.size:
        return ""
    k = int(over[0])
    return f"{max(COORDINATES, key=lambda c: err[c][k])} at {err['t'][k]:.2f} s"


@dataclass
class TrajectoryPart:
    """One scenario's share of the trajectory section (a stage of its own, run in parallel)."""

    rows: list[tuple]
    comparisons: list[dict]
    figure: Figure
    correction: str


def exudyn_trajectory(name: str) -> TrajectoryPart:
    """One forward scenario on both Exudyn builds against the reference `thesis-disc`."""
    comparisons: list[dict] = []
    model = load_model("thesis-disc")
    sc = SCENARIOS[name]
    ref = reference_run(model, sc)
    hor = reference_horizon(model, sc, reference=ref)
    # nothing beyond the horizon is compared, so the engines run only to it (and two samples)
    start, step, n = sc.grid
    cut = dataclasses.replace(sc, grid=(start, step, min(n, int(np.ceil((hor.t - start) / step)) + 3)))
    rows, curves = [], {}
    for build in BUILDS:
        traj = load_engine("exudyn", model, build=build, step=EXUDYN_STEP).simulate(cut)
        err = error_vs_time(ref, traj, coords=COORDINATES, horizon=hor.t)
        worst = float(err["max"].max())
        first = first_past(err)
        rows.append((name, f"{hor.t:.2f}", hor.limited_by, build, f"{worst:.2e}",
                     first or f"none (all below {DIVERGED:g})",
                     f"{traj.t_end:.3f} s ({traj.status}{', run to the horizon' if cut.grid[2] < n else ''})"))
        comparisons.append({
            "quantity": "trajectory (disc builds)", "scenario": name,
            "model": "thesis-disc", "engines": ["reference", f"exudyn-{build}"],
            "max_error": worst, "tolerance": None, "passed": None,
            "horizon": hor.t, "horizon_reason": hor.reason, "localized_to": first or "-",
            "note": "reported, not judged: the convergence study judges Exudyn's trajectories"})
        curves[build] = {"t": err["t"], "theta": err["theta"], "xc": err["xc"]}
    fig = Figure(f"exudyn_error_{name}.png", "error_vs_time",
                 dict(curves=curves, horizon=hor.t, threshold=DIVERGED,
                      title=f"{name}: Exudyn against the reference up to the horizon ({hor.t:.2f} s)"))
    return TrajectoryPart(rows, comparisons, fig, f"{name}: {ref.settings['initial_correction']}")


def merge_trajectories(parts: list[TrajectoryPart]) -> Section:
    """The per-scenario trajectory stages as one section (one table, one figure each)."""
    sec = Section("Reference vs Exudyn, forward trajectories (disc contact)")
    sec.text(f"Both Exudyn builds at h = {EXUDYN_STEP:g} s against the reference `thesis-disc` "
             "(DOP853, rtol 1e-11, projection). The *horizon* is where two reference runs "
             "1e-9 rad/s apart in theta_dot(0) separate by more than 1e-6 (the bike is unstable: "
             "beyond it no comparison means anything), or the end of the shorter run; the builds "
             "run only to it. These "
             "errors are reported, not judged: a fixed-step integrator's error is judged by its "
             "convergence order (next section).")
    rows = [row for p in parts for row in p.rows]
    sec.comparisons = [c for p in parts for c in p.comparisons]
    sec.table(("scenario", "horizon [s]", "horizon set by", "build",
               "max error, 8 coordinates, to the horizon [rad, m]",
               f"first coordinate past {DIVERGED:g}", "end (status)"), rows)
    sec.text("Initial state of each run, projected once on `thesis-disc` and used by the "
             "reference and both builds: " + "; ".join(p.correction for p in parts) + ".")
    sec.blocks += [p.figure for p in parts]
    return sec


# -- Exudyn: convergence order ---------------------------------------------------------------

def exudyn_convergence(quick: bool, model: str | None = None) -> Section:
    """The convergence study on the thesis bicycle, or on ``model`` (a user's disc-contact
    bicycle: Exudyn's tree against the reference on the same model, which must converge)."""
    if model is not None:
        return _model_convergence(quick, model)
    steps = convergence_steps(quick)
    sec = Section("Exudyn convergence: integrator error or model difference?")
    sec.text(f"stability-psid10 up to {CONVERGENCE_HORIZON} s at four steps"
             + (" (`--quick`: each twice the full run's, and without the thesis-contact tree)"
                if quick else "") + ". An error that "
             "shrinks at the solver's order (about 2) is the integrator's; one that does not is a "
             "difference between the models. The disc-contact build against the thesis-contact "
             "reference is declared as an expected model difference (the two front contact "
             "points differ when lean and steer are both non-zero): its 'does not converge' is "
             "the expected verdict, and it would be reported as unexpected if it ever converged.")
    sc = SCENARIOS["stability-psid10"]
    disc, thesis = load_model("thesis-disc"), load_model("thesis")
    declared = {e.engines: e for e in sc.expected_differences if e.quantity == "convergence order"}
    mismatch = declared["exudyn-tree (disc contact) vs reference (thesis contact)"]
    cases = [("tree", disc, disc, "converges"), ("redundant", disc, disc, "converges"),
             ("tree", disc, thesis, mismatch.expected)]
    if not quick:
        cases.append(("tree", thesis, thesis, "converges"))   # thesis contact via user constraints
    rows, curves = [], []
    for build, eng_model, ref_model, expected in cases:
        study = convergence_study(
            ref_model, lambda h, b=build, m=eng_model: load_engine("exudyn", m, build=b, step=h),
            sc, steps=steps, horizon=CONVERGENCE_HORIZON)
        ok = study.verdict == expected
        why = ("declared model difference: " + mismatch.reason) if expected != "converges" else ""
        rows.append((f"exudyn {build}, {eng_model.contact} contact", ref_model.name,
                     ", ".join(f"{e:.2e}" for e in study.errors), f"{study.order:.2f}",
                     study.verdict, expected + (f" ({why})" if why else ""),
                     "yes" if ok else "NO"))
        sec.comparisons.append({
            "quantity": "convergence order", "scenario": sc.name, "model": ref_model.name,
            "engines": ["reference", f"exudyn-{build}-{eng_model.contact}"],
            "max_error": study.difference, "tolerance": None, "order": study.order,
            "steps": list(study.steps), "errors": list(study.errors), "verdict": study.verdict,
            "expected": expected, "passed": ok, "reason": study.verdict_reason,
            "localized_to": f"order {study.order:.2f}: {study.verdict}"
                            + (" (expected: declared model difference)" if why else "")})
        curves.append({"label": f"exudyn {build} ({eng_model.contact}) vs reference "
                                f"{ref_model.name}: order {study.order:.2f}",
                       "steps": list(study.steps), "errors": list(study.errors)})
    sec.table(("engine", "reference", "errors by step [rad, m]", "fitted order", "verdict",
               "expected", "as expected"), rows,
              note="Errors: max over the eight coordinates up to "
                   f"{CONVERGENCE_HORIZON} s, at h = " + ", ".join(f"{h:g}" for h in steps)
                   + " s. The 'order' column is the fitted slope of log error against log h.")
    sec.figure("exudyn_convergence.png", "convergence", curves=curves,
               horizon=CONVERGENCE_HORIZON, title="Exudyn against the reference, stability-psid10")
    return sec


def _model_convergence(quick: bool, spec: str) -> Section:
    from .cases import model_spec, on_model
    steps = convergence_steps(quick)
    m = model_spec(spec)
    model = load_model(spec)
    sc = on_model(SCENARIOS["stability-psid10"], m)
    sec = Section(f"Exudyn convergence on {m.name}: integrator error or model difference?")
    sec.text(f"{sc.name} up to {CONVERGENCE_HORIZON} s at four steps (h = "
             + ", ".join(f"{h:g}" for h in steps) + " s): Exudyn's kinematic tree built from "
             f"{m.name} against the reference built from the same file, the same {model.contact} "
             "front contact. An error that shrinks at the solver's order (about 2) is the "
             "integrator's; one that does not is a difference between the models, and here none "
             "is declared: the expected verdict is 'converges'.")
    study = convergence_study(model, lambda h: load_engine("exudyn", model, build="tree", step=h),
                              sc, steps=steps, horizon=CONVERGENCE_HORIZON)
    ok = study.verdict == "converges"
    sec.table(("engine", "reference", "errors by step [rad, m]", "fitted order", "verdict",
               "expected", "as expected"),
              [(f"exudyn tree, {model.contact} contact", model.name,
                ", ".join(f"{e:.2e}" for e in study.errors), f"{study.order:.2f}", study.verdict,
                "converges", "yes" if ok else "NO")],
              note=f"Errors: max over the eight coordinates up to {CONVERGENCE_HORIZON} s.")
    sec.comparisons.append({
        "quantity": "convergence order", "scenario": sc.name, "model": model.name,
        "engines": ["reference", f"exudyn-tree-{model.contact}"],
        "max_error": study.difference, "tolerance": None, "order": study.order,
        "steps": list(study.steps), "errors": list(study.errors), "verdict": study.verdict,
        "expected": "converges", "passed": ok, "reason": study.verdict_reason,
        "localized_to": f"order {study.order:.2f}: {study.verdict}"})
    sec.figure(f"exudyn_convergence_{_slug(m.name)}.png", "convergence",
               curves=[{"label": f"exudyn tree vs reference {model.name}: order "
                                 f"{study.order:.2f}",
                        "steps": list(study.steps), "errors": list(study.errors)}],
               horizon=CONVERGENCE_HORIZON, title=f"Exudyn against the reference, {sc.name}")
    return sec


def _free_roll_on(spec: str, free) -> tuple:
    """The energy check's free roll on ``spec`` and how it starts, in words. On thesis-disc
    the stability study's leaned and steered state (pi/16) at psi_dot = 10 rad/s; on a user's
    bicycle a gentler start, lean and steer pi/32 at the middle of its self-stable speed range
    (1.2 x its weave speed when it has no capsize speed below 10 m/s, psi_dot = 10 rad/s when
    it has no weave speed either), so that the bicycle does not fall within the second:
    measured on BicycleParameters' Browserins, the thesis's start falls at 0.99 s and even at
    a self-stable speed it reaches 1.3 rad of lean, where Exudyn's drift at h = 1e-3 s is 0.3 %,
    against 1.4e-4 % from pi/32."""
    from ..judgments.energy import free_roll_scenario
    if spec == "thesis-disc":
        return None, "the stability study's leaned and steered state at psi_dot = 10 rad/s"
    from .stability import critical
    crit = critical(spec) if free.contact == "disc" else {}
    if "weave" in crit:
        v = (0.5 * (crit["weave"] + crit["capsize"]) if "capsize" in crit
             else 1.2 * crit["weave"])
        psi_dot = v / free.params.R_rear
    else:
        psi_dot = 10.0
    sc = free_roll_scenario(psi_dot=psi_dot, model=free.name, lean=np.pi / 32)
    return sc, (f"lean and steer pi/32 at psi_dot = {psi_dot:.4g} rad/s "
                f"(v = {psi_dot * free.params.R_rear:.3f} m/s"
                + (", the middle of its self-stable range)" if "capsize" in crit else ")"))


def _slug(name: str) -> str:
    from .cases import slug
    return slug(name)


# -- energy drift ----------------------------------------------------------------------------

def energy_section(tolerances: Tolerances, model: str = "thesis-disc") -> Section:
    """The energy drift of a torque- and drag-free roll of ``model`` (default thesis-disc; a
    user's bicycle with ``--model``) on the reference and Exudyn's builds."""
    sec = Section("Energy drift, torque-free and drag-free (IFToMM: 100 (Emax - Emin) / E0)"
                  + ("" if model == "thesis-disc" else f" on {load_model(model).name}"))
    free = free_roll_model(load_model(model))
    scenario, start = _free_roll_on(model, free)
    rows = energy_drifts(free, scenario, step=EXUDYN_STEP)
    tol = tolerances["energy_drift"]
    sec.text(f"Free roll from {start} for 1 s, cv = 0, no torques; potential energy zero at "
             "the ground.",
             f"Tolerance {tol.tolerance:g} % (`tolerances.toml` [energy_drift]: {tol.reason})")
    table = []
    for r in rows:
        ok = r["status"] != "failed" and r["drift_percent"] <= tol.tolerance
        table.append((r["engine"], r["settings"], f"{r['E0']:.3f}", f"{r['drift_percent']:.2e}",
                      "pass" if ok else "FAIL", f"{r['status']} at {r['t_end']:.2f} s"))
        sec.comparisons.append({"quantity": "energy drift percent", "scenario": "free-roll",
                                "model": f"{free.name} (cv = 0)", "engines": [r["engine"]],
                                "max_error": r["drift_percent"], "tolerance": tol.tolerance,
                                "passed": bool(ok), "localized_to": r["settings"],
                                "note": describe_drift(r)})
    sec.table(("engine", "settings", "E0 [J]", "drift [% of E0]", "verdict", "status"), table)
    return sec
