"""The soft-contact study: how far an engine's soft wheel-ground contact is from the reference's
ideal rolling, and whether refining its settings gets closer. Every engine that declares
`engines.facts.SoftContact` gets it, with the same tables, figures and judgments.

A soft contact has no rolling constraint: each wheel touches the plane through a soft,
frictional contact (a declared model difference, never judged by the ideal-rolling tolerances).
On `thesis-disc` (the disc contact a soft wheel approximates) and stability-psid10 (the
stability study's fastest run), or on each disc-contact ``--model``, the study reports:

* the contact settings as the engine declares them (`SoftContact.settings_rows`);
* one run at the engine's defaults: slip speed and penetration of each wheel over the run, the
  ground's normal forces, the trajectory error to the reference against time, up to
  `WINDOW`. The reference (DOP853, rtol 1e-11, projection) is checked reproducible to 1e-6
  over that window by its twin 1e-9 rad/s apart (`convergence.meaningful_horizon`). Where the
  ideal model needs the ground to *pull* a wheel down (a negative normal force, which the
  reference's bilateral constraint supplies and a unilateral contact cannot), the engine's
  wheel lifts off: from there on the two models differ in kind, and the run is only shown;
* the refinement study at `STUDY_TIME` (inside both horizons): the error against each series
  of settings the engine declares (`SoftContact.refinements`), each with its fitted order
  (`judgments.contact.refinement_study`), and the engine's own reading of them.

The run's ``diagnostics`` carry per-wheel ``slip_speed_rear/front``, ``penetration_rear/front``
and optionally ``normal_force_rear/front`` (docs/engines.md, "A soft contact's diagnostics").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engines import load_engine
from reference_model import load_model
from reference_model.scenarios import SCENARIOS, torque_input

from ..judgments.contact import contact_fidelity, lift_off_time, refinement_study
from ..judgments.convergence import HORIZON_THRESHOLD, meaningful_horizon, perturbed_scenario, \
    reference_run
from ..judgments.rows import Comparison
from .cases import slug
from .results import Section
from .stage import Assembled, Plan, Stage

__all__ = ["MODEL", "SCENARIO", "STUDY_TIME", "DiscClaims", "SoftContactStage", "claims_on_disc",
           "contact_study", "ideal_normal_forces", "merge_claims", "window"]

SCENARIO = "stability-psid10"
MODEL = "thesis-disc"
STUDY_TIME = 0.3        # s: psid10 before the steer runs away and before any wheel unloads
WINDOW = 0.6            # s: the default run, past the first lift-off (about 0.45 s)
QUICK_WINDOW = 0.5


def window(quick: bool) -> float:
    """The contact study's window (s) in a quick or a full run."""
    return QUICK_WINDOW if quick else WINDOW


def _scenario_on(spec: str):
    """The study's scenario on the model ``spec`` (its own on thesis-disc; bound to a user's
    bicycle, its start made consistent for that geometry, as `cases.on_model` does)."""
    if spec == MODEL:
        return SCENARIOS[SCENARIO]
    from .cases import model_spec, on_model
    return on_model(SCENARIOS[SCENARIO], model_spec(spec))


def _reference(window: float, spec: str = MODEL):
    """The reference on ``spec`` up to ``window`` and how far it is reproducible there."""
    model = load_model(spec)
    sc = _scenario_on(spec)
    ref = reference_run(model, sc, t_end=window)
    twin = reference_run(model, perturbed_scenario(sc), t_end=window)
    hor = meaningful_horizon(ref, twin, what="two reference runs 1e-9 rad/s apart in theta_dot(0)")
    return model, sc, ref, hor


def ideal_normal_forces(model, ref) -> tuple[np.ndarray, np.ndarray]:
    """(rear, front) normal forces (N, up) the reference's ideal rolling needs along ``ref``.

    Front: minus the multiplier of the front contact's height constraint rD_z (exact, from the
    reference's KKT solve at each sample). Rear: the rest of the vertical balance of the whole
    bicycle, sum m_i (z''_Gi + g) - front, with z''_Gi by central differences on the output
    grid (second-order in its 0.01 s interval; used for its sign and size only)."""
    torque = torque_input(model, SCENARIOS[SCENARIO])
    T = (np.array([np.asarray(torque(t), dtype=float) for t in ref.t]) if callable(torque)
         else np.broadcast_to(np.asarray(torque, dtype=float), (ref.t.size, 3)))
    front = -model.forward(ref.q, ref.dq, T).lam[:, 0]
    p = model.params
    pts = model.points(ref.q)
    masses = {"rG2": p.m2, "rG3": p.m3, "rG4": p.m4, "rG5": p.m5}
    mz = sum(m * pts[k][:, 2] for k, m in masses.items())
    total = np.gradient(np.gradient(mz, ref.t), ref.t) + sum(masses.values()) * p.g
    return total - front, front


def contact_study(spec: str, quick: bool, model_spec: str = MODEL) -> Section:
    """The study (module docstring) of the engine ``spec`` as a report section, on thesis-disc
    or on a user's disc-contact bicycle ``model_spec``. A stage."""
    from engines import UnsupportedModel
    from engines.facts import engine_facts
    facts = engine_facts(spec)
    soft = facts.soft_contact
    who = facts.label
    on = "" if model_spec == MODEL else f" on {load_model(model_spec).name}"
    sec = Section(f"{who} contact study{on}: soft contact against ideal rolling")
    window_s = window(quick)
    model, sc, ref, hor = _reference(window_s, model_spec)
    try:
        eng = load_engine(spec, model)
    except UnsupportedModel as exc:   # a declared limitation: said, not failed
        sec.text(f"Not run on this model: {exc}")
        return sec
    run = eng.simulate(sc, t_end=window_s)
    s = run.settings
    sec.text(f"{who} with its own wheel-ground contact, on `{model.name}`"
             + (f" ({soft.about})" if soft.about else "")
             + f", and `{SCENARIO}`, against the reference (DOP853, rtol 1e-11, projection: the "
             "rolling constraints hold exactly). The engine's default contact settings:")
    if soft.settings_rows is not None:
        sec.table(("setting", "value"), soft.settings_rows(s))

    # -- the default run --------------------------------------------------------------------
    lift = lift_off_time(run)
    loaded = min(x for x in (lift, hor.t, run.t_end) if x is not None)
    loaded_end = float(run.t[run.t < loaded - 1e-9][-1]) if lift is not None else loaded
    fid_loaded = contact_fidelity(ref, run, horizon=loaded_end)
    fid_all = contact_fidelity(ref, run, horizon=min(hor.t, run.t_end))
    rear, front = ideal_normal_forces(model, ref)
    need = np.minimum(rear, front)
    pull = np.flatnonzero(need < 0)
    pull_text = (f"the ideal model needs the ground to pull a wheel down from "
                 f"t = {ref.t[pull[0]]:.2f} s ({'rear' if rear[pull[0]] < 0 else 'front'} "
                 f"normal force {need[pull[0]]:.0f} N)" if pull.size else
                 "the ideal model's normal forces stay positive")
    sec.heading("Slip, penetration and trajectory error at the defaults")
    sec.text(f"The reference is reproducible to {HORIZON_THRESHOLD:g} over this window ("
             f"{hor.describe()}). "
             + (f"{who}'s wheels carry load up to {loaded_end:.2f} s; a wheel lifts off at "
                f"{lift:.2f} s, where {pull_text}: the soft contact is unilateral, the "
                "reference's rolling constraint is not, so past that time the runs differ in "
                "kind (a declared model difference), not in accuracy."
                if lift is not None else f"Both wheels stay loaded; {pull_text}."))
    rows = []
    for label, f in (("while both wheels are loaded", fid_loaded),
                     ("whole window", fid_all)):
        rows.append((f"{label} (0 - {f.horizon:.2f} s)", f"{f.slip_max:.2e} ({f.slip_worst})",
                     f"{f.slip_rms:.2e}", f"{f.penetration_max:.2e} ({f.penetration_worst})",
                     f"{f.penetration_rms:.2e}", f"{f.error_max:.2e}"))
    # summary.json: the loaded part only (past a lift-off the models differ in kind)
    f = fid_loaded
    sec.comparisons.append(Comparison.of({
        "quantity": "contact fidelity (slip, penetration, trajectory)", "scenario": sc.name,
        "model": model.name, "engines": ["reference", facts.name], "max_error": f.error_max,
        "tolerance": None, "passed": None, "horizon": f.horizon,
        "slip_max": f.slip_max, "slip_rms": f.slip_rms,
        "penetration_max": f.penetration_max, "penetration_rms": f.penetration_rms,
        "lift_off_s": lift, "ideal_pull_s": float(ref.t[pull[0]]) if pull.size else None,
        "localized_to": f"slip max {f.slip_max:.1e} m/s ({f.slip_worst})",
        "note": "while both wheels are loaded; reported, not judged: a declared model "
                "difference (soft contact)"}))
    sec.table(("up to", "slip max [m/s]", "slip RMS [m/s]", "penetration max [m]",
               "penetration RMS [m]", "max error, 8 coordinates [rad, m]"), rows,
              note="Slip: speed of each wheel's contact point (the disc's lowest point) in the "
                   "ground plane, 0 for ideal rolling; penetration: depth of that point below "
                   "the ground (negative: above it; a leaned cylinder rests on its cap's rim). "
                   "Statistics over both wheels' samples on the 0.01 s grid.")
    d = run.diagnostics
    tag = ("" if model_spec == MODEL else f"_{slug(model.name)}")
    prefix = slug(facts.name)
    sec.figure(f"{prefix}_contact_run{tag}.png", "contact_run",
               t=run.t, error=fid_all.error, horizon=loaded_end,
               slip={"rear": d["slip_speed_rear"], "front": d["slip_speed_front"]},
               penetration={"rear": d["penetration_rear"], "front": d["penetration_front"]},
               normal={"rear": d.get("normal_force_rear"), "front": d.get("normal_force_front")},
               ideal_normal={"t": ref.t, "rear": rear, "front": front}, engine_label=who,
               title=f"{sc.name} on {who} (defaults) against the reference {model.name}")

    # -- the refinement study ---------------------------------------------------------------
    series = [r for r in soft.refinements if not quick or r.quick_values is not None]
    if not series:
        return sec
    ref_study = reference_run(model, sc, t_end=STUDY_TIME)
    simulate = lambda **o: eng.simulate(sc, t_end=STUDY_TIME, **o)
    studies = [refinement_study(ref_study,
                                [(v, simulate(**r.options(v, s)))
                                 for v in (r.quick_values if quick else r.values)],
                                r.parameter, STUDY_TIME, r.held) for r in series]
    sec.heading(f"Refinement: the error at {STUDY_TIME:g} s against the contact's settings")
    rows = []
    for st in studies:
        rows.append((st.parameter.split(" [")[0], st.held,
                     ", ".join(f"{v:g}" for v in st.values),
                     ", ".join(f"{e:.2e}" for e in st.errors),
                     ", ".join(f"{x:.2e}" for x in st.slip_rms),
                     ", ".join(f"{o:.2f}" for o in st.orders), f"{st.order:.2f}", st.verdict))
        sec.comparisons.append(Comparison.of({
            "quantity": f"contact refinement ({st.parameter.split(' [')[0]}, {st.held})",
            "scenario": sc.name, "model": model.name, "engines": ["reference", facts.name],
            "max_error": min(st.errors), "tolerance": None, "passed": None,
            "order": st.order, "values": list(st.values), "errors": list(st.errors),
            "slip_rms": list(st.slip_rms), "verdict": st.verdict, "reason": st.verdict_reason,
            "localized_to": f"order {st.order:.2f}: {st.verdict}",
            "note": "reported, not judged: a declared model difference (soft contact)"}))
    sec.table(("refined", "held", "values", f"error at {STUDY_TIME:g} s [rad, m]",
               "slip RMS [m/s]", "local orders", "fitted order", "verdict"), rows,
              note="Error: max over the eight coordinates at the grid time "
                   f"{STUDY_TIME:g} s (inside the reference's meaningful horizon and before any "
                   "wheel unloads). Local orders: log(e_i/e_i+1)/log(v_i/v_i+1); fitted order: "
                   "the slope of log error against log value. Every other setting at the "
                   "defaults above.")
    if soft.conclusion is not None:
        sec.text(soft.conclusion(studies, s))
    sec.figure(f"{prefix}_contact_refinement{tag}.png", "refinement",
               curves=[{"label": f"{st.parameter.split(' [')[0]} ({st.held}): order "
                                 f"{st.order:.2f}", "values": list(st.values),
                        "errors": list(st.errors)} for st in studies],
               at_time=STUDY_TIME, title=f"{who} against ideal rolling, {sc.name}")
    return sec


# -- the thesis's claims on a soft-contact engine --------------------------------------------

def on_disc(label: str) -> str:
    """The prefix of a claim's evidence judged on the engine's thesis-disc run."""
    return (f"on thesis-disc ({label} has no thesis fork-axis contact; the claim judged on its "
            "run of the same scenario with the disc contact): ")


@dataclass
class DiscClaims:
    """The stability claims judged on an engine's and the reference's thesis-disc runs."""

    claims: list[dict]       # judge_claims entries for the engine, evidence prefixed on_disc
    section: Section


def claims_on_disc(spec: str, names: tuple[str, ...]) -> DiscClaims:
    """The stability scenarios among ``names`` on the engine ``spec`` (defaults) and on the
    reference, both on thesis-disc, and the thesis's claims that need them judged on each
    (`judge_claims`). A stage."""
    from engines.facts import engine_facts
    from engines.runs import run_scenario

    from ..judgments.claims import judge_claims
    facts = engine_facts(spec)
    who, name = facts.label, facts.name
    model = load_model(MODEL)
    stab = [n for n in names if n.startswith("stability-")]
    runs = {}
    built = {name: load_engine(spec, model), "reference": load_engine("reference", model)}
    for n in stab:
        for label, engine in built.items():
            runs[(label, n)] = run_scenario(label, engine, model, SCENARIOS[n], ("forward",))
    judged = [c for c in judge_claims(runs, ["reference", name], model, stab)
              if c["claim_id"].startswith("stability-")]
    sec = Section(f"{who} on thesis-disc: the thesis's stability claims")
    sec.text(f"{who} cannot run the thesis's fork-axis contact, so the stability claims are "
             "judged on its runs of the same scenarios with the disc contact (`thesis-disc`, "
             "the engine's defaults), beside the reference's runs on `thesis-disc` (DOP853, the "
             "scenario's Baumgarte constraint handling) for comparison. Where the steer whips a "
             "wheel off the ground the runs leave the reference (see the contact study): the "
             f"verdicts say what {who}'s bicycle does, not how closely it follows the reference.")
    by = {(c["claim_id"], c["engine"]): c for c in judged}
    ids = list(dict.fromkeys(c["claim_id"] for c in judged))
    sec.table(("claim", "reference thesis-disc", f"{name} thesis-disc"),
              [(next(c["claim"] for c in judged if c["claim_id"] == i),
                f"{by[(i, 'reference')]['verdict']}: {by[(i, 'reference')]['evidence']}",
                f"{by[(i, name)]['verdict']}: {by[(i, name)]['evidence']}") for i in ids])
    mine = [dict(c, evidence=on_disc(who) + c["evidence"]) for c in judged if c["engine"] == name]
    return DiscClaims(mine, sec)


def merge_claims(claims: list[dict], disc: DiscClaims, engine: str) -> list[dict]:
    """``claims`` with ``engine``'s entries replaced by their thesis-disc judgments where
    made."""
    new = {c["claim_id"]: c for c in disc.claims}
    return [new.get(c["claim_id"], c) if c["engine"] == engine else c for c in claims]


class SoftContactStage(Stage):
    """The study of every engine declaring a soft contact: on thesis-disc with its claims there
    (full runs), or on each disc-contact ``--model``."""

    name, section = "soft-contact", "contact"

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        out = []
        for f in plan.engines(lambda f: f.soft_contact is not None):
            if not plan.opts.models:
                out.append(Task(("study", f.spec, MODEL), contact_study, (f.spec, plan.quick),
                                1.5 if plan.quick else 3.0, f"{f.label} contact study", f.spec))
                stab = tuple(n for n in plan.opts.scenarios if n.startswith("stability-"))
                if stab and not plan.quick:   # ~2 s of runs: the full report only
                    out.append(Task(("claims", f.spec, MODEL), claims_on_disc, (f.spec, stab),
                                    0.4 * len(stab),
                                    f"{f.label}: the stability claims on thesis-disc", f.spec))
            for m in plan.opts.models:
                if m.contact == "disc":
                    out.append(Task(("study", f.spec, m.spec), contact_study,
                                    (f.spec, plan.quick, m.spec), 1.5 if plan.quick else 3.0,
                                    f"{m.name}: {f.label} contact study", f.spec))
        return out

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        for key in results:
            kind, spec, _ = key
            who = plan.facts[spec].label
            title = f"{who} contact study" if kind == "study" else f"{who} claims on thesis-disc"
            v, failed = self.value(results, key, title)
            out.sections.append(failed or (v if kind == "study" else v.section))
        return out

    def revise_claims(self, plan: Plan, results: dict, claims: list[dict]) -> list[dict]:
        for (kind, spec, _), r in results.items():
            if kind == "claims" and r.error is None:
                claims = merge_claims(claims, r.value, plan.facts[spec].name)
        return claims
