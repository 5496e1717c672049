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

The scenarios are files (``reference_model/scenario_data/*.toml``, the format of
`reference_model.scenario_files`, which a user's ``--scenario-file`` shares); ``SCENARIOS`` is
read from them on first use; what a scenario is (`Scenario` and its parts) is defined in
`reference_model.scenario_types` and re-exported here. The thesis samples every scenario on
t = 0:0.01:2*pi (629 samples); here t_k = 0.01 k exactly. Engines run the same `Scenario`
objects (this module depends on nothing above the model).
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.interpolate import CubicSpline

from .model import DEP, Model
from .scenario_types import (FORWARD_QUANTITIES, INVERSE_QUANTITIES, MOTIONS, QUANTITIES,
                             THESIS_GRID, TORQUE_FUNCTIONS, ExpectedDifference, Scenario,
                             TorqueSamples)
from .solvers import (ConsistentState, InverseDynamics, Trajectory, consistent_state,
                      inverse_dynamics, inverse_kinematics, simulate)

__all__ = [  # the registry and the runs; the scenario types re-exported from scenario_types
    "SCENARIOS", "UnknownScenarioError", "builtin_scenarios", "get_scenario", "initial_state",
    "run_forward", "run_inverse", "torque_input",
    "FORWARD_QUANTITIES", "INVERSE_QUANTITIES", "MOTIONS", "QUANTITIES", "THESIS_GRID",
    "TORQUE_FUNCTIONS", "ExpectedDifference", "Scenario", "TorqueSamples"]


@functools.cache
def builtin_scenarios() -> dict[str, Scenario]:
    """The built-in scenarios, read once from their files in ``reference_model/scenario_data/``
    (`reference_model.scenario_files.load_builtin_scenarios`), by name."""
    from .scenario_files import load_builtin_scenarios   # on first use: the files are read then
    return load_builtin_scenarios()


def __getattr__(name: str):
    # ``SCENARIOS`` (the registry) is read from the files on first use (PEP 562)
    if name == "SCENARIOS":
        return builtin_scenarios()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class UnknownScenarioError(KeyError):
    def __str__(self):
        return self.args[0]


def get_scenario(name: str) -> Scenario:
    scenarios = builtin_scenarios()
    try:
        return scenarios[name]
    except KeyError:
        raise UnknownScenarioError(f"unknown scenario {name!r}; choose one of: "
                                   f"{', '.join(scenarios)}") from None


# -- running on the reference model ---------------------------------------------------

def run_inverse(model: Model, sc: Scenario, *, reproject: bool = False) -> InverseDynamics:
    """Inverse kinematics then the 13x13 inverse dynamics on the grid. The dependent
    coordinates start at 0 (the thesis: its upright frame pitch is 0) with beta(0) re-solved
    from [rD]_z = 0 when the geometry needs it (recorded in ``motion.info['initial_correction']``)."""
    if sc.kind != "inverse":
        raise ValueError(f"scenario {sc.name!r} is a forward scenario; use simulate")
    # q_dep(0) = 0 is the thesis's start (its upright frame pitch is 0); inverse_kinematics
    # re-solves beta(0) from [rD]_z = 0 for any other geometry and reports the correction
    motion = inverse_kinematics(model, sc.motion, sc.t, np.zeros(len(DEP)), reproject=reproject)
    return inverse_dynamics(model, motion)


def initial_state(model: Model, sc: Scenario) -> ConsistentState:
    """The scenario's initial state projected onto the constraints (the same for every engine)."""
    if sc.kind != "forward":
        raise ValueError(f"scenario {sc.name!r} is an inverse scenario; it has no initial state")
    q0 = np.asarray(sc.q0, dtype=np.float64)
    dq0 = np.zeros(8)
    dq0[[3, 4, 6]] = sc.dq_ind0
    return consistent_state(model, q0, dq0)


def torque_input(model: Model, sc: Scenario):
    """Constant torques, or for 'zigzag' the not-a-knot cubic spline (MATLAB's spline) of the
    zigzag inverse-dynamics torques computed on this model, or the interpolated samples."""
    if isinstance(sc.torques, TorqueSamples):
        return sc.torques.function()
    if isinstance(sc.torques, str):
        source = get_scenario(sc.torques)
        ident = run_inverse(model, source)
        spline = CubicSpline(ident.motion.t, ident.T, axis=0, bc_type="not-a-knot")
        return lambda t: spline(t)
    return sc.torques


def run_forward(model: Model, sc: Scenario, *, constraints: str | None = None,
                torques_from: Model | None = None, **kwargs) -> Trajectory:
    """Forward run of a scenario from its projected initial state. ``torques_from``: the model
    whose inverse dynamics make a torque history named by another scenario (default
    ``model``; an engine without inverse dynamics passes the reference model)."""
    init = initial_state(model, sc)
    traj = simulate(model, init.q, init.dq, sc.t, torque_input(torques_from or model, sc),
                    constraints=constraints or sc.constraints, baumgarte=sc.baumgarte,
                    **{"fall_limit": sc.fall_limit, **kwargs})
    traj.settings["initial_correction"] = init.describe()
    traj.settings["beta_correction"] = init.beta_correction
    return traj
