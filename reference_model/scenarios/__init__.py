"""The thesis's scenarios as named, immutable data, and how to run each on the reference model.

| name               | kind    | what (thesis chapter)                                                   |
|--------------------|---------|-------------------------------------------------------------------------|
| check              | inverse | theta = gamma = 0, psi = 5t: straight rolling at 1.6 m/s (4.3, 5.3)      |
| zigzag             | inverse | theta = -sin(t)/3, psi = 5t, gamma = sin(t)/2 (4.3, 5.3)                  |
| replay             | forward | zigzag's torques fed back from its initial state, Baumgarte (6.2.2.1)    |
| stability-psidN    | forward | q0 = [0,0,0,pi/16,0,0,pi/16,0], T = [0,1,0], psi_dot(0) = N (6.2.2.2)    |
| check-forward      | forward | check's constant pedal torque fed forward from upright rolling at 1.6 m/s |
| benchmark-vV       | forward | model benchmark: IFToMM uncontrolled bicycle, upright at V m/s, roll rate kick, 5 s |

Each scenario also names the quantities the harness compares on it (`compared`, from
`QUANTITIES`) and the differences between engines it expects, with their reasons
(`expected_differences`): an expected difference that stops differing is reported too.

The room, by job (each module imports only those above it): ``definition`` (what a scenario
is: `Scenario` and its parts), ``files`` (the scenario file format, which a user's
``--scenario-file`` shares; the built-ins are files in ``reference_model/scenario_data/``),
``registry`` (the built-in scenarios by name: ``SCENARIOS``, read from their files on first
use) and ``runs`` (how to run one on the reference model). This package re-exports the
registry, the runs and the definitions; ``reference_model.scenario_types`` and
``reference_model.scenario_files`` are the older names of ``definition`` and ``files``. The
thesis samples every scenario on t = 0:0.01:2*pi (629 samples); here t_k = 0.01 k exactly.
Engines run the same `Scenario` objects (this package depends on nothing above the model).
"""

from .definition import (FORWARD_QUANTITIES, INVERSE_QUANTITIES, MOTIONS, QUANTITIES,
                         THESIS_GRID, TORQUE_FUNCTIONS, ExpectedDifference, Scenario,
                         TorqueSamples)
from .registry import UnknownScenarioError, builtin_scenarios, get_scenario
from .runs import initial_state, run_forward, run_inverse, torque_input
# what the old flat module had imported, so every old import of reference_model.scenarios works
from ..model import DEP, Model  # noqa: F401,E402
from ..solvers import (ConsistentState, InverseDynamics, Trajectory,  # noqa: F401
                       consistent_state, inverse_dynamics, inverse_kinematics, simulate)

__all__ = [  # the registry and the runs; the scenario definitions
    "SCENARIOS", "UnknownScenarioError", "builtin_scenarios", "get_scenario", "initial_state",
    "run_forward", "run_inverse", "torque_input",
    "FORWARD_QUANTITIES", "INVERSE_QUANTITIES", "MOTIONS", "QUANTITIES", "THESIS_GRID",
    "TORQUE_FUNCTIONS", "ExpectedDifference", "Scenario", "TorqueSamples"]


def __getattr__(name: str):
    # ``SCENARIOS`` (the registry) is read from the files on first use (PEP 562)
    if name == "SCENARIOS":
        return builtin_scenarios()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
