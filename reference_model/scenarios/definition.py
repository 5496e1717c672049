"""What a scenario is: the `Scenario` record, the quantities a scenario can ask to compare, the
expected differences it declares, sampled rider torques, and the named motions and torque
functions that scenario files refer to.

The registry of built-in scenarios and how to run one on the reference are
`reference_model.scenarios.registry` and ``runs`` (the package re-exports these names); the
file format is `reference_model.scenarios.files`. They import this module, and it imports
none of them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..solvers import DEFAULT_FALL_LIMIT, THESIS_BAUMGARTE, IndependentMotion

__all__ = ["FORWARD_QUANTITIES", "INVERSE_QUANTITIES", "MOTIONS", "QUANTITIES", "THESIS_GRID",
           "TORQUE_FUNCTIONS", "ExpectedDifference", "Scenario", "TorqueSamples"]

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
    engines: str         # e.g. "an engine with the disc contact vs the reference with the thesis contact"
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
        """t -> (3,) torques (or (N, 3) for an array of times). Outside the samples (a run
        never asks there: a scenario file's samples cover it) "linear" and "previous" give the
        nearest end sample and "cubic" continues its end pieces."""
        t, T = np.asarray(self.t), np.asarray(self.T)
        if self.interpolation == "cubic":
            from scipy.interpolate import CubicSpline
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
