"""The `symbrim` engine: SymBRiM's Whipple bicycle (knife-edge wheels, flat ground) in the
thesis's coordinates.

SymBRiM's model (`engines.symbrim.derivation`) is in Moore's coordinates, as the Kane engine's
own derivation is, and printed to the same five generated functions (`KaneDerivation`:
unconstrained M and F, the constraint rows, their Jacobian and bias) by the Kane engine's
printer and cache (`engines.symbrim.codegen`). Everything after that is the Kane engine's:
the project's Moore <-> thesis mapping (`reference_model.moore`, ``u = T dq``), the per-state
elimination of the dependent speeds and
the reference's solvers for runs. Its parameters are Moore's from BicycleParameters' own
conversion of the model's Table 1 values (`engines.symbrim.parameters`; the project's own
conversion only for a bicycle with no Table 1 counterpart, ``parameter_route`` says which).
This class only swaps the equations: SymBRiM's instead of
the project's own Kane derivation, so where the two engines disagree, one of the two
derivations is wrong.

SymBRiM's knife edge touches the ground at the disc's lowest point: the thesis's rim-point
contact is refused (`CapabilityError`).

Option ``crown_radius`` (m, default 0): the front wheel is SymBRiM's `ToroidalWheel`, a tyre
whose crown is a circle of that radius (its contact point is the torus's lowest point), with
the major radius ``R_front - crown_radius`` so that the hub stands at R_front when upright, as
the reference's. With 0 it is the disc exactly (the same generated equations' toroidal
variant, checked against the reference); with > 0 it is another bicycle, a model difference
(the front contact moves sideways with lean), not an error of either: declared as the option
study ``CROWN_STUDY`` (its eigenvalues, by `engines.linear` from this engine's own toroidal
contact, and critical speeds against the crown radius, in the report).
"""

from __future__ import annotations

import math

import numpy as np

from reference_model import Model

from ..base import CapabilityError, Engine, EngineSpecError
from ..facts import Costs, OptionStudy, RunSetup
from ..kane.engine import KaneEngine
from ..kane.names import MOORE_PARAMETERS
from . import codegen
from .parameters import moore_parameters, parameter_route

__all__ = ["CROWN_STUDY", "SymbrimEngine", "symbrim_parameters"]

def _prepare_torus() -> None:
    """The toroidal variant's generated code (a second derivation: ~15-65 s cold, cached)."""
    codegen.load(front_crown=True)


#: the declared model difference of ``crown_radius`` > 0, and the values it is studied at
CROWN_STUDY = OptionStudy(
    option="crown_radius", quantity="front tyre crown radius", unit="m",
    values=(0.0, 0.005, 0.01, 0.02, 0.03), reference_value=0.0,
    difference="a toroidal front tyre (SymBRiM's ToroidalWheel, crown of this radius, major "
               "radius R_front - crown): its contact point moves sideways as the wheel leans, "
               "where the reference's knife-edge disc touches at the wheel plane's lowest point",
    why="0 is the reference's knife edge; 5-30 mm spans the cross-section radii of real tyres "
        "(half the width of a 10-60 mm tyre: track and road tyres about 10-15 mm, city and "
        "mountain-bike tyres 20-30 mm); 30 mm is under a tenth of the benchmark's R_front "
        "(0.35 m), where the torus stays a tyre",
    prepare=_prepare_torus)


def symbrim_parameters(params, crown_radius: float = 0.0) -> np.ndarray:
    """The generated code's parameter vector: Moore's (`engines.symbrim.parameters`: through
    BicycleParameters' own conversion where the model has Table 1 values), then the front
    tyre's crown radius (0: the knife edge, which does not read it). With a crown, Moore's
    rf is the torus's major radius, R_front - crown_radius (the hub's height unchanged)."""
    p = np.r_[moore_parameters(params), float(crown_radius)]
    p[MOORE_PARAMETERS.index("rf")] -= crown_radius
    return p


def _crown(value, R_front: float) -> float:
    try:
        c = float(value)
    except (TypeError, ValueError):
        c = math.nan
    if not (0.0 <= c < R_front):
        raise EngineSpecError(f"engine option crown_radius = {value!r}: give the front tyre's "
                              f"crown radius in metres, 0 <= crown_radius < R_front "
                              f"({R_front} m)")
    return c


class SymbrimEngine(KaneEngine):
    """SymBRiM's WhippleBicycleMoore with knife-edge wheels, generated numpy code, disc contact
    only; the Kane engine's mapping, elimination and solvers."""

    name = "symbrim"
    label = "SymBRiM"
    colour = "tab:pink"
    marker = "X"
    run_setups = (RunSetup(kinds=("forward",),
                           settings="SymBRiM's Whipple bicycle (WhippleBicycleMoore, KnifeEdgeWheel, "
                                    "NonHolonomicTire, FlatGround; sympy KanesMethod, generated "
                                    "code, dependent speeds eliminated per state) in the "
                                    "reference's solvers (same integrator and tolerances); disc "
                                    "front contact only; no inverse dynamics"),)
    # measured on the quiet 2-core host (2026-12-02, `bicycle-xval run`): the energy drift's
    # free roll 1.3 s on SymBRiM and 1.3 s on Kane, so Kane's rate (1.4) rather than the 0.2
    # it had, which started that stage last and left one worker idle at the end; the cold
    # derivation (35-50 s) is `prepare`'s, once per machine, and a cached load ~0.1 s
    costs = Costs(run_per_second=1.4, short_run=0.8, terms=1.5, faults=2.0)
    option_studies = (CROWN_STUDY,)

    @classmethod
    def prepare(cls) -> None:
        """Derive and generate the code if the cache is cold (~40-60 s), once, before workers
        fork."""
        codegen.load()

    def __init__(self, model: Model, crown_radius: float = 0.0):
        if model.contact not in self.contacts:
            raise CapabilityError(
                f"engine 'symbrim' cannot use the front contact {model.contact!r}: SymBRiM's "
                "knife-edge wheel touches the ground at the disc's lowest point, not at the "
                "thesis's rim point along the fork's -z; use a disc-contact model (e.g. "
                "thesis-disc)")
        Engine.__init__(self, model)
        self.crown_radius = _crown(crown_radius, model.params.R_front)
        self.p = symbrim_parameters(model.params, self.crown_radius)
        self.parameter_route = parameter_route(model.params)
        self.code = codegen.load(front_crown=self.crown_radius > 0)
        self.params, self.contact = model.params, model.contact
