"""The `symbrim` engine: SymBRiM's Whipple bicycle (knife-edge wheels, flat ground) in the
thesis's coordinates.

SymBRiM's model (`engines.symbrim.derivation`) is in Moore's coordinates, as the Kane engine's
own derivation is, and printed to the same five generated functions (`KaneDerivation`:
unconstrained M and F, the constraint rows, their Jacobian and bias) by the Kane engine's
printer and cache (`engines.symbrim.codegen`). Everything after that is the Kane engine's:
the project's Moore <-> thesis mapping (`reference_model.moore`, ``u = T dq``), the parameter
conversion (`engines.kane.moore_parameters`: the thesis's geometry and inertias as Moore's
d1..d3, l1..l4 and the products' signs), the per-state elimination of the dependent speeds and
the reference's solvers for runs. This class only swaps the equations: SymBRiM's instead of
the project's own Kane derivation, so where the two engines disagree, one of the two
derivations is wrong.

SymBRiM's knife edge touches the ground at the disc's lowest point: the thesis's rim-point
contact is refused (`CapabilityError`).
"""

from __future__ import annotations

import numpy as np

from reference_model import Model

from ..base import CapabilityError, Engine
from ..facts import Costs, RunSetup
from ..kane.engine import KaneEngine, moore_parameters
from . import codegen

__all__ = ["SymbrimEngine", "symbrim_parameters"]


def symbrim_parameters(params) -> np.ndarray:
    """The generated code's parameter vector: Moore's (`moore_parameters`), then the front
    tyre's crown radius (0: the knife edge, which does not read it)."""
    return np.r_[moore_parameters(params), 0.0]


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
    costs = Costs(run_per_second=0.3, short_run=0.8, terms=1.5, faults=2.0)

    @classmethod
    def prepare(cls) -> None:
        """Derive and generate the code if the cache is cold (~40-60 s), once, before workers
        fork."""
        codegen.load()

    def __init__(self, model: Model):
        if model.contact not in self.contacts:
            raise CapabilityError(
                f"engine 'symbrim' cannot use the front contact {model.contact!r}: SymBRiM's "
                "knife-edge wheel touches the ground at the disc's lowest point, not at the "
                "thesis's rim point along the fork's -z; use a disc-contact model (e.g. "
                "thesis-disc)")
        Engine.__init__(self, model)
        self.p = symbrim_parameters(model.params)
        self.code = codegen.load()
        self.params, self.contact = model.params, model.contact
