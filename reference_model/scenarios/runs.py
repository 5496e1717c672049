"""How to run a scenario on the reference model: the inverse dynamics along its motion, its
consistent initial state, its rider torques, the forward run. Engines run the same `Scenario`
objects (this module depends on nothing above the model)."""

from __future__ import annotations

import bisect
import math

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
        return SplineAtTime(CubicSpline(ident.motion.t, ident.T, axis=0, bc_type="not-a-knot"))
    return sc.torques


class SplineAtTime:
    """A scipy `CubicSpline` of the torques, evaluated at one time in plain floats: bit for
    bit what ``spline(t)`` gives (its interval rule, x_i <= t < x_i+1 with the last interval
    closed and extrapolation from the end intervals, and its sum c3 + c2 s + c1 s^2 + c0 s^3
    in that order), in a third of the time of scipy's call (8-13 against 21-31 us measured
    under load), which the integrator makes at every right-hand side (a fifth of Pinocchio's
    replay).
    Arrays of times, and a time that is not finite, go to the spline itself."""

    __slots__ = ("spline", "_x", "_c", "_last")

    def __init__(self, spline: CubicSpline):
        self.spline = spline
        self._x = spline.x.tolist()
        c = spline.c                                  # (4, intervals, torques), c[0]: s^3
        self._c = [tuple(tuple(col) for col in c[:, i, :].T.tolist()) for i in range(c.shape[1])]
        self._last = len(self._x) - 2                 # the last interval

    def __call__(self, t):
        if not isinstance(t, (float, int, np.floating)) or not math.isfinite(t):
            return self.spline(t)
        t = float(t)
        i = min(max(bisect.bisect_right(self._x, t) - 1, 0), self._last)
        s = t - self._x[i]
        s2 = s * s
        s3 = s2 * s
        return np.array([0.0 + c3 + c2 * s + c1 * s2 + c0 * s3 for c0, c1, c2, c3 in self._c[i]])


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
