"""The engines stage of `bicycle-xval run`: Pinocchio term by term, Exudyn trajectories up to
their meaningful horizons, Exudyn's convergence order, and the IFToMM energy drift.

Each section returns its comparisons (for summary.json), markdown lines and figures. What
passes or fails:

* terms (Pinocchio): each quantity against its tolerance in `tolerances.toml`;
* trajectories (Exudyn): errors are *reported* against time up to the horizon where two
  reference runs 1e-9 rad/s apart still agree (the bike is unstable: beyond it nothing is
  meaningful); the verdict on them is the convergence study's;
* convergence: a matched model must converge at the solver's order (verdict 'converges'); the
  disc-contact build against the thesis-contact reference is a declared, expected model
  difference, and is reported as unexpected if it ever stops differing.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from engines import load_engine
from reference_model import COORDINATES, load_model
from reference_model.scenarios import SCENARIOS

from .convergence import (DEFAULT_STEPS, error_vs_time, reference_horizon, reference_run,
                          convergence_study)
from .energy import describe_drift, energy_drifts, free_roll_model
from .terms import compare_terms, random_states
from .tolerances import load_tolerances

EXUDYN_STEP = 1e-3
BUILDS = ("tree", "redundant")
CONVERGENCE_HORIZON = 0.5   # s: psid10 before its steer runs away (asymptotic regime of the errors)
FORWARD = ("stability-psid0", "stability-psid1", "stability-psid5", "stability-psid10", "replay")
QUICK_FORWARD = ("stability-psid5",)


@dataclass
class Section:
    """One section of the report."""

    title: str
    lines: list[str] = field(default_factory=list)
    comparisons: list[dict] = field(default_factory=list)
    figures: list[str] = field(default_factory=list)


def _md(text) -> str:
    return str(text).replace("|", "\\|")


def _savefig(fig, out: Path, name: str, section: Section) -> None:
    import matplotlib.pyplot as plt
    fig.tight_layout()
    fig.savefig(out / "figures" / name, dpi=90)
    plt.close(fig)
    section.figures.append(name)   # linked after the section's text and tables


# -- Pinocchio: term by term -----------------------------------------------------------------

def pinocchio_terms(out: Path, n_states: int, progress: Callable[[str], None]) -> Section:
    import matplotlib.pyplot as plt
    sec = Section("Reference vs Pinocchio, term by term")
    sec.lines += [f"At {n_states} deterministic states (large lean, steer near ±π/2, rates up to "
                  "20 rad/s); errors relative to the scale each tolerance names "
                  "(`comparisons/tolerances.toml`).", "",
                  "| model | quantity | max error | tolerance | verdict | worst entry |",
                  "|---|---|---|---|---|---|"]
    states = random_states(n_states, seed=7)
    for name in ("thesis", "thesis-disc"):
        progress(f"  Pinocchio terms on {name} ...")
        model = load_model(name)
        ref, pin = load_engine("reference", model), load_engine("pinocchio", model)
        for r in compare_terms(ref, pin, states):
            sec.lines.append(f"| {name} | {r.quantity} | {r.max_error:.1e} | {r.tolerance:.0e} | "
                             f"{'pass' if r.passed else 'FAIL'} | {_md(r.worst_entry)} |")
            sec.comparisons.append({
                "quantity": r.quantity, "scenario": f"random-states-{n_states}", "model": name,
                "engines": list(r.engines), "max_error": r.max_error, "tolerance": r.tolerance,
                "passed": r.passed, "localized_to": r.worst_entry})
        if name == "thesis":
            diff = np.abs(ref.mass_matrix(states.q) - pin.mass_matrix(states.q)).max(axis=0)
            scale = np.abs(ref.mass_matrix(states.q)).max()
            fig, ax = plt.subplots(figsize=(5.2, 4.4))
            im = ax.imshow(np.log10(np.maximum(diff / scale, 1e-18)), cmap="viridis", vmin=-18, vmax=-12)
            ax.set_xticks(range(8), COORDINATES, rotation=45)
            ax.set_yticks(range(8), COORDINATES)
            fig.colorbar(im, ax=ax, label="log10 max |M_ref - M_pin| / max|M|")
            ax.set_title("mass matrix: reference vs Pinocchio\n(tolerance 1e-12 = top of the scale)")
            _savefig(fig, out, "mass_matrix_error_pinocchio.png", sec)
    return sec


def exudyn_terms(n_states: int, progress) -> Section:
    """The terms Exudyn's kinematic tree provides (M, and Qv + Qgrav + Qaero + S T)."""
    sec = Section("Reference vs Exudyn kinematic tree, term by term")
    sec.lines += [f"At {n_states} deterministic states, `thesis-disc` (the terms do not depend on "
                  "the contact model): M from Exudyn's ComputeMassMatrix in the thesis's joint "
                  "coordinates.", "", "| quantity | max error | tolerance | verdict | worst entry |",
                  "|---|---|---|---|---|"]
    progress("  Exudyn tree terms ...")
    model = load_model("thesis-disc")
    ref, exu = load_engine("reference", model), load_engine("exudyn", model, build="tree")
    for r in compare_terms(ref, exu, random_states(n_states, seed=7)):
        sec.lines.append(f"| {r.quantity} | {r.max_error:.1e} | {r.tolerance:.0e} | "
                         f"{'pass' if r.passed else 'FAIL'} | {_md(r.worst_entry)} |")
        sec.comparisons.append({
            "quantity": r.quantity, "scenario": f"random-states-{n_states}", "model": model.name,
            "engines": ["reference", "exudyn-tree"], "max_error": r.max_error,
            "tolerance": r.tolerance, "passed": r.passed, "localized_to": r.worst_entry})
    return sec


# -- Exudyn: trajectories up to the horizon --------------------------------------------------

def exudyn_trajectories(out: Path, scenarios, progress) -> Section:
    import matplotlib.pyplot as plt
    sec = Section("Reference vs Exudyn, forward trajectories (disc contact)")
    sec.lines += [
        f"Both Exudyn builds at h = {EXUDYN_STEP:g} against the reference `thesis-disc` (DOP853, "
        "rtol 1e-11, projection). The horizon is where two reference runs 1e-9 rad/s apart in "
        "theta_dot(0) separate by more than 1e-6 (the bike is unstable: beyond it no comparison "
        "means anything), or the end of the shorter run.", "",
        "| scenario | horizon [s] | why | build | max error, all 8 coordinates, up to horizon | first to exceed 1e-6 | end (status) |",
        "|---|---|---|---|---|---|---|"]
    model = load_model("thesis-disc")
    corrections = []
    for name in scenarios:
        sc = SCENARIOS[name]
        progress(f"  Exudyn {name}: reference, twin and both builds ...")
        ref = reference_run(model, sc)
        corrections.append(f"- {name}: {_md(ref.settings['initial_correction'])}")
        hor = reference_horizon(model, sc, reference=ref)
        fig, ax = plt.subplots(figsize=(7, 3.6))
        for build in BUILDS:
            traj = load_engine("exudyn", model, build=build, step=EXUDYN_STEP).simulate(sc)
            err = error_vs_time(ref, traj, coords=COORDINATES, horizon=hor.t)
            worst = float(err["max"].max())
            over = np.flatnonzero(err["max"] > 1e-6)
            first = "-"
            if over.size:
                k = int(over[0])
                c = max(COORDINATES, key=lambda c: err[c][k])
                first = f"{c} at {err['t'][k]:.2f} s"
            sec.lines.append(f"| {name} | {hor.t:.2f} | {hor.limited_by} | {build} | {worst:.2e} | "
                             f"{first} | {traj.t_end:.3f} s ({traj.status}) |")
            sec.comparisons.append({
                "quantity": "trajectory (disc builds)", "scenario": name,
                "model": "thesis-disc", "engines": ["reference", f"exudyn-{build}"],
                "max_error": worst, "tolerance": None, "passed": None,
                "horizon": hor.t, "horizon_reason": hor.reason, "localized_to": first,
                "note": "reported, not judged: the convergence study judges Exudyn's trajectories"})
            for c, style in (("theta", "-"), ("xc", ":")):
                ax.semilogy(err["t"], np.maximum(err[c], 1e-16), style, label=f"{build}: {c}")
        ax.axhline(1e-6, color="grey", lw=0.8)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("|exudyn - reference| [rad, m]")
        ax.set_title(f"{name}: error against time up to the horizon ({hor.t:.2f} s)")
        ax.legend(fontsize=7, ncol=2)
        _savefig(fig, out, f"exudyn_error_{name}.png", sec)
    sec.lines += ["", "Initial state of each run, projected once on `thesis-disc` and used by the "
                  "reference and both builds:", ""] + corrections
    return sec


# -- Exudyn: convergence order ---------------------------------------------------------------

def exudyn_convergence(out: Path, quick: bool, progress) -> Section:
    import matplotlib.pyplot as plt
    sec = Section("Exudyn convergence: integrator error or model difference?")
    sec.lines += [
        f"stability-psid10 up to {CONVERGENCE_HORIZON} s at four steps. An error that shrinks at "
        "the solver's order (about 2) is the integrator's; one that does not is a difference "
        "between the models. The disc-contact build against the thesis-contact reference is "
        "declared as an expected model difference (the two front contact points differ when lean "
        "and steer are both non-zero); if it ever converged, that would be reported as unexpected.",
        "", "| engine | reference | errors by step | fitted order | verdict | expected | as expected |",
        "|---|---|---|---|---|---|---|"]
    sc = SCENARIOS["stability-psid10"]
    disc, thesis = load_model("thesis-disc"), load_model("thesis")
    declared = {e.engines: e for e in sc.expected_differences if e.quantity == "convergence order"}
    mismatch = declared["exudyn-tree (disc contact) vs reference (thesis contact)"]
    cases = [("tree", disc, disc, "converges"), ("redundant", disc, disc, "converges"),
             ("tree", disc, thesis, mismatch.expected)]
    if not quick:
        cases.append(("tree", thesis, thesis, "converges"))   # thesis contact via user constraints
    fig, ax = plt.subplots(figsize=(6, 4))
    for build, eng_model, ref_model, expected in cases:
        progress(f"  convergence: exudyn {build} ({eng_model.contact} contact) vs reference "
                 f"{ref_model.name} ...")
        study = convergence_study(
            ref_model, lambda h, b=build, m=eng_model: load_engine("exudyn", m, build=b, step=h),
            sc, steps=DEFAULT_STEPS, horizon=CONVERGENCE_HORIZON)
        ok = study.verdict == expected
        errs = ", ".join(f"{e:.2e}" for e in study.errors)
        label = f"exudyn {build} ({eng_model.contact}) vs reference {ref_model.name}"
        sec.lines.append(f"| exudyn {build}, {eng_model.contact} contact | {ref_model.name} | {errs} | "
                         f"{study.order:.2f} | {study.verdict} | {expected} | "
                         f"{'yes' if ok else 'NO'} |")
        sec.comparisons.append({
            "quantity": "convergence order", "scenario": sc.name, "model": ref_model.name,
            "engines": ["reference", f"exudyn-{build}-{eng_model.contact}"],
            "max_error": study.difference, "tolerance": None, "order": study.order,
            "steps": list(study.steps), "errors": list(study.errors), "verdict": study.verdict,
            "expected": expected, "passed": ok,
            "reason": study.verdict_reason})
        ax.loglog(study.steps, study.errors, "o-", label=f"{label}: order {study.order:.2f}")
    h = np.array(DEFAULT_STEPS)
    ax.loglog(h, 120 * h**2, "k--", lw=0.8, label="slope 2")
    ax.set_xlabel("step h [s]")
    ax.set_ylabel(f"max error up to {CONVERGENCE_HORIZON} s [rad, m]")
    ax.set_title("Exudyn against the reference, stability-psid10")
    ax.legend(fontsize=7)
    _savefig(fig, out, "exudyn_convergence.png", sec)
    return sec


# -- energy drift ----------------------------------------------------------------------------

def energy_section(progress) -> Section:
    sec = Section("Energy drift, torque-free and drag-free (IFToMM: 100 (Emax - Emin) / E0)")
    progress("  energy drift: free roll on the reference and both Exudyn builds ...")
    rows = energy_drifts(free_roll_model(load_model("thesis-disc")), step=EXUDYN_STEP)
    tol = load_tolerances()["energy_drift"]
    sec.lines += ["Free roll from the stability study's leaned and steered state at psi_dot = 10 "
                  "rad/s for 1 s, cv = 0, no torques; potential energy zero at the ground.", "",
                  f"Tolerance {tol.tolerance:g} % (`tolerances.toml` [energy_drift]: {tol.reason})", "",
                  "| engine | settings | E0 [J] | drift [% of E0] | verdict | status |", "|---|---|---|---|---|---|"]
    for r in rows:
        verdict = "pass" if r["status"] != "failed" and r["drift_percent"] <= tol.tolerance else "FAIL"
        sec.lines.append(f"| {r['engine']} | {r['settings']} | {r['E0']:.3f} | "
                         f"{r['drift_percent']:.2e} | {verdict} | {r['status']} at {r['t_end']:.2f} s |")
        ok = r["status"] != "failed" and r["drift_percent"] <= tol.tolerance
        sec.comparisons.append({"quantity": "energy drift percent", "scenario": "free-roll",
                                "model": "thesis-disc (cv = 0)", "engines": [r["engine"]],
                                "max_error": r["drift_percent"], "tolerance": tol.tolerance,
                                "passed": bool(ok), "localized_to": r["settings"],
                                "note": describe_drift(r)})
    return sec


def run_engine_stage(out: Path, engines, quick: bool, progress) -> list[Section]:
    """The sections of the selected engines, in report order."""
    sections = []
    if "pinocchio" in engines:
        progress("engines: Pinocchio term by term ...")
        sections.append(pinocchio_terms(out, 50 if quick else 200, progress))
    if "exudyn" in engines:
        sections.append(exudyn_terms(20 if quick else 100, progress))
        progress("engines: Exudyn trajectories ...")
        sections.append(exudyn_trajectories(out, QUICK_FORWARD if quick else FORWARD, progress))
        progress("engines: Exudyn convergence ...")
        sections.append(exudyn_convergence(out, quick, progress))
        sections.append(energy_section(progress))
    if "pinocchio" in engines and "exudyn" in engines:
        from .benchmark_report import benchmark_section
        progress("benchmark bicycle (Meijaard et al. 2007): eigenvalues, engines, IFToMM manoeuvres ...")
        sections.append(benchmark_section(out, quick, progress))
    return sections
