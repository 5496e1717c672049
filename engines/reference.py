"""The reference model (the thesis's equations, generated C) as an engine."""

from __future__ import annotations

from reference_model.scenarios import Scenario, run_forward

from .base import CAPABILITIES, Engine


class ReferenceEngine(Engine):
    """Every capability, straight from `reference_model.Model`."""

    name = "reference"
    capabilities = frozenset(CAPABILITIES)

    def mass_matrix(self, q):
        return self.model.mass_matrix(q)

    def inverse_dynamics(self, q, dq, ddq):
        return self.model.inverse_dynamics(q, dq, ddq)

    def gravity(self, q):
        return self.model.Qgrav(q)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self.model.generalized_forces(q, dq, torques)

    def constraint_jacobian(self, q):
        return self.model.constraint_jacobian(q)

    def constraint_bias(self, q, dq):
        return self.model.constraint_bias(q, dq)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self.model.forward_acceleration(q, dq, torques)

    def simulate(self, scenario: Scenario, **options):
        return run_forward(self.model, scenario, **options)
