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
read from them on first use. The thesis samples every scenario on t = 0:0.01:2*pi (629
samples); here t_k = 0.01 k exactly. Engines run the same `Scenario` objects (this module
depends on nothing above the model).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

from .model import DEP, Model
from .solvers import (DEFAULT_FALL_LIMIT, THESIS_BAUMGARTE, ConsistentState, IndependentMotion,
                      InverseDynamics, Trajectory, consistent_state, inverse_dynamics,
                      inverse_kinematics, simulate)

THESIS_GRID = (0.0, 0.01, 629)   # start, step, samples: 0:0.01:2*pi

# What the harness can compare on a scenario (the keys of `Scenario.compared`).
QUANTITIES = {
    "mass_matrix": "M at the scenario's states, every engine that provides M",
    "torques": "inverse-dynamics rider torques Mdir, Mped, Mvue along the motion",
    "multipliers": "the five constraint multipliers along the motion",
    "trajectory": "all eight coordinates against time, up to the meaningful horizon",
    "constraint_residual": "max |C| (the five constraints, evaluated by the reference) along the run",
}
INVERSE_QUANTITIES = ("mass_matrix", "torques", "multipliers")
FORWARD_QUANTITIES = ("mass_matrix", "trajectory", "constraint_residual")


@dataclass(frozen=True)
class ExpectedDifference:
    """A difference between two engines that is expected, and why. Strict: if the compared
    quantity stops differing, the harness reports that as unexpected too."""

    quantity: str        # e.g. "convergence order"
    engines: str         # e.g. "exudyn-tree (disc contact) vs reference (thesis contact)"
    expected: str        # the verdict expected, e.g. "model difference"
    reason: str


@dataclass(frozen=True)
class TorqueSamples:
    """Rider torques given by samples (from a scenario file's CSV): times ``t`` (s, strictly
    increasing, covering the run), ``T`` rows (Mdir, Mped, Mvue) in N m, and how to
    interpolate between them: "cubic" (not-a-knot spline), "linear" or "previous" (hold)."""

    t: tuple[float, ...]
    T: tuple[tuple[float, float, float], ...]
    interpolation: str = "cubic"
    source: str = ""

    def function(self):
        """t -> (3,) torques (or (N, 3) for an array of times)."""
        t, T = np.asarray(self.t), np.asarray(self.T)
        if self.interpolation == "cubic":
            spline = CubicSpline(t, T, axis=0, bc_type="not-a-knot")
            return lambda s: spline(s)
        if self.interpolation == "linear":
            return lambda s: np.stack([np.interp(s, t, T[:, j]) for j in range(3)], axis=-1)
        if self.interpolation == "previous":
            def hold(s):
                i = np.clip(np.searchsorted(t, s, side="right") - 1, 0, len(t) - 1)
                return T[i]
            return hold
        raise ValueError(f"unknown interpolation {self.interpolation!r}; use cubic, linear or "
                         "previous")


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
    torques: tuple[float, float, float] | str | TorqueSamples = (0.0, 0.0, 0.0)  # or "zigzag"
    #                                          (spline of its ID; TORQUE_FUNCTIONS), or samples
    constraints: str = "baumgarte"
    baumgarte: tuple[float, float] = THESIS_BAUMGARTE
    thesis_claim: str = ""
    tags: tuple[str, ...] = field(default_factory=tuple)
    compared: tuple[str, ...] = ()             # keys of QUANTITIES; default by kind
    expected_differences: tuple[ExpectedDifference, ...] = ()
    fall_limit: float = DEFAULT_FALL_LIMIT     # rad: a forward run stops when |theta| reaches it

    def __post_init__(self):
        if not self.compared:
            object.__setattr__(self, "compared",
                               INVERSE_QUANTITIES if self.kind == "inverse" else FORWARD_QUANTITIES)
        unknown = [c for c in self.compared if c not in QUANTITIES]
        if unknown:
            raise ValueError(f"scenario {self.name!r}: unknown compared quantity {unknown[0]!r}; "
                             f"choose from {', '.join(QUANTITIES)}")

    @property
    def duration(self) -> float:
        start, step, n = self.grid
        return step * (n - 1)

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


# The named independent motions of inverse scenarios (scenario files name them) and the named
# torque functions of forward ones (the inverse-dynamics torques of that built-in scenario).
MOTIONS: dict[str, IndependentMotion] = {
    "check": IndependentMotion(_check_motion, "theta = 0, psi = 5 t, gamma = 0"),
    "zigzag": IndependentMotion(_zigzag_motion, "theta = -sin t / 3, psi = 5 t, gamma = sin t / 2"),
}
TORQUE_FUNCTIONS: tuple[str, ...] = ("check", "zigzag")


@functools.cache
def builtin_scenarios() -> dict[str, Scenario]:
    """The built-in scenarios, read once from their files in ``reference_model/scenario_data/``
    (`reference_model.scenario_files.load_builtin_scenarios`), by name."""
    from .scenario_files import load_builtin_scenarios   # it imports this module: not at the top
    return load_builtin_scenarios()


def __getattr__(name: str):
    # ``SCENARIOS`` (the registry) is read from the files on first use (PEP 562), so this module
    # and the file loader, which needs this module's classes, import each other without a cycle
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
