"""The reference model (the thesis's equations, generated C) as an engine."""

from __future__ import annotations

from reference_model.scenarios import Scenario, run_forward

from .base import CAPABILITIES, Engine
from .facts import Costs, RunSetup


class ReferenceEngine(Engine):
    """Every capability, straight from `reference_model.Model`."""

    name = "reference"
    capabilities = frozenset(CAPABILITIES)
    label = "reference"
    colour = "k"
    marker = "o"
    trajectory_tolerance = None   # everything else is compared against it
    trajectory_judged_by = "it is the reference"
    run_setups = (RunSetup(settings="inverse: inverse kinematics DOP853 rtol 1e-12 + 13x13 LU; "
                                    "forward: DOP853 rtol 1e-10, atol 1e-12, the scenario's "
                                    "constraint handling (Baumgarte a1 = a2 = 10)"),)
    costs = Costs(run_per_second=0.05, short_run=0.1, terms=0.0, faults=0.0)

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

    def eigenvalues(self, speeds):
        """The exact linearization's (`reference_model.linearize`: complex-step derivatives of
        the reduced equations), (n, 4)."""
        import numpy as np
        return self.model.eigenvalues(np.atleast_1d(speeds))     # it checks and converts them
