"""A second soft-contact engine for the tests: MuJoCo's adapter under another name, label,
colour and facts, with a five times softer contact (solref time constant 1e-3 s against the
built-in's 2e-4 s; the step at half of it, 5e-4 s) and its own refinement series. The harness
must give it the same study, a row of its own in the ranking and its own claims, and must not
mix its numbers with the built-in's.

Loaded as a plugin by the file spec `SPEC` (the harness knows it by its class name).

Why it is a fair second engine: MuJoCo drives each friction row toward J qacc = -b J qdot with
b = 2 / (dmax tc) and leaves out the rolling point's dJ/dt qdot, so its slip settles near that
term's size over b, proportional to tc (engines/mujoco/contact_study.py, measured there), and
the error follows. Five times the time constant therefore means about five times the slip and
the error: a different engine whose place in the ranking is known before it is run.
"""

from __future__ import annotations

from pathlib import Path

from engines.facts import Costs, Refinement, RunSetup, SoftContact
from engines.mujoco.contact_study import settings_rows
from engines.mujoco.engine import MujocoEngine

SPEC = f"{Path(__file__).resolve()}:SoftTwin"
NAME = "SoftTwin"           # what the harness calls a file-spec engine: its class name
TC = 1e-3                   # s: its contact's time constant (the built-in's: 2e-4 s)
STEP = TC / 2               # s
TC_SERIES = (4e-3, 2e-3, 1e-3, 5e-4)      # 8x (the span a verdict needs), step tc / 2 (divides 0.01 s)


def _tc_half_step(tc: float, s: dict) -> dict:
    return {"timestep": tc / 2, "solref": (tc, s["solref"][1])}


class SoftTwin(MujocoEngine):
    """MuJoCo's contact, five times softer (module docstring)."""

    name = NAME
    label = "Soft twin"
    colour = "tab:olive"
    run_setups = (RunSetup(kinds=("forward",), settings=(
        f"the test's soft twin: MuJoCo's contact at solref ({TC:g} s, 1), timestep {STEP:g} s")),)
    costs = Costs(run_per_second=0.1, short_run=0.5, terms=1.0, faults=1.0)
    soft_contact = SoftContact(
        refinements=(Refinement("solref time constant [s]", "timestep = time constant / 2",
                                TC_SERIES, _tc_half_step, quick_values=TC_SERIES),),
        settings_rows=settings_rows,
        about="the built-in soft contact, five times softer: a second engine for the tests")

    def __init__(self, model, timestep: float = STEP, solref=(TC, 1.0), **options):
        super().__init__(model, timestep=timestep, solref=solref, **options)
