"""The MuJoCo contact study of `bicycle-xval run`: how far MuJoCo's soft wheel-ground contact is
from the reference's ideal rolling, and whether refining it gets closer.

MuJoCo has no rolling constraint: each wheel is a thin cylinder touching the plane through a
soft, frictional contact (a declared model difference). On `thesis-disc` (MuJoCo's cylinder
approximates the rolling disc; the thesis's fork-axis front contact has no counterpart) and
stability-psid10 (the stability study's fastest run), this stage reports:

* the contact settings as the engine uses them (geometry, cone, condim, solref, solimp, noslip
  iterations, timestep, integrator);
* one run at the engine's defaults: slip speed and penetration of each wheel over the run, the
  ground's normal forces, the trajectory error to the reference against time, up to
  `WINDOW`. The reference (DOP853, rtol 1e-11, projection) is checked reproducible to 1e-6
  over that window by its twin 1e-9 rad/s apart (`convergence.meaningful_horizon`). Where the
  ideal model needs the ground to *pull* a wheel down (a negative normal force, which the
  reference's bilateral constraint supplies and MuJoCo's unilateral contact cannot), MuJoCo's
  wheel lifts off: from there on the two models differ in kind, and the run is only shown;
* the refinement study at `STUDY_TIME` (inside both horizons): the error against the solref
  time constant with the timestep at half of it (MuJoCo honours time constants down to two
  steps), against the timestep at a fixed time constant, and against the time constant at a
  fixed timestep, each with its fitted order (`judgments.contact.refinement_study`).

Measured (MuJoCo 4.0.0, thesis-disc, stability-psid10 at 0.3 s): the slip RMS is 1.0 x the
solref time constant (m/s per s) whatever the solimp, impratio, cone, condim or noslip
iterations; the error shrinks at order ~1 with the time constant (timestep = tc / 2) and not
with the step alone. Why: MuJoCo drives each contact row's J qacc toward
aref = -b J qdot - k r, with b = 2 / (dmax tc) and k = 0 on the friction rows (checked: the
friction rows' efc_aref equals -b J qdot to all digits); the rolling point's own acceleration
term dJ/dt qdot is not in it, so the friction rows settle at a slip J qdot = dJ/dt qdot / b,
proportional to tc. MuJoCo honours tc down to 2 timesteps: the error is first order in the step
at the closest setting, tc = 2 h.
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
from .cases import slug
from .results import Section

SCENARIO = "stability-psid10"
MODEL = "thesis-disc"
STUDY_TIME = 0.3        # s: psid10 before the steer runs away and before any wheel unloads
WINDOW = 0.6            # s: the default run, past the first lift-off (about 0.45 s)
QUICK_WINDOW = 0.5


def window(quick: bool) -> float:
    """The contact study's window (s) in a quick or a full run."""
    return QUICK_WINDOW if quick else WINDOW
# (solref time constant, timestep) pairs; each series spans 8x (convergence.MIN_SPAN)
TC_WITH_STEP = (1e-3, 5e-4, 2.5e-4, 1.25e-4)            # timestep = tc / 2
QUICK_TC_WITH_STEP = (2e-3, 1e-3, 5e-4, 2.5e-4)
FIXED_TC = 2e-3                                         # s: the timestep series' time constant
STEPS_AT_FIXED_TC = (1e-3, 5e-4, 2.5e-4, 1.25e-4)       # all <= FIXED_TC / 2
FIXED_STEP = 1.25e-4                                    # s: the time-constant series' step
TC_AT_FIXED_STEP = (2e-3, 1e-3, 5e-4, 2.5e-4)           # all >= 2 FIXED_STEP


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


def _settings_rows(s: dict) -> list[tuple[str, str]]:
    return [("geometry", s["wheels"]),
            ("friction", f"{s['friction_coefficients']}; cone {s['cone']}, condim {s['condim']}"),
            ("solref (time constant s, damping ratio)", ", ".join(f"{x:g}" for x in s["solref"])),
            ("solimp (dmin, dmax, width m, midpoint, power)",
             ", ".join(f"{x:g}" for x in s["solimp"])),
            ("noslip iterations", str(s["noslip_iterations"])),
            ("timestep, integrator", f"{s['timestep']:g} s, {s['integrator']}"),
            ("constraint solver", f"{s['solver']}, {s['iterations']} iterations, tolerance "
                                  f"{s['tolerance']:g}"),
            ("rear wheel height", s["rear_height_joint"]),
            ("loads", s["loads"])]


def mujoco_contact(quick: bool, spec: str = MODEL) -> Section:
    """The contact study (module docstring) as a report section, on thesis-disc or on a
    user's disc-contact bicycle ``spec``."""
    from engines import UnsupportedModel
    on = "" if spec == MODEL else f" on {load_model(spec).name}"
    sec = Section(f"MuJoCo contact study{on}: soft contact against ideal rolling")
    window_s = window(quick)
    model, sc, ref, hor = _reference(window_s, spec)
    try:
        eng = load_engine("mujoco", model)
    except UnsupportedModel as exc:   # a declared limitation: said, not failed
        sec.text(f"Not run on this model: {exc}")
        return sec
    run = eng.simulate(sc, t_end=window_s)
    s = run.settings
    sec.text(f"MuJoCo {s['mujoco_version']} with its own wheel-ground contact, on `{model.name}` "
             f"(MuJoCo's rolling cylinder approximates the rolling disc; the thesis's fork-axis "
             "front contact has no MuJoCo counterpart, so MuJoCo does not run the thesis-contact "
             f"scenarios: declared model difference) and `{SCENARIO}`, against the reference "
             "(DOP853, rtol 1e-11, projection: the rolling constraints hold exactly). The engine's "
             "default contact settings, the ones this study found closest to ideal rolling at "
             "the cost of a 1e-4 s step:")
    sec.table(("setting", "value"), _settings_rows(s))

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
             + (f"MuJoCo's wheels carry load up to {loaded_end:.2f} s; a wheel lifts off at "
                f"{lift:.2f} s, where {pull_text}: MuJoCo's contact is unilateral, the "
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
    for label, f in (("while both wheels are loaded", fid_loaded),):
        sec.comparisons.append({
            "quantity": "contact fidelity (slip, penetration, trajectory)", "scenario": sc.name,
            "model": model.name, "engines": ["reference", "mujoco"], "max_error": f.error_max,
            "tolerance": None, "passed": None, "horizon": f.horizon,
            "slip_max": f.slip_max, "slip_rms": f.slip_rms,
            "penetration_max": f.penetration_max, "penetration_rms": f.penetration_rms,
            "lift_off_s": lift, "ideal_pull_s": float(ref.t[pull[0]]) if pull.size else None,
            "localized_to": f"slip max {f.slip_max:.1e} m/s ({f.slip_worst})",
            "note": f"{label}; reported, not judged: a declared model difference (soft contact)"})
    sec.table(("up to", "slip max [m/s]", "slip RMS [m/s]", "penetration max [m]",
               "penetration RMS [m]", "max error, 8 coordinates [rad, m]"), rows,
              note="Slip: speed of each wheel's contact point (the disc's lowest point) in the "
                   "ground plane, 0 for ideal rolling; penetration: depth of that point below "
                   "the ground (negative: above it; a leaned cylinder rests on its cap's rim). "
                   "Statistics over both wheels' samples on the 0.01 s grid.")
    d = run.diagnostics
    tag = "" if spec == MODEL else f"_{slug(model.name)}"
    sec.figure(f"mujoco_contact_run{tag}.png", "contact_run",
               t=run.t, error=fid_all.error, horizon=loaded_end,
               slip={"rear": d["slip_speed_rear"], "front": d["slip_speed_front"]},
               penetration={"rear": d["penetration_rear"], "front": d["penetration_front"]},
               normal={"rear": d.get("normal_force_rear"), "front": d.get("normal_force_front")},
               ideal_normal={"t": ref.t, "rear": rear, "front": front},
               title=f"{sc.name} on MuJoCo (defaults) against the reference {model.name}")

    # -- the refinement study ---------------------------------------------------------------
    ref_study = reference_run(model, sc, t_end=STUDY_TIME)
    simulate = lambda **o: eng.simulate(sc, t_end=STUDY_TIME, **o)
    series = [("solref time constant [s]", "timestep = time constant / 2",
               [(tc, simulate(timestep=tc / 2, solref=(tc, s["solref"][1])))
                for tc in (QUICK_TC_WITH_STEP if quick else TC_WITH_STEP)])]
    if not quick:
        series += [("timestep [s]", f"time constant {FIXED_TC:g} s",
                    [(h, simulate(timestep=h, solref=(FIXED_TC, s["solref"][1])))
                     for h in STEPS_AT_FIXED_TC]),
                   ("solref time constant [s]", f"timestep {FIXED_STEP:g} s",
                    [(tc, simulate(timestep=FIXED_STEP, solref=(tc, s["solref"][1])))
                     for tc in TC_AT_FIXED_STEP])]
    studies = [refinement_study(ref_study, runs, param, STUDY_TIME, held)
               for param, held, runs in series]
    sec.heading(f"Refinement: the error at {STUDY_TIME:g} s against the contact's stiffness and "
                "the timestep")
    rows = []
    for st in studies:
        rows.append((st.parameter.split(" [")[0], st.held,
                     ", ".join(f"{v:g}" for v in st.values),
                     ", ".join(f"{e:.2e}" for e in st.errors),
                     ", ".join(f"{x:.2e}" for x in st.slip_rms),
                     ", ".join(f"{o:.2f}" for o in st.orders), f"{st.order:.2f}", st.verdict))
        sec.comparisons.append({
            "quantity": f"contact refinement ({st.parameter.split(' [')[0]}, {st.held})",
            "scenario": sc.name, "model": model.name, "engines": ["reference", "mujoco"],
            "max_error": min(st.errors), "tolerance": None, "passed": None,
            "order": st.order, "values": list(st.values), "errors": list(st.errors),
            "slip_rms": list(st.slip_rms), "verdict": st.verdict, "reason": st.verdict_reason,
            "localized_to": f"order {st.order:.2f}: {st.verdict}",
            "note": "reported, not judged: a declared model difference (soft contact)"})
    sec.table(("refined", "held", "values [s]", f"error at {STUDY_TIME:g} s [rad, m]",
               "slip RMS [m/s]", "local orders", "fitted order", "verdict"), rows,
              note="Error: max over the eight coordinates at the grid time "
                   f"{STUDY_TIME:g} s (inside the reference's meaningful horizon and before any "
                   "wheel unloads). Local orders: log(e_i/e_i+1)/log(v_i/v_i+1); fitted order: "
                   "the slope of log error against log value. Every other setting at the "
                   "defaults above.")
    sec.text(_conclusion(studies, s))
    sec.figure(f"mujoco_contact_refinement{tag}.png", "refinement",
               curves=[{"label": f"{st.parameter.split(' [')[0]} ({st.held}): order "
                                 f"{st.order:.2f}", "values": list(st.values),
                        "errors": list(st.errors)} for st in studies],
               at_time=STUDY_TIME, title=f"MuJoCo against ideal rolling, {sc.name}")
    return sec


def _conclusion(studies, s) -> str:
    main = studies[0]
    text = (f"**Conclusion.** With the timestep at half the time constant, MuJoCo {main.verdict}"
            f" ({main.verdict_reason}); its slip RMS is {main.slip_rms[-1] / main.values[-1]:.2f}"
            f" x the time constant (m/s per s).")
    by_step = [st for st in studies if st.parameter.startswith("timestep")]
    if by_step:
        st = by_step[0]
        text += (f" The timestep alone, at a fixed {st.held}: {st.verdict} (order {st.order:.2f};"
                 f" errors {min(st.errors):.1e} to {max(st.errors):.1e}, where the integrator's "
                 f"own first-order error and the contact's add or cancel), and the slip stays "
                 f"{min(st.slip_rms):.2e} to {max(st.slip_rms):.2e} m/s: the step does not remove "
                 "the contact's departure from rolling.")
    by_tc = [st for st in studies[1:] if st.parameter.startswith("solref")]
    if by_tc:
        st = by_tc[0]
        text += (f" The time constant alone, at a fixed {st.held}: {st.verdict} (order "
                 f"{st.order:.2f}; local orders {', '.join(f'{o:.2f}' for o in st.orders)}), down "
                 "to the integrator's own error at that step.")
    text += (" MuJoCo honours time constants down to two steps, so the setting closest to ideal "
             "rolling at a given cost is time constant = 2 x timestep. Defaults chosen: timestep "
             f"{s['timestep']:g} s, solref ({s['solref'][0]:g}, {s['solref'][1]:g}), integrator "
             f"{s['integrator']}, cone {s['cone']}, condim {s['condim']}, noslip iterations "
             f"{s['noslip_iterations']}, solimp ({', '.join(f'{x:g}' for x in s['solimp'])}).")
    return text


# -- the thesis's claims on MuJoCo ---------------------------------------------------------------

ON_DISC = ("on thesis-disc (MuJoCo has no thesis fork-axis contact; the claim judged on its run "
           "of the same scenario with the disc contact): ")


@dataclass
class DiscClaims:
    """The stability claims judged on MuJoCo's and the reference's thesis-disc runs."""

    claims: list[dict]       # judge_claims entries for 'mujoco', evidence prefixed ON_DISC
    section: Section


def claims_on_disc(names: tuple[str, ...]) -> DiscClaims:
    """The stability scenarios among ``names`` on MuJoCo (defaults) and on the reference, both
    on thesis-disc, and the thesis's claims that need them judged on each (`judge_claims`)."""
    from engines.runs import run_scenario

    from ..judgments.claims import judge_claims
    model = load_model(MODEL)
    stab = [n for n in names if n.startswith("stability-")]
    runs = {}
    built = {label: load_engine(label, model) for label in ("mujoco", "reference")}
    for n in stab:
        for label, engine in built.items():
            runs[(label, n)] = run_scenario(label, engine, model, SCENARIOS[n], ("forward",))
    judged = [c for c in judge_claims(runs, ["reference", "mujoco"], model, stab)
              if c["claim_id"].startswith("stability-")]
    sec = Section("MuJoCo on thesis-disc: the thesis's stability claims")
    sec.text("MuJoCo cannot run the thesis's fork-axis contact, so the stability claims are judged "
             "on its runs of the same scenarios with the disc contact (`thesis-disc`, the engine's "
             "defaults), beside the reference's runs on `thesis-disc` (DOP853, the scenario's "
             "Baumgarte constraint handling) for comparison. The runs leave the reference "
             "within its first half second wherever the steer whips a wheel off the ground (see "
             "the contact study): the verdicts say what MuJoCo's bicycle does, not how closely it "
             "follows the reference.")
    by = {(c["claim_id"], c["engine"]): c for c in judged}
    ids = list(dict.fromkeys(c["claim_id"] for c in judged))
    sec.table(("claim", "reference thesis-disc", "mujoco thesis-disc"),
              [(next(c["claim"] for c in judged if c["claim_id"] == i),
                f"{by[(i, 'reference')]['verdict']}: {by[(i, 'reference')]['evidence']}",
                f"{by[(i, 'mujoco')]['verdict']}: {by[(i, 'mujoco')]['evidence']}") for i in ids])
    mine = [dict(c, evidence=ON_DISC + c["evidence"]) for c in judged if c["engine"] == "mujoco"]
    return DiscClaims(mine, sec)


def merge_claims(claims: list[dict], disc: DiscClaims) -> list[dict]:
    """``claims`` with MuJoCo's entries replaced by their thesis-disc judgments where made."""
    new = {c["claim_id"]: c for c in disc.claims}
    return [new.get(c["claim_id"], c) if c["engine"] == "mujoco" else c for c in claims]
