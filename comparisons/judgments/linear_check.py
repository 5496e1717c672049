"""The project's linearization of a disc-contact bicycle against the benchmark's closed form.

``reference_model.linearize`` differentiates the reduced dynamics of the model's own equations
(the thesis's minimal coordinates, complex steps); :mod:`.meijaard` is Meijaard et al. (2007)
Appendix A, evaluated from the model's Table 1 values (``reference_model.benchmark.
to_benchmark``). They share no code: an error in the derivation, the contact, the reduction,
the sign conventions or the speed scaling of either shows up as a difference.

Compared:

* M, C1, K0, K2 (benchmark signs, over [phi, delta]): max |linearization - closed form| over a
  matrix, divided by the closed form's largest entry of that matrix (``[linear_closed_form]``);
* the weave and capsize speeds within ``speeds``: the linearization's
  (``judgments.eigenvalues.critical_speeds``, what the stability section shows) against the
  closed form's (:func:`.meijaard.closed_form_critical_speeds`, its own root finding on the
  closed form's eigenvalues), absolute, m/s (``[linear_closed_form_speeds]``). A speed found
  by one and not the other fails; none on both agrees.

Which models: those with a benchmark counterpart (contact disc, wheels with Izz = Ixx). A model
with drag (cv > 0) has no steady upright motion: it is checked with cv = 0, as the stability
section linearizes it, and the result says so. Any other model is *not applicable* (with
``to_benchmark``'s reason), never a failure. No I/O: the tolerances are an argument.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .meijaard import MATRICES, closed_form, closed_form_critical_speeds
from .tolerances import Tolerance

__all__ = ["LinearCheck", "MatrixCheck", "SpeedCheck", "linear_benchmark_check"]

MATRIX_TOLERANCE = "linear_closed_form"
SPEED_TOLERANCE = "linear_closed_form_speeds"
_COORDS = ("phi", "delta")


@dataclass(frozen=True)
class MatrixCheck:
    """One matrix: max relative difference, where it is largest (e.g. ``K2[phi, delta]``)."""

    name: str
    error: float
    tolerance: float
    worst: str

    @property
    def passed(self) -> bool:
        return bool(self.error <= self.tolerance)


@dataclass(frozen=True)
class SpeedCheck:
    """One critical speed (m/s) by the closed form and by the linearization; None: none in range."""

    mode: str                      # "weave" or "capsize"
    closed_form: float | None
    linearization: float | None
    tolerance: float

    @property
    def difference(self) -> float | None:
        if self.closed_form is None or self.linearization is None:
            return None
        return abs(self.linearization - self.closed_form)

    @property
    def passed(self) -> bool:
        if self.closed_form is None or self.linearization is None:
            return self.closed_form is None and self.linearization is None
        return bool(self.difference <= self.tolerance)


@dataclass(frozen=True)
class LinearCheck:
    """The check of one model. ``reason`` (not empty) when it is not applicable; ``note``: how
    the model was changed to be checked (drag removed), else empty."""

    model: str
    reason: str
    note: str
    speeds_range: tuple[float, float]
    matrices: tuple[MatrixCheck, ...] = ()
    speeds: tuple[SpeedCheck, ...] = ()

    @property
    def applicable(self) -> bool:
        return not self.reason

    @property
    def passed(self) -> bool | None:
        """All within tolerance; None when not applicable."""
        if not self.applicable:
            return None
        return all(c.passed for c in (*self.matrices, *self.speeds))


def _matrix_check(name: str, got: np.ndarray, expected: np.ndarray, tol: Tolerance) -> MatrixCheck:
    diff = np.abs(np.asarray(got, dtype=float) - expected)
    i, j = np.unravel_index(int(np.argmax(diff)), diff.shape)
    return MatrixCheck(name, float(diff.max()) / tol.normalizer(expected), tol.tolerance,
                       f"{name}[{_COORDS[i]}, {_COORDS[j]}]")


def linear_benchmark_check(model, tolerances: Mapping[str, Tolerance],
                           speeds: tuple[float, float] = (0.0, 10.0)) -> LinearCheck:
    """``model``'s linearization against the closed form of its Table 1 values (module doc)."""
    from reference_model.benchmark import to_benchmark
    from reference_model.linearize import linearize
    from reference_model.params import ParameterError

    from .eigenvalues import critical_speeds

    rng = (float(speeds[0]), float(speeds[1]))
    note = ""
    if model.params.cv != 0.0:
        note = (f"{model.name} has drag (cv = {model.params.cv:g} kg/m), so no steady upright "
                "motion: checked with cv = 0, as the stability section linearizes it")
        model = model.with_params(model.params.replace(cv=0.0))
    try:
        table1 = to_benchmark(model.params)
    except ParameterError as exc:
        # the reason follows the *last* lead-in: the model's name, a free string, comes
        # before it and may hold the same words
        why = exc.problem.rsplit("counterpart: ", 1)[-1]
        return LinearCheck(model.name, f"no benchmark counterpart: {why}", note, rng)
    cf = closed_form(table1)
    lin = linearize(model, 0.0)
    tol_m, tol_s = tolerances[MATRIX_TOLERANCE], tolerances[SPEED_TOLERANCE]
    matrices = tuple(_matrix_check(k, getattr(lin, k), getattr(cf, k), tol_m) for k in MATRICES)
    found = closed_form_critical_speeds(cf, rng)
    ours = critical_speeds(model, np.array(rng))
    checks = tuple(SpeedCheck(mode, theirs, mine, tol_s.tolerance)
                   for mode, theirs, mine in zip(("weave", "capsize"), found, ours))
    return LinearCheck(model.name, "", note, rng, matrices, checks)
