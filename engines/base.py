"""The engine interface: one small set of methods, each optional and declared.

Every engine is built from a `reference_model.Model` (so from the same parameter file, never
from copied numbers) and declares in ``capabilities`` which of the methods below it provides;
the harness compares only what two engines both provide. Asking for anything else raises
`CapabilityError`, naming the engine and the capability.

Sign conventions are the thesis's (see `reference_model.model`):

* ``mass_matrix(q)``                      M (8, 8)
* ``inverse_dynamics(q, dq, ddq)``        unconstrained M ddq - Qv - Qgrav (8,)
* ``gravity(q)``                          Qgrav, the generalised gravity *force* (8,)
* ``generalized_forces(q, dq, torques)``  Qv + Qgrav + Qaero + S T (8,)
* ``constraint_jacobian(q)``              D (5, 8), rows [rD_z, vC_x, vC_y, vD_x, vD_y]
* ``constraint_bias(q, dq)``              dD dq (5,)
* ``forward_acceleration(q, dq, torques)`` exact constrained ddq (8,)
* ``simulate(scenario, **options)``       a `reference_model.solvers.Trajectory`
"""

from __future__ import annotations

from reference_model import Model

CAPABILITIES = (
    "mass_matrix", "inverse_dynamics", "gravity", "generalized_forces", "constraint_jacobian",
    "constraint_bias", "forward_acceleration", "simulate",
)


class CapabilityError(NotImplementedError):
    """An engine was asked for something it does not provide."""


class EngineError(RuntimeError):
    """An engine could not be built or run (missing package, unsupported model...)."""


class EngineUsageError(EngineError, ValueError):
    """An engine option the user gave is invalid (unknown build, a time step that does not
    divide the output grid...): a usage error, exit status 2 in the CLI. Still an
    `EngineError`, so code that catches those keeps working."""


class Engine:
    """Base class: subclasses set ``name`` and ``capabilities`` and implement those methods."""

    name: str = "engine"
    capabilities: frozenset[str] = frozenset()

    def __init__(self, model: Model):
        self.model = model

    def __repr__(self) -> str:
        return f"{type(self).__name__}(model={self.model.name!r}, contact={self.model.contact!r})"

    def supports(self, capability: str) -> bool:
        return capability in self.capabilities

    def _missing(self, capability: str):
        have = ", ".join(c for c in CAPABILITIES if c in self.capabilities) or "nothing"
        raise CapabilityError(f"engine {self.name!r} cannot compute {capability}; it provides: {have}")

    def mass_matrix(self, q):
        self._missing("mass_matrix")

    def inverse_dynamics(self, q, dq, ddq):
        self._missing("inverse_dynamics")

    def gravity(self, q):
        self._missing("gravity")

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        self._missing("generalized_forces")

    def constraint_jacobian(self, q):
        self._missing("constraint_jacobian")

    def constraint_bias(self, q, dq):
        self._missing("constraint_bias")

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        self._missing("forward_acceleration")

    def simulate(self, scenario, **options):
        self._missing("simulate")
