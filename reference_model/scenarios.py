"""The thesis's scenarios as named, immutable data, and how to run each on the reference model.

| name               | kind    | what (thesis chapter)                                                   |
|--------------------|---------|-------------------------------------------------------------------------|
| check              | inverse | theta = gamma = 0, psi = 5t: straight rolling at 1.6 m/s (4.3, 5.3)      |
| zigzag             | inverse | theta = -sin(t)/3, psi = 5t, gamma = sin(t)/2 (4.3, 5.3)                  |
| replay             | forward | zigzag's torques fed back from its initial state, Baumgarte (6.2.2.1)    |
| stability-psidN    | forward | q0 = [0,0,0,pi/16,0,0,pi/16,0], T = [0,1,0], psi_dot(0) = N (6.2.2.2)    |

The thesis samples every scenario on t = 0:0.01:2*pi (629 samples); here t_k = 0.01 k exactly.
Engines run the same `Scenario` objects (this module depends on nothing above the model).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

from .model import Model
from .solvers import (THESIS_BAUMGARTE, ConsistentState, IndependentMotion, InverseDynamics,
                      Trajectory, consistent_state, inverse_dynamics, inverse_kinematics, simulate)

THESIS_GRID = (0.0, 0.01, 629)   # start, step, samples: 0:0.01:2*pi


@dataclass(frozen=True)
class Scenario:
    """One named scenario: its kind, model, grid, and either a prescribed independent motion
    (inverse) or an initial state and rider torques (forward)."""

    name: str
    description: str
    kind: str                                  # "inverse" | "forward"
    model: str = "thesis"                      # the named model the thesis used
    grid: tuple[float, float, int] = THESIS_GRID
    motion: IndependentMotion | None = None    # inverse: theta, psi, gamma of t
    q0: tuple[float, ...] | None = None        # forward: initial coordinates (projected)
    dq_ind0: tuple[float, float, float] | None = None   # forward: dtheta, dpsi, dgamma at t0
    torques: tuple[float, float, float] | str = (0.0, 0.0, 0.0)  # or "zigzag" (spline of its ID)
    constraints: str = "baumgarte"
    baumgarte: tuple[float, float] = THESIS_BAUMGARTE
    thesis_claim: str = ""
    tags: tuple[str, ...] = field(default_factory=tuple)

    @property
    def t(self) -> np.ndarray:
        start, step, n = self.grid
        return start + step * np.arange(n)


def _check_motion(t):
    z = np.zeros_like(t)
    q = np.stack([z, 5.0 * t, z], axis=-1)
    dq = np.stack([z, 5.0 + z, z], axis=-1)
    return q, dq, np.zeros_like(q)


def _zigzag_motion(t):
    s, c = np.sin(t), np.cos(t)
    q = np.stack([-s / 3, 5.0 * t, s / 2], axis=-1)
    dq = np.stack([-c / 3, 5.0 + 0 * t, c / 2], axis=-1)
    ddq = np.stack([s / 3, 0 * t, -s / 2], axis=-1)
    return q, dq, ddq


def _stability(psid: float) -> Scenario:
    return Scenario(
        name=f"stability-psid{psid:g}",
        description=(f"stability study: leaned and steered by pi/16, pedal torque 1 N m, "
                     f"psi_dot(0) = {psid:g} rad/s (thesis Fig. 6-{ {0: 4, 1: 5, 5: 6, 10: 7}[psid] })"),
        kind="forward", q0=(0, 0, 0, np.pi / 16, 0, 0, np.pi / 16, 0), dq_ind0=(0.0, psid, 0.0),
        torques=(0.0, 1.0, 0.0),
        thesis_claim={0: "falls quickly", 1: "falls, sooner than at psi_dot(0) = 0",
                      5: "travels some metre before falling",
                      10: "places its frame in a vertical plane and stabilises"}[psid],
        tags=("stability",),
    )


SCENARIOS: dict[str, Scenario] = {s.name: s for s in (
    Scenario("check", "straight rolling at R*5 = 1.6 m/s: only the pedal torque, constant, "
             "balancing the drag", "inverse",
             motion=IndependentMotion(_check_motion, "theta = 0, psi = 5 t, gamma = 0"),
             thesis_claim="only the pedal torque is non-zero, and constant"),
    Scenario("zigzag", "prescribed lean and steer oscillation: theta = -sin(t)/3, psi = 5t, "
             "gamma = sin(t)/2", "inverse",
             motion=IndependentMotion(_zigzag_motion, "theta = -sin t / 3, psi = 5 t, gamma = sin t / 2")),
    Scenario("replay", "zigzag's rider torques (cubic spline) fed into the forward dynamics from "
             "its initial state, Baumgarte a1 = a2 = 10 (thesis 6.2.2.1)", "forward",
             q0=(0,) * 8, dq_ind0=(-1 / 3, 5.0, 0.5), torques="zigzag",
             thesis_claim="motion identical to the zigzag inverse kinematics; constraint error "
                          "below 2e-3"),
    *(_stability(v) for v in (0, 1, 5, 10)),
)}


class UnknownScenarioError(KeyError):
    def __str__(self):
        return self.args[0]


def get_scenario(name: str) -> Scenario:
    try:
        return SCENARIOS[name]
    except KeyError:
        raise UnknownScenarioError(f"unknown scenario {name!r}; choose one of: "
                                   f"{', '.join(SCENARIOS)}") from None


# -- running on the reference model ---------------------------------------------------

def run_inverse(model: Model, sc: Scenario, *, reproject: bool = False) -> InverseDynamics:
    """Inverse kinematics (q_dep(0) = 0) then the 13x13 inverse dynamics on the grid."""
    if sc.kind != "inverse":
        raise ValueError(f"scenario {sc.name!r} is a forward scenario; use simulate")
    motion = inverse_kinematics(model, sc.motion, sc.t, reproject=reproject)
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
    zigzag inverse-dynamics torques computed on this model."""
    if isinstance(sc.torques, str):
        source = get_scenario(sc.torques)
        ident = run_inverse(model, source)
        spline = CubicSpline(ident.motion.t, ident.T, axis=0, bc_type="not-a-knot")
        return lambda t: spline(t)
    return sc.torques


def run_forward(model: Model, sc: Scenario, *, constraints: str | None = None, **kwargs) -> Trajectory:
    """Forward run of a scenario from its projected initial state."""
    init = initial_state(model, sc)
    traj = simulate(model, init.q, init.dq, sc.t, torque_input(model, sc),
                    constraints=constraints or sc.constraints, baumgarte=sc.baumgarte, **kwargs)
    traj.settings["initial_correction"] = init.describe()
    traj.settings["beta_correction"] = init.beta_correction
    return traj
