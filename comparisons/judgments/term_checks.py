"""The terms of the equations taken out of an engine, and each checked against its tolerance.

The thesis's equations ``M ddq + D^T lambda = Qv + Qgrav + Qaero + S T``, ``D ddq + dD dq = 0``:
`model_terms` gives the reference's terms, `engine_terms` an engine's through the Engine
interface alone. For `comparisons.judgments.diagnose`, `extract` also takes the copies of Qgrav
and Qv out of ``generalized_forces`` where an engine has gravity() and inverse_dynamics() too,
and the constrained solve of its own terms its forward accelerations are checked against
(`SolveValues`). Each
compared array is a `Block` (a term of one engine from one source, with its reference and the
per-state scale of its tolerance from ``tolerances.toml``); `check_block` judges it and names its
worst entries over the whole array.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from engines.base import Engine
from reference_model import COORDINATES, Model

from .terms import States, entry_name
from .tolerances import Tolerance

__all__ = [
    "COPY_SOURCE", "SOLVE_NEEDS", "SOURCE_LABEL", "TERMS", "TERM_TOLERANCE", "Block", "SolveValues",
    "TermCheck", "check_block", "check_terms", "engine_terms", "extract", "model_terms",
    "solve_values", "term_blocks",
]

TERMS = ("M", "Qv", "Qgrav", "Qaero", "S", "D", "dD dq")
#: term -> (the tolerances.toml entry it is judged by, the terms its extraction from an engine
#: involves: the round-off of a difference is relative to the largest of them)
TERM_TOLERANCE: dict[str, tuple[str, tuple[str, ...]]] = {
    "M": ("mass_matrix", ("M",)),
    "Qv": ("generalized_forces", ("Qv", "Qgrav")),
    "Qgrav": ("gravity", ("Qgrav",)),
    "Qaero": ("generalized_forces", ("Qaero", "Qv", "Qgrav")),
    "S": ("generalized_forces", ("S", "Qgrav")),
    "D": ("constraint_jacobian", ("D",)),
    "dD dq": ("constraint_bias", ("dD dq",)),
}


def model_terms(model: Model, states: States) -> dict[str, np.ndarray]:
    """Every term of the reference model at the states (batch C calls)."""
    q, dq = states.q, states.dq
    return {"M": model.mass_matrix(q), "Qv": model.Qv(q, dq), "Qgrav": model.Qgrav(q),
            "Qaero": model.Qaero(q, dq), "S": model.S(q), "D": model.constraint_jacobian(q),
            "dD dq": model.constraint_bias(q, dq)}


def extract(engine: Engine, states: States, extras: bool
             ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], "SolveValues | None"]:
    """(terms, copies, solve): the terms as `engine_terms` gives them; with ``extras``, the
    copies of Qgrav and Qv taken out of ``generalized_forces`` where the terms came from
    gravity() and inverse_dynamics(), of M out of inverse_dynamics (`COPY_SOURCE`), and the
    engine's forward solve against its own terms."""
    q, dq = states.q, states.dq
    n = len(states)
    zero3 = np.zeros((n, 3))
    out: dict[str, np.ndarray] = {}
    copies: dict[str, np.ndarray] = {}
    has = engine.supports
    if has("mass_matrix"):
        out["M"] = np.asarray(engine.mass_matrix(q), dtype=float)
    rest = np.asarray(engine.generalized_forces(q, np.zeros_like(dq), zero3), dtype=float) \
        if has("generalized_forces") else None
    if has("gravity"):
        out["Qgrav"] = np.asarray(engine.gravity(q), dtype=float)
        if rest is not None:
            copies["Qgrav"] = rest
    elif rest is not None:
        out["Qgrav"] = rest
    if has("inverse_dynamics") and "Qgrav" in out:
        out["Qv"] = -np.asarray(engine.inverse_dynamics(q, dq, np.zeros_like(dq)), dtype=float) \
            - out["Qgrav"]
    if rest is not None:
        plus = np.asarray(engine.generalized_forces(q, dq, zero3), dtype=float)
        minus = np.asarray(engine.generalized_forces(q, -dq, zero3), dtype=float)
        # F's own Qv: its own gravity (F at rest) taken off, so one mistake in F shows once
        Qv = 0.5 * (plus + minus) - rest
        if "Qv" in out:
            copies["Qv"] = Qv
        out["Qv"] = out.get("Qv", Qv)
        out["Qaero"] = 0.5 * (plus - minus)
        cols = []
        for k in range(3):
            T = zero3.copy()
            T[:, k] = 1.0
            cols.append(np.asarray(engine.generalized_forces(q, np.zeros_like(dq), T)) - rest)
        out["S"] = np.stack(cols, axis=-1)
    if extras and has("inverse_dynamics"):   # M again, column k = ID(q, 0, e_k) - ID(q, 0, 0)
        zero = np.zeros_like(dq)
        at_rest = np.asarray(engine.inverse_dynamics(q, zero, zero), dtype=float)
        copies["M"] = np.stack([np.asarray(engine.inverse_dynamics(q, zero, np.eye(len(zero[0]))[k]
                                                                   + zero), dtype=float) - at_rest
                                for k in range(zero.shape[1])], axis=-1)
    if has("constraint_jacobian"):
        out["D"] = np.asarray(engine.constraint_jacobian(q), dtype=float)
    if has("constraint_bias"):
        out["dD dq"] = np.asarray(engine.constraint_bias(q, dq), dtype=float)
    terms = {t: out[t] for t in TERMS if t in out}
    solve = None
    if extras and all(has(c) for c in SOLVE_NEEDS):
        F = np.asarray(engine.generalized_forces(q, dq, states.T), dtype=float)
        ddq = np.asarray(engine.forward_acceleration(q, dq, states.T), dtype=float)
        solve = solve_values(ddq, terms["M"], F, terms["D"], terms["dD dq"])
    return terms, (copies if extras else {}), solve


def engine_terms(engine: Engine, states: States) -> dict[str, np.ndarray]:
    """The terms an engine provides, taken out through the Engine interface only.

    Qgrav is ``gravity`` or the generalized forces at rest, ``F(q, 0, 0)``; Qv is
    ``-inverse_dynamics(q, dq, 0) - Qgrav`` or ``(F(q, dq, 0) + F(q, -dq, 0))/2 - F(q, 0, 0)``
    (Qv is even in dq, Qaero odd); Qaero ``(F(q, dq, 0) - F(q, -dq, 0))/2``; column k of S
    ``F(q, 0, e_k) - F(q, 0, 0)``.
    """
    return extract(engine, states, extras=False)[0]


#: what the check of an engine's forward solve needs from it
SOLVE_NEEDS = ("mass_matrix", "generalized_forces", "constraint_jacobian", "constraint_bias",
               "forward_acceleration")


@dataclass(frozen=True)
class SolveValues:
    """An engine's forward accelerations and the solves of its own terms they are checked
    against: the constrained one ([M D^T; D 0] [ddq; lambda] = [F; -dD dq]) and the two ways
    a solve is commonly got wrong."""

    ddq: np.ndarray            # the engine's forward_acceleration
    own: np.ndarray            # the constrained solve of the engine's own M, F, D, dD dq
    unconstrained: np.ndarray  # M^-1 F: the constraint rows left out
    bias_flipped: np.ndarray   # the solve with +dD dq on the right-hand side


def _kkt(M, F, D, rhs):
    n, m = M.shape[-1], D.shape[-2]
    K = np.zeros(M.shape[:-2] + (n + m, n + m))
    K[..., :n, :n], K[..., :n, n:], K[..., n:, :n] = M, np.swapaxes(D, -1, -2), D
    return np.linalg.solve(K, np.concatenate([F, rhs], axis=-1)[..., None])[..., :n, 0]


def solve_values(ddq, M, F, D, bias) -> SolveValues | None:
    """`SolveValues` of an engine (None where its own terms make a singular system)."""
    try:
        with np.errstate(all="ignore"):
            return SolveValues(ddq, _kkt(M, F, D, -bias),
                               np.linalg.solve(M, F[..., None])[..., 0], _kkt(M, F, D, bias))
    except np.linalg.LinAlgError:
        return None


def _scales(term: str, ref: Mapping[str, np.ndarray], tol: Tolerance) -> np.ndarray:
    """Per-state number the absolute error of ``term`` is divided by (the tolerance's scale)."""
    parts = TERM_TOLERANCE[term][1]
    n = ref[term].shape[0]
    return np.array([tol.normalizer(ref[term][k], [ref[p][k] for p in parts]) for k in range(n)])


#: a block's source -> how the term table names it
SOURCE_LABEL = {"": "", "F": " in F", "ID": " in ID", "solve": " solve"}
#: a term's second copy -> where it is taken from: generalized_forces ('F') or inverse_dynamics
COPY_SOURCE = {"Qgrav": "F", "Qv": "F", "M": "ID"}


@dataclass(frozen=True)
class Block:
    """One compared array: a term of one engine from one source ('' its own method, 'F' the
    copy taken out of generalized_forces, 'solve' the forward accelerations against the solve
    of the engine's own terms), its reference, and the per-state scale of its tolerance."""

    engine: str
    term: str
    source: str
    value: np.ndarray
    reference: np.ndarray
    scale: np.ndarray
    tolerance: float

    @property
    def label(self) -> str:
        return self.term + SOURCE_LABEL[self.source]

    def weighted(self, a: np.ndarray) -> np.ndarray:
        return a / self.scale.reshape((-1,) + (1,) * (a.ndim - 1))


def term_blocks(ref: Mapping[str, np.ndarray], engine_values: Mapping[str, Mapping[str, np.ndarray]],
                tolerances: Mapping[str, Tolerance],
                copies: Mapping[str, Mapping[str, np.ndarray]] | None = None,
                solves: Mapping[str, SolveValues | None] | None = None) -> list[Block]:
    """Every compared array of every engine (`Block`), its terms first."""
    tols = tolerances
    scale = {t: _scales(t, ref, tols[TERM_TOLERANCE[t][0]])
             for t in {t for v in engine_values.values() for t in v}}
    out = []
    for name, values in engine_values.items():
        for term, E in values.items():
            out.append(Block(name, term, "", E, ref[term], scale[term],
                             tols[TERM_TOLERANCE[term][0]].tolerance))
        for term, E in (copies or {}).get(name, {}).items():
            out.append(Block(name, term, COPY_SOURCE[term], E, ref[term], scale[term],
                             tols[TERM_TOLERANCE[term][0]].tolerance))
        solve = (solves or {}).get(name)
        if solve is not None:
            tol = tols["forward_acceleration"]
            s = np.array([tol.normalizer(o) for o in solve.own])
            out.append(Block(name, "ddq", "solve", solve.ddq, solve.own, s, tol.tolerance))
    return out


@dataclass(frozen=True)
class TermCheck:
    """One term of the equations, the model under test against one engine."""

    engine: str
    term: str
    max_error: float          # relative to the tolerance's scale
    max_abs_error: float
    tolerance: float
    passed: bool
    worst_state: int
    entries: tuple[str, ...]  # the entries above tolerance, worst first (at most 3), else the worst
    source: str = ""          # '' the engine's own method, 'F' generalized_forces, 'solve'

    @property
    def label(self) -> str:
        return self.term + SOURCE_LABEL[self.source]

    def describe(self) -> str:
        verdict = "ok" if self.passed else "DIFFERS"
        return (f"{self.label} vs {self.engine}: {verdict}, max error {self.max_error:.2e} "
                f"(tolerance {self.tolerance:.0e}) at {', '.join(self.entries)}")

    def to_dict(self) -> dict:
        return {"engine": self.engine, "term": self.term, "max_error": self.max_error,
                "max_abs_error": self.max_abs_error, "tolerance": self.tolerance,
                "passed": self.passed, "worst_state": self.worst_state,
                "entries": list(self.entries), "source": self.source}


def _entry(term: str, index: tuple[int, ...]) -> str:
    return entry_name(term, index) if term != "ddq" else f"ddq[{COORDINATES[index[0]]}]"


def check_block(b: Block) -> TermCheck:
    """A block against its tolerance: the worst entries over the whole array (a matrix's lower
    triangle too, so a non-symmetric M shows where; an entry whose mirror is already named
    with the same error is not named twice)."""
    diff = np.abs(b.value - b.reference)
    rel = diff / b.scale.reshape((-1,) + (1,) * (diff.ndim - 1))
    rel = np.where(np.isfinite(rel), rel, np.inf)
    per_entry = rel.max(axis=0)
    k = int(np.unravel_index(int(np.argmax(rel)), rel.shape)[0])
    order = np.argsort(-per_entry, axis=None, kind="stable")   # ties: the upper entry first
    named: list[tuple[int, ...]] = []
    for i in order:
        idx = tuple(int(j) for j in np.unravel_index(i, per_entry.shape))
        if named and per_entry[idx] <= b.tolerance:
            break
        mirror = idx[::-1]
        if b.term == "M" and mirror in named and \
                abs(per_entry[mirror] - per_entry[idx]) <= 1e-9 * per_entry[idx]:
            continue
        named.append(idx)
        if len(named) == 3:
            break
    err = float(rel.max())
    return TermCheck(b.engine, b.term, err, float(diff.max()), b.tolerance,
                     bool(err <= b.tolerance), k, tuple(_entry(b.term, i) for i in named),
                     b.source)


def check_terms(ref: Mapping[str, np.ndarray], engine_values: Mapping[str, Mapping[str, np.ndarray]],
                tolerances: Mapping[str, Tolerance]) -> list[TermCheck]:
    """Every term each engine provides against the model's (``ref`` from `model_terms`)."""
    return [check_block(b) for b in term_blocks(ref, engine_values, tolerances)]
