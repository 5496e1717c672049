"""Term-by-term comparison of two engines at a set of states, localised to the entry.

When two engines disagree, the first question is *which term*: M, inverse dynamics (M ddq -
Qv - Qgrav), gravity, the generalised forces, D, dD dq or the constrained accelerations; then
*which entry* (row and column named by coordinate and constraint) and at which state.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from engines.base import Engine
from reference_model import CONSTRAINT_NAMES, COORDINATES, TORQUE_NAMES

from .tolerances import Tolerance

QUANTITIES = ("mass_matrix", "inverse_dynamics", "gravity", "generalized_forces",
              "constraint_jacobian", "constraint_bias", "forward_acceleration")
SYMBOL = {"mass_matrix": "M", "inverse_dynamics": "M ddq - Qv - Qgrav", "gravity": "Qgrav",
          "generalized_forces": "Qv + Qgrav + Qaero + S T", "constraint_jacobian": "D",
          "constraint_bias": "dD dq", "forward_acceleration": "ddq"}


@dataclass(frozen=True)
class States:
    """A set of states at which engines are compared (all arrays have N rows)."""

    q: np.ndarray       # (N, 8)
    dq: np.ndarray      # (N, 8)
    ddq: np.ndarray     # (N, 8), for inverse dynamics
    T: np.ndarray       # (N, 3), rider torques

    def __len__(self) -> int:
        return self.q.shape[0]


def random_states(n: int, seed: int = 0) -> States:
    """Deterministic states covering large lean, steer near +-pi/2, fast spins and rates."""
    rng = np.random.default_rng(seed)
    lo = np.array([-10, -10, -np.pi, -1.2, -np.pi, -0.5, -1.55, -np.pi])
    q = rng.uniform(lo, -lo, (n, 8))
    dq = rng.uniform(-20, 20, (n, 8))
    return States(q, dq, rng.uniform(-10, 10, (n, 8)), rng.uniform(-10, 10, (n, 3)))


@dataclass(frozen=True)
class TermComparison:
    """One quantity compared between two engines over a set of states."""

    quantity: str
    engines: tuple[str, str]
    max_error: float          # normalised (see the tolerance's scale)
    max_abs_error: float
    tolerance: float
    passed: bool
    worst_state: int
    worst_entry: str          # e.g. "M[theta, gamma]"
    n_states: int

    def describe(self) -> str:
        verdict = "ok" if self.passed else "DIFFERS"
        return (f"{self.quantity} ({SYMBOL[self.quantity]}), {self.engines[0]} vs {self.engines[1]}: "
                f"{verdict}, max error {self.max_error:.2e} (tolerance {self.tolerance:.0e}), worst "
                f"at {self.worst_entry} of state {self.worst_state} (|diff| {self.max_abs_error:.2e})")


TERM = {"mass_matrix": "M", "inverse_dynamics": "tau", "gravity": "Qgrav",
        "generalized_forces": "Qv", "constraint_jacobian": "D", "constraint_bias": "dD dq",
        "forward_acceleration": "ddq"}   # the name an entry of each quantity is printed with


def entry_name(term: str, index: tuple[int, ...]) -> str:
    """'M[theta, gamma]', 'Qv[psi]', 'S[gamma, Mdir]', 'D[vD_x, beta]', 'dD dq[rD_z]'."""
    if term == "M":
        return f"M[{COORDINATES[index[0]]}, {COORDINATES[index[1]]}]"
    if term == "S":
        return f"S[{COORDINATES[index[0]]}, {TORQUE_NAMES[index[1]]}]"
    if term == "D":
        return f"D[{CONSTRAINT_NAMES[index[0]]}, {COORDINATES[index[1]]}]"
    if term == "dD dq":
        return f"dD dq[{CONSTRAINT_NAMES[index[0]]}]"
    return f"{term}[{COORDINATES[index[0]]}]"


def _entry_name(quantity: str, index: tuple[int, ...]) -> str:
    return entry_name(TERM[quantity], index)


def _evaluate(engine: Engine, quantity: str, s: States) -> np.ndarray:
    if quantity == "mass_matrix":
        return engine.mass_matrix(s.q)
    if quantity == "inverse_dynamics":
        return engine.inverse_dynamics(s.q, s.dq, s.ddq)
    if quantity == "gravity":
        return engine.gravity(s.q)
    if quantity == "generalized_forces":
        return engine.generalized_forces(s.q, s.dq, s.T)
    if quantity == "constraint_jacobian":
        return engine.constraint_jacobian(s.q)
    if quantity == "constraint_bias":
        return engine.constraint_bias(s.q, s.dq)
    if quantity == "forward_acceleration":
        return engine.forward_acceleration(s.q, s.dq, s.T)
    raise ValueError(f"unknown quantity {quantity!r}; choose from {QUANTITIES}")


def _terms(engine: Engine, quantity: str, s: States, k: int) -> list[np.ndarray] | None:
    """The parts a 'largest_term' scale is taken over, from the first engine's model."""
    m = engine.model
    q, dq = s.q[k], s.dq[k]
    if quantity == "inverse_dynamics":
        return [m.mass_matrix(q) @ s.ddq[k], m.Qv(q, dq), m.Qgrav(q)]
    if quantity == "generalized_forces":
        return [m.Qv(q, dq), m.Qgrav(q), m.Qaero(q, dq), m.S(q) @ s.T[k]]
    return None


def compare_term(quantity: str, a: Engine, b: Engine, states: States,
                 tolerance: Tolerance) -> TermComparison:
    """Compare one quantity of engines a (the reference side) and b at every state, judged by
    ``tolerance`` (the run's entry for ``quantity``). ValueError for no states: nothing would
    be compared, and a pass would be no finding."""
    if len(states) == 0:
        raise ValueError(f"no states to compare {quantity} at: give at least one")
    tol = tolerance
    A = np.asarray(_evaluate(a, quantity, states), dtype=float)
    B = np.asarray(_evaluate(b, quantity, states), dtype=float)
    worst = (-1.0, 0, (0,), 0.0)
    for k in range(len(states)):
        diff = np.abs(A[k] - B[k])
        err = float(diff.max()) / tol.normalizer(A[k], _terms(a, quantity, states, k))
        if not np.isfinite(err):
            err = np.inf
        if err > worst[0]:
            idx = np.unravel_index(int(np.argmax(diff)), diff.shape)
            worst = (err, k, tuple(int(i) for i in idx), float(diff.max()))
    err, k, idx, absdiff = worst
    return TermComparison(quantity, (a.name, b.name), err, absdiff, tol.tolerance,
                          bool(err <= tol.tolerance), k, _entry_name(quantity, idx), len(states))


def compare_terms(a: Engine, b: Engine, states: States, tolerances: Mapping[str, Tolerance],
                  quantities=None) -> list[TermComparison]:
    """Every quantity both engines provide (or the given subset), in a fixed order, each
    judged by its entry in ``tolerances``."""
    tols = tolerances
    qs = [q for q in (quantities or QUANTITIES) if a.supports(q) and b.supports(q)]
    return [compare_term(q, a, b, states, tols[q]) for q in qs]
