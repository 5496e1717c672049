"""MuJoCo's share of the soft-contact study (`engines.facts.SoftContact`): which of its settings
the study refines, how its contact settings read, and what its refinement series mean.

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

from ..facts import Refinement, SoftContact

__all__ = ["SOFT_CONTACT", "conclusion", "settings_rows"]

# (solref time constant, timestep) pairs; each series spans 8x (the refinement study's span)
TC_WITH_STEP = (1e-3, 5e-4, 2.5e-4, 1.25e-4)            # timestep = tc / 2
QUICK_TC_WITH_STEP = (2e-3, 1e-3, 5e-4, 2.5e-4)
FIXED_TC = 2e-3                                         # s: the timestep series' time constant
STEPS_AT_FIXED_TC = (1e-3, 5e-4, 2.5e-4, 1.25e-4)       # all <= FIXED_TC / 2
FIXED_STEP = 1.25e-4                                    # s: the time-constant series' step
TC_AT_FIXED_STEP = (2e-3, 1e-3, 5e-4, 2.5e-4)           # all >= 2 FIXED_STEP


def settings_rows(s: dict) -> list[tuple[str, str]]:
    """A run's ``settings`` as the study's table of the contact settings."""
    return [(f"MuJoCo version", str(s["mujoco_version"])),
            ("geometry", s["wheels"]),
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


def conclusion(studies, s: dict) -> str:
    """What the refinement series say about MuJoCo's contact (``studies``: the study's
    `RefinementStudy` results in the order of `SOFT_CONTACT.refinements`)."""
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


def _tc_half_step(tc: float, s: dict) -> dict:
    return {"timestep": tc / 2, "solref": (tc, s["solref"][1])}


def _step_at_fixed_tc(h: float, s: dict) -> dict:
    return {"timestep": h, "solref": (FIXED_TC, s["solref"][1])}


def _tc_at_fixed_step(tc: float, s: dict) -> dict:
    return {"timestep": FIXED_STEP, "solref": (tc, s["solref"][1])}


SOFT_CONTACT = SoftContact(
    refinements=(
        Refinement("solref time constant [s]", "timestep = time constant / 2", TC_WITH_STEP,
                   _tc_half_step, quick_values=QUICK_TC_WITH_STEP),
        Refinement("timestep [s]", f"time constant {FIXED_TC:g} s", STEPS_AT_FIXED_TC,
                   _step_at_fixed_tc),
        Refinement("solref time constant [s]", f"timestep {FIXED_STEP:g} s", TC_AT_FIXED_STEP,
                   _tc_at_fixed_step)),
    settings_rows=settings_rows, conclusion=conclusion,
    about="MuJoCo's rolling cylinder approximates the rolling disc; the thesis's fork-axis front "
          "contact has no MuJoCo counterpart, so MuJoCo does not run the thesis-contact "
          "scenarios (a declared model difference)")
