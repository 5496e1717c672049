"""Drake's share of the soft-contact study (`engines.facts.SoftContact`): which of its settings
the study refines, how its contact settings read, and what its refinement series mean.

Measured (Drake 1.51.1, thesis-disc, stability-psid10, error at 0.3 s, wheel half-width 1e-6 m):

* With TAMSI and a point stiffness of 1e8 N/m the error is first order in the time step
  (4.3e-4, 2.1e-4, 1.1e-4 at 5e-4, 2.5e-4, 1.25e-4 s) and so is the slip: its RMS is about
  2.0 x the step (m/s per s). The stiction tolerance (1e-5 to 1e-2 m/s) moves the error by
  under 10 % (7.8e-4 to 8.5e-4 at 1e-3 s): the friction impulse of a step already holds the
  contact point within the regularized band, and what remains is the step's own slip (the
  rolling point's acceleration over one step, which a solve at the end of the step does not
  see).
* SAP behaves the same way (order 1.01: 2.0e-3, 1.0e-3, 5.0e-4, 2.5e-4 from 2e-3 to 2.5e-4 s)
  at about 1.3 x TAMSI's error and 2-3 x its cost per step; SAP ignores both the stiction
  tolerance and a point stiffness above its near-rigid limit (1e7 and 1e8 N/m give the same
  run), so its penetration is set by the step (2.2e-4 m at 1e-3 s).
* With TAMSI at 1e7 N/m the error stops shrinking near 2.7e-4 (the rear wheel sinks 5e-5 m,
  which shortens its rolling radius); 1e8 N/m (5e-6 m) removes that floor.
* The cylinder's width matters most, as for MuJoCo: at 5e-4 s (SAP) the error is 6.8e-3 at a
  half-width of 1e-3 m, 1.1e-3 at 1e-4 m, 5.2e-4 at 1e-5 and 1e-6 m: a leaned cylinder rests on
  its cap's rim, beside the disc's contact point.
* Lagged and similar give TAMSI's error (4.3e-4, 4.2e-4 at 5e-4 s). Hydroelastic contact stays
  far from rolling (0.43 at 0.3 s with the wheels meshed at 0.1 m, 0.34 at 0.01 m). Not refined
  here.
"""

from __future__ import annotations

from ..facts import Refinement, SoftContact

__all__ = ["SOFT_CONTACT", "conclusion", "settings_rows"]

STEPS = (1e-3, 5e-4, 2.5e-4, 1.25e-4)          # s: each series spans 8x
QUICK_STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4)
#: SAP's steps: one octave coarser than the default solver's (SAP's step costs ~2x TAMSI's;
#: the series keeps the study's run time within a few seconds)
SAP_STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4)
STICTION = (1e-2, 1e-3, 1e-4, 1e-5)            # m/s
STICTION_STEP = 1e-3                           # s: the stiction series' step


def settings_rows(s: dict) -> list[tuple[str, str]]:
    """A run's ``settings`` as the study's table of the contact settings."""
    model = s["contact_model"]
    rows = [("Drake version", str(s["drake_version"])),
            ("geometry", s["wheels"]),
            ("contact model, discrete approximation", f"{model}, {s['approximation']}"),
            ("Coulomb friction (static = dynamic)", f"{s['friction']:g}"),
            ("stiction tolerance", f"{s['stiction_tolerance']:g} m/s")]
    if model == "point":
        rows.append(("point contact stiffness, Hunt-Crossley dissipation",
                     f"{s['point_stiffness']:g} N/m, {s['dissipation']:g} s/m"))
    else:
        rows.append(("hydroelastic modulus (compliant wheels, rigid ground)",
                     f"{s['hydroelastic_modulus']:g} Pa"))
    return rows + [("time step", f"{s['time_step']:g} s"),
                   ("rear wheel height", s["rear_height_joint"]),
                   ("loads", s["loads"])]


def conclusion(studies, s: dict) -> str:
    """What the refinement series say about Drake's contact (``studies``: the study's
    `RefinementStudy` results in the order of `SOFT_CONTACT.refinements`)."""
    main = studies[0]
    text = (f"**Conclusion.** Refining the time step ({main.held}), Drake {main.verdict} "
            f"({main.verdict_reason}); its slip RMS is {main.slip_rms[-1] / main.values[-1]:.2f}"
            " x the step (m/s per s): each step's friction impulse leaves the slip the rolling "
            "point's acceleration builds up over one step.")
    for st in studies[1:]:
        what = st.parameter.split(" [")[0]
        text += (f" The {what} ({st.held}): {st.verdict} (order {st.order:.2f}; errors "
                 f"{min(st.errors):.1e} to {max(st.errors):.1e}).")
    text += (f" Defaults chosen: {s['approximation']} with {s['contact_model']} contact, time "
             f"step {s['time_step']:g} s, point stiffness {s['point_stiffness']:g} N/m, stiction "
             f"tolerance {s['stiction_tolerance']:g} m/s, wheel half-width "
             f"{s['wheel_half_width']:g} m: the closest to ideal rolling at about the cost of "
             "the other engines' runs.")
    return text


def _step(h: float, s: dict) -> dict:
    return {"time_step": h}


def _stiction(v: float, s: dict) -> dict:
    return {"time_step": STICTION_STEP, "stiction_tolerance": v}


def _sap_step(h: float, s: dict) -> dict:
    return {"time_step": h, "approximation": "sap"}


SOFT_CONTACT = SoftContact(
    refinements=(
        Refinement("time step [s]", "the default solver and contact", STEPS, _step,
                   quick_values=QUICK_STEPS),
        Refinement("stiction tolerance [m/s]", f"time step {STICTION_STEP:g} s", STICTION,
                   _stiction),
        Refinement("time step [s]", "SAP", SAP_STEPS, _sap_step)),
    settings_rows=settings_rows, conclusion=conclusion,
    about="Drake's thin cylinders on a half-space approximate the rolling disc; the thesis's "
          "fork-axis front contact has no counterpart in Drake's contact, so Drake does not run "
          "the thesis-contact scenarios (a declared model difference)")
