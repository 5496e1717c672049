"""How to run a scenario on the reference model: the inverse dynamics along its motion, its
consistent initial state, its rider torques, the forward run. Engines run the same `Scenario`
objects (this module depends on nothing above the model)."""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from ..model import DEP, Model
from ..solvers import (ConsistentState, InverseDynamics, Trajectory, consistent_state,
                       inverse_dynamics, inverse_kinematics, simulate)
from .definition import Scenario, TorqueSamples
from .registry import get_scenario

__all__ = ["initial_state", "run_forward", "run_inverse", "torque_input"]


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
