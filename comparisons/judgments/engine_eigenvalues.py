"""An engine's roll/steer eigenvalues (its ``eigenvalues`` capability) against the reference's
exact linearization, and its weave and capsize speeds against the reference's.

The reference side is `reference_model.linearize` (complex-step derivatives of the thesis's
reduced equations: no truncation error); the engine's side whatever its capability computes
(for most engines `engines.linear`: central differences of the engine's own accelerations on
its own constraints), so the two share no arithmetic beyond the sort order.

Compared, per engine and model:

* the eigenvalues over a speed grid: at each speed the four eigenvalues are matched to the
  reference's (the pairing of the 4! that minimizes the largest difference: a sort order that
  flips where a pair forms is not an error), the largest |difference| divided by max(1, the
  largest |reference eigenvalue| at that speed); the error is the largest over the grid
  (``[engine_eigenvalues]``);
* the weave and capsize speeds (m/s) within the range, absolute (``[engine_critical_speeds]``).
  A speed found on one side only fails; none on both agrees.

A row whose engine setup declares a model difference (an option study's value other than the
reference's) is *reported* (passed None, the difference named), never a failure. No I/O: the
tolerances are an argument.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from itertools import permutations

import numpy as np

from .rows import Comparison
from .tolerances import Tolerance

__all__ = ["EIGENVALUE_TOLERANCE", "SPEED_TOLERANCE", "CriticalSpeed", "EigenvalueCheck",
           "check_rows", "judge_eigenvalues", "matched_error"]

EIGENVALUE_TOLERANCE = "engine_eigenvalues"
SPEED_TOLERANCE = "engine_critical_speeds"
_PERMS = np.array(list(permutations(range(4))))       # (24, 4)


def matched_error(got, expected) -> np.ndarray:
    """(n,): at each speed, the largest |got - expected| over the four eigenvalues under the
    best pairing, divided by max(1, max |expected|) at that speed (module docstring)."""
    g = np.asarray(got, dtype=complex).reshape(-1, 4)
    e = np.asarray(expected, dtype=complex).reshape(-1, 4)
    diff = np.abs(g[:, _PERMS] - e[:, None, :]).max(axis=2)          # (n, 24)
    return diff.min(axis=1) / np.maximum(1.0, np.abs(e).max(axis=1))


@dataclass(frozen=True)
class CriticalSpeed:
    """One critical speed (m/s) of the engine and of the reference; None: none in range."""

    mode: str
    engine: float | None
    reference: float | None
    tolerance: float

    @property
    def difference(self) -> float | None:
        if self.engine is None or self.reference is None:
            return None
        return abs(self.engine - self.reference)

    @property
    def passed(self) -> bool:
        if self.engine is None or self.reference is None:
            return self.engine is None and self.reference is None
        return bool(self.difference <= self.tolerance)


@dataclass(frozen=True)
class EigenvalueCheck:
    """One engine setup's eigenvalues on one model against the reference's. ``error``: the
    largest matched error over ``speeds`` (at ``worst_speed``); ``difference``: a declared
    model difference of this setup (its rows reported), else empty."""

    engine: str
    model: str
    speeds: tuple[float, ...]
    error: float
    worst_speed: float
    tolerance: float
    critical: tuple[CriticalSpeed, ...]
    speed_range: tuple[float, float]
    difference: str = ""

    @property
    def eigenvalues_passed(self) -> bool:
        return bool(self.error <= self.tolerance)

    @property
    def passed(self) -> bool | None:
        """Everything within tolerance; None when the setup declares a model difference."""
        if self.difference:
            return None
        return self.eigenvalues_passed and all(c.passed for c in self.critical)


def judge_eigenvalues(engine: str, model: str, speeds, got, expected,
                      engine_critical: tuple[float | None, float | None],
                      reference_critical: tuple[float | None, float | None],
                      speed_range: tuple[float, float], tolerances: Mapping[str, Tolerance],
                      difference: str = "") -> EigenvalueCheck:
    """The check of ``got`` ((n, 4), the engine's at ``speeds``) against ``expected`` (the
    reference's), and of the (weave, capsize) speeds of each (module docstring)."""
    v = np.asarray(speeds, dtype=float).reshape(-1)
    err = matched_error(got, expected)
    i = int(np.argmax(err))
    tol = tolerances[SPEED_TOLERANCE].tolerance
    crit = tuple(CriticalSpeed(mode, e, r, tol) for mode, e, r in
                 zip(("weave", "capsize"), engine_critical, reference_critical))
    return EigenvalueCheck(engine, model, tuple(float(x) for x in v), float(err[i]), float(v[i]),
                           tolerances[EIGENVALUE_TOLERANCE].tolerance, crit,
                           (float(speed_range[0]), float(speed_range[1])), difference)


def _speed(x: float | None) -> str:
    return "none" if x is None else f"{x:.10f}"


def check_rows(check: EigenvalueCheck, quantity: str = "eigenvalues",
               scenario: str = "upright straight running") -> list[Comparison]:
    """The comparison rows of one check: the eigenvalues, then each critical speed; judged,
    or reported when the setup declares a model difference."""
    lo, hi = check.speed_range
    declared = {} if not check.difference else {
        "declared_difference": check.difference, "why": "declared model difference"}
    note_tail = ("" if not check.difference else
                 f"; reported, not judged: a declared model difference ({check.difference})")
    rows = [Comparison.of({
        "quantity": f"{quantity}: roll/steer eigenvalues", "scenario": scenario,
        "model": check.model, "engines": ["reference", check.engine],
        "max_error": check.error, "tolerance": check.tolerance,
        "passed": check.eigenvalues_passed if not check.difference else None,
        "localized_to": f"v = {check.worst_speed:g} m/s",
        "speeds": [check.speeds[0], check.speeds[-1], len(check.speeds)],
        "note": "largest |difference| of the matched eigenvalues / max(1, max |reference|), "
                f"over {len(check.speeds)} speeds {check.speeds[0]:g}-{check.speeds[-1]:g} "
                f"m/s" + note_tail, **declared})]
    for c in check.critical:
        rows.append(Comparison.of({
            "quantity": f"{quantity}: {c.mode} speed", "scenario": scenario,
            "model": check.model, "engines": ["reference", check.engine],
            "max_error": c.difference, "tolerance": c.tolerance,
            "passed": c.passed if not check.difference else None,
            "reference": c.reference, "engine_value": c.engine,
            "localized_to": f"reference {_speed(c.reference)} m/s, engine {_speed(c.engine)} m/s",
            "note": f"in {lo:g}-{hi:g} m/s; none on both counts as agreement" + note_tail,
            **declared}))
    return rows
