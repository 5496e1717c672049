"""DART's share of the soft-contact study (`engines.facts.SoftContact`): which of its settings
the study refines, how its contact settings read, and what its refinement series mean.

DART's contact is rigid (no stiffness or time constant to refine): each step solves a boxed LCP
for the impulses that stop the contact points' normal approach and, within the friction
pyramid, their sliding at the *end* of the step. The contact point moves on the wheel during
the step, so the rolling point slips by about its acceleration times the step: the error is
first order in the time step. Measured (dartpy 6.20.0, thesis-disc, stability-psid10 at 0.3 s,
ODE's detector, half-width 1e-6 m): 8.5e-4, 4.3e-4, 2.2e-4, 1.1e-4 at 1e-3 ... 1.25e-4 s.
The cylinder's half-width is the other knob: a leaned cylinder rests on its lower cap's rim,
beside the disc's contact point.
"""

from __future__ import annotations

from ..facts import Refinement, SoftContact
from .options import DEFAULTS

__all__ = ["SOFT_CONTACT", "conclusion", "settings_rows"]

STEPS = (1e-3, 5e-4, 2.5e-4, 1.25e-4)                 # s, each divides the 0.01 s grid
QUICK_STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4)
WIDTH_STEP = 2.5e-4                                   # s: the half-width series' step
HALF_WIDTHS = (8e-4, 4e-4, 2e-4, 1e-4)                # m


def settings_rows(s: dict) -> list[tuple[str, str]]:
    """A run's ``settings`` as the study's table of the contact settings."""
    return [("DART version", str(s["dart_version"])),
            ("geometry", s["wheels"]),
            ("collision detector", s["collision_detector"]),
            ("friction", s["friction_coefficients"]),
            ("contact solver", f"boxed LCP, {s['solver']}; split impulse "
                               f"{'on' if s['split_impulse'] else 'off'}"),
            ("time step, integrator", f"{s['timestep']:g} s, {s['integrator']}"),
            ("rear wheel height", s["rear_height_joint"]),
            ("loads", s["loads"])]


def conclusion(studies, s: dict) -> str:
    """What the refinement series say about DART's contact (``studies``: the study's
    `RefinementStudy` results in the order of `SOFT_CONTACT.refinements`)."""
    main = studies[0]
    text = (f"**Conclusion.** DART's rigid LCP contact has no stiffness to refine: its departure "
            f"from rolling is the time stepping's. With the time step, DART {main.verdict} "
            f"({main.verdict_reason}); its slip RMS is {main.slip_rms[-1] / main.values[-1]:.2f} x "
            f"the step (m/s per s), the contact point's acceleration times the step.")
    by_width = [st for st in studies[1:] if st.parameter.startswith("wheel half-width")]
    if by_width:
        st = by_width[0]
        text += (f" The cylinder's half-width at a fixed {st.held}: {st.verdict} (order "
                 f"{st.order:.2f}; errors {max(st.errors):.1e} to {min(st.errors):.1e}): a "
                 "leaned cylinder rests on its cap's rim, beside the disc's contact point.")
    text += (f" Defaults: time step {s['timestep']:g} s, half-width {s['wheel_half_width']:g} m, "
             f"the {s['collision_detector']} detector, {s['solver']} LCP, friction "
             f"{s['friction']:g}.")
    return text


def _step(h: float, s: dict) -> dict:
    return {"timestep": h}


def _width(w: float, s: dict) -> dict:
    return {"timestep": WIDTH_STEP, "wheel_half_width": w}


SOFT_CONTACT = SoftContact(
    refinements=(
        Refinement("time step [s]", f"half-width {DEFAULTS.wheel_half_width:g} m", STEPS, _step, quick_values=QUICK_STEPS),
        Refinement("wheel half-width [m]", f"time step {WIDTH_STEP:g} s", HALF_WIDTHS, _width)),
    settings_rows=settings_rows, conclusion=conclusion,
    about="DART's thin cylinders on a ground box, with its rigid, frictional, unilateral LCP "
          "contact, approximate the rolling disc; the thesis's fork-axis front contact has no "
          "counterpart in a collision detector, so DART does not run the thesis-contact "
          "scenarios (a declared model difference)")
