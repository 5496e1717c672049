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
  (`judgments.contact.refinement_study`) and each setting's run time per simulated second,
  and the engine's own reading of them;
* the engines side by side (`ranking_section`, summary.json's ``soft_contact_ranking``): each
  default run's row on a horizon shared by every engine, the last sample before ideal rolling
  needs the ground to pull (`judgments.contact_ranking`), ranked by the error there;
* in full runs, the thesis's stability claims on every engine's thesis-disc runs beside the
  reference's (`soft_contact_claims`).

The run times are measured (wall time over simulated time): the one part of the report that
varies from run to run.

The run's ``diagnostics`` carry per-wheel ``slip_speed_rear/front``, ``penetration_rear/front``
and optionally ``normal_force_rear/front`` (docs/engines.md, "A soft contact's diagnostics").
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from engines import load_engine
from reference_model import load_model
from reference_model.scenarios import SCENARIOS, torque_input

from ..judgments.contact import contact_fidelity, lift_off_time, refinement_study
from ..judgments.contact_ranking import ContactRow, contact_row, rank, shared_horizon
from ..judgments.convergence import HORIZON_THRESHOLD, meaningful_horizon, perturbed_scenario, \
    reference_run
from ..judgments.rows import Comparison
from .cases import slug
from .results import Section, num
from .soft_contact_claims import (DiscClaims, claims_on_disc, claims_section, merge_claims,
                                  reference_claims_on_disc)
from .stage import Assembled, Plan, Stage

__all__ = ["MODEL", "SCENARIO", "STUDY_TIME", "ContactStudy", "SoftContactStage",
           "contact_study", "ideal_normal_forces", "ranking_section", "ranking_summary",
           "window"]

SCENARIO = "stability-psid10"
MODEL = "thesis-disc"
# The run lengths, per engine: the default run over WINDOW and every refinement run over
# STUDY_TIME, i.e. 0.5 + 12 x 0.2 = 2.9 simulated s for the built-in engine's three series of
# four (1.3 s quick: its one quick series). Measured on the built-in at 0.2 s against 0.3 s:
# the same verdicts and orders (1.03 / 0.17 / 0.85 against 1.04 / 0.17 / 0.86), a third less
# integration; 0.5 s is past the first lift-off (0.44 s) and the ranking's horizon (0.43 s).
STUDY_TIME = 0.2        # s: psid10 before the steer runs away and before any wheel unloads
WINDOW = 0.5            # s: the default run, past the first lift-off (about 0.45 s)
QUICK_WINDOW = 0.5      # s: the same in a --quick run


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


@dataclass(frozen=True)
class ContactStudy:
    """One engine's study on one model: its section, and its default run's row of the
    side-by-side ranking (None when the engine cannot represent the model)."""

    section: Section
    row: ContactRow | None


def _timed(simulate, **options):
    """(run, wall seconds) of ``simulate(**options)``."""
    t0 = time.perf_counter()
    run = simulate(**options)
    return run, time.perf_counter() - t0


def _per_second(seconds: float, run) -> float:
    return seconds / run.t_end if run.t_end > 0 else float("nan")


def contact_study(spec: str, quick: bool, model_spec: str = MODEL) -> ContactStudy:
    """The study (module docstring) of the engine ``spec`` as a report section and its row of
    the ranking, on thesis-disc or on a user's disc-contact bicycle ``model_spec``. A stage."""
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
        return ContactStudy(sec, None)
    run, seconds = _timed(lambda **o: eng.simulate(sc, t_end=window_s, **o))
    s = run.settings
    sec.text(f"{who} with its own wheel-ground contact, on `{model.name}`"
             + (f" ({soft.about})" if soft.about else "")
             + f", and `{SCENARIO}`, against the reference (DOP853, rtol 1e-11, projection: the "
             "rolling constraints hold exactly). The engine's default contact settings (the "
             "settings of its runs in every section), and their cost: this run took "
             f"{_per_second(seconds, run):.2g} s of wall time per simulated second "
             f"({seconds:.2g} s for {run.t_end:.2f} s; measured, it varies with the machine's "
             "load):")
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
    ideal_pull = float(ref.t[pull[0]]) if pull.size else None
    row = contact_row(facts.name, who, ref, run,
                      shared_horizon(ref.t, ideal_pull, hor.t, window_s), seconds,
                      model=model.name, scenario=sc.name, lift_off_s=lift,
                      settings=_settings_line(facts))
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
        "lift_off_s": lift, "ideal_pull_s": ideal_pull,
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
        return ContactStudy(sec, row)
    ref_study = reference_run(model, sc, t_end=STUDY_TIME)
    simulate = lambda **o: eng.simulate(sc, t_end=STUDY_TIME, **o)
    studies, costs = [], []
    for r in series:
        timed = [(v, *_timed(simulate, **r.options(v, s)))
                 for v in (r.quick_values if quick else r.values)]
        studies.append(refinement_study(ref_study, [(v, run_v) for v, run_v, _ in timed],
                                        r.parameter, STUDY_TIME, r.held))
        # in the study's order, coarsest first
        by_value = {v: _per_second(sec_v, run_v) for v, run_v, sec_v in timed}
        costs.append([by_value[v] for v in studies[-1].values])
    sec.heading(f"Refinement: the error at {STUDY_TIME:g} s against the contact's settings")
    rows = []
    for st, cost in zip(studies, costs):
        rows.append((st.parameter.split(" [")[0], st.held,
                     ", ".join(f"{v:g}" for v in st.values),
                     ", ".join(f"{e:.2e}" for e in st.errors),
                     ", ".join(f"{x:.2e}" for x in st.slip_rms),
                     ", ".join(f"{o:.2f}" for o in st.orders), f"{st.order:.2f}", st.verdict,
                     ", ".join(f"{c:.2g}" for c in cost)))
        sec.comparisons.append(Comparison.of({
            "quantity": f"contact refinement ({st.parameter.split(' [')[0]}, {st.held})",
            "scenario": sc.name, "model": model.name, "engines": ["reference", facts.name],
            "max_error": min(st.errors), "tolerance": None, "passed": None,
            "order": st.order, "values": list(st.values), "errors": list(st.errors),
            "slip_rms": list(st.slip_rms), "verdict": st.verdict, "reason": st.verdict_reason,
            "run_time_per_simulated_second": cost,
            "localized_to": f"order {st.order:.2f}: {st.verdict}",
            "note": "reported, not judged: a declared model difference (soft contact)"}))
    sec.table(("refined", "held", "values", f"error at {STUDY_TIME:g} s [rad, m]",
               "slip RMS [m/s]", "local orders", "fitted order", "verdict",
               "run time per simulated second [s]"), rows,
              note="Error: max over the eight coordinates at the grid time "
                   f"{STUDY_TIME:g} s (inside the reference's meaningful horizon and before any "
                   "wheel unloads). Local orders: log(e_i/e_i+1)/log(v_i/v_i+1); fitted order: "
                   "the slope of log error against log value. Every other setting at the "
                   "defaults above. Run time: wall time of each run over its simulated "
                   f"{STUDY_TIME:g} s (measured: the cost of each setting).")
    if soft.conclusion is not None:
        sec.text(soft.conclusion(studies, s))
    sec.figure(f"{prefix}_contact_refinement{tag}.png", "refinement",
               curves=[{"label": f"{st.parameter.split(' [')[0]} ({st.held}): order "
                                 f"{st.order:.2f}", "values": list(st.values),
                        "errors": list(st.errors)} for st in studies],
               at_time=STUDY_TIME, title=f"{who} against ideal rolling, {sc.name}")
    return ContactStudy(sec, row)


def _settings_line(facts) -> str:
    """The engine's defaults as its first run setup states them (one line)."""
    return next((u.settings for u in facts.run_setups if u.settings), "")


def ranking_section(rows: list[ContactRow]) -> Section:
    """The soft-contact engines side by side on one model and manoeuvre (`contact_ranking`):
    one row per engine, closest to ideal rolling first."""
    ranked = rank(rows)
    first = ranked[0].row
    sec = Section("Soft-contact engines side by side: how close to ideal rolling"
                  + ("" if first.model == MODEL else f" on {first.model}"))
    sec.text(f"Every engine with a soft wheel-ground contact ({len(ranked)}: "
             f"{', '.join(r.row.label for r in ranked)}) on the same manoeuvre, `{first.scenario}` "
             f"on `{first.model}`, at its default settings, against the ideal-rolling reference "
             f"up to the same time, {first.horizon:.2f} s: the last output sample before ideal "
             "rolling needs the ground to pull a wheel down (which no unilateral contact can), "
             "within the reference's meaningful horizon. Ranked by the error at that time, "
             "then by slip RMS; a run that ends before it comes last. Reported, not judged: "
             "each soft contact is a declared model difference.")
    sec.table(("rank", "engine", f"error at {first.horizon:.2f} s [rad, m]",
               "max error up to it", "slip RMS [m/s]", "slip max [m/s]",
               "penetration max [m]", "penetration RMS [m]", "first lift-off [s]",
               "run time per simulated second [s]"),
              [(str(r.rank), r.row.label,
                num(r.row.error_at_horizon, ".2e") if r.row.reached
                else f"ends at {r.row.simulated_s:.2f} s",
                num(r.row.error_max, ".2e"), num(r.row.slip_rms, ".2e"),
                num(r.row.slip_max, ".2e"), num(r.row.penetration_max, ".2e"),
                num(r.row.penetration_rms, ".2e"), num(r.row.lift_off_s, ".2f"),
                f"{r.row.run_time_per_simulated_second:.2g}") for r in ranked],
              note="Errors: max over the eight coordinates; slip and penetration over both "
                   "wheels' samples on the 0.01 s grid up to the shared time. Run time: wall "
                   "time of the engine's default run of the study over its simulated time "
                   "(measured on this machine, under its load; the only number here that "
                   "varies from run to run). Each engine's settings and its refinement are "
                   "in its contact study below.")
    return sec


def ranking_summary(rows: list[ContactRow]) -> dict:
    """summary.json's entry for one model's ranking (``soft_contact_ranking``)."""
    ranked = rank(rows)
    first = ranked[0].row
    return {"model": first.model, "scenario": first.scenario, "horizon_s": first.horizon,
            "ranked_by": "error_at_horizon, then slip_rms; runs ending before the horizon last",
            "rows": [{"rank": r.rank, **r.row.as_dict()} for r in ranked]}


def _study_seconds(soft, quick: bool) -> float:
    """Simulated seconds of one study: the default run and every refinement run."""
    n = sum(len(r.quick_values if quick else r.values) for r in soft.refinements
            if not quick or r.quick_values is not None)
    return window(quick) + n * STUDY_TIME


class SoftContactStage(Stage):
    """The study of every engine declaring a soft contact, on thesis-disc (full runs: with
    the stability claims there) or on each disc-contact ``--model``; the engines side by side
    on each model."""

    name, section = "soft-contact", "contact"

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        out = []
        soft = plan.engines(lambda f: f.soft_contact is not None)
        models = [m.spec for m in plan.opts.models if m.contact == "disc"]
        stab = tuple(n for n in plan.opts.scenarios if n.startswith("stability-"))
        claims = bool(soft and stab and not plan.quick and not plan.opts.models)
        if claims:   # the reference's thesis-disc runs, once for every engine
            out.append(Task(("claims-reference", "reference", MODEL), reference_claims_on_disc,
                            (stab,), 0.3 * len(stab), "reference: the stability runs on thesis-disc"))
        for f in soft:
            cost = f.costs.run_per_second * _study_seconds(f.soft_contact, plan.quick)
            for m in models or ([] if plan.opts.models else [MODEL]):
                on = "" if m == MODEL else f"{m}: "
                out.append(Task(("study", f.spec, m), contact_study,
                                (f.spec, plan.quick) + (() if m == MODEL else (m,)), cost,
                                f"{on}{f.label} contact study", f.spec))
            if claims:   # runs end at the fall, within about 2 s
                out.append(Task(("claims", f.spec, MODEL), claims_on_disc, (f.spec, stab),
                                f.costs.run_per_second * 2.0 * len(stab),
                                f"{f.label}: the stability claims on thesis-disc", f.spec))
        return out

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        studies, failed, rows = [], [], {}
        for key in results:
            kind, spec, model = key
            if kind != "study":
                continue
            v, bad = self.value(results, key, f"{plan.facts[spec].label} contact study")
            if bad is not None:
                failed.append(bad)
                continue
            studies.append(v.section)
            if v.row is not None:
                rows.setdefault(model, []).append(v.row)
        out.sections += [ranking_section(r) for r in rows.values()] + studies + failed
        out.summary["soft_contact_ranking"] = [ranking_summary(r) for r in rows.values()]
        disc, bad = self._claims(plan, results)
        if disc:
            ref = results.get(("claims-reference", "reference", MODEL))
            out.sections.append(claims_section(
                ref.value if ref is not None and ref.error is None else None, disc))
        if ("claims-reference", "reference", MODEL) in results:
            _, ref_failed = self.value(results, ("claims-reference", "reference", MODEL),
                                       "reference: the stability runs on thesis-disc")
            bad += [ref_failed] if ref_failed is not None else []
        out.sections += bad
        return out

    def _claims(self, plan: Plan, results: dict) -> tuple[list[DiscClaims], list[Section]]:
        disc, bad = [], []
        for key in results:
            if key[0] == "claims":
                v, failed = self.value(results, key,
                                       f"{plan.facts[key[1]].label} claims on thesis-disc")
                (disc.append(v) if failed is None else bad.append(failed))
        return disc, bad

    def revise_claims(self, plan: Plan, results: dict, claims: list[dict]) -> list[dict]:
        for (kind, _, _), r in results.items():
            if kind == "claims" and r.error is None:
                claims = merge_claims(claims, r.value)
        return claims
