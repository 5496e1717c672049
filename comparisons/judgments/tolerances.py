"""Tolerances of the comparisons, read from `tolerances.toml` (one table per quantity, each
with its reason), and the error metric each one uses."""

from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

TOLERANCES_FILE = Path(__file__).with_name("tolerances.toml")
TOLERANCES_ENV = "BICYCLE_XVAL_TOLERANCES"   # `bicycle-xval run --tolerances FILE` sets it
SCALES = ("max_abs", "max_abs_or_one", "largest_term", "absolute")


class ToleranceError(ValueError):
    """A malformed tolerance file (names the quantity and the field)."""


@dataclass(frozen=True)
class Tolerance:
    """The accepted error of one quantity: error / scale <= tolerance."""

    quantity: str
    tolerance: float
    scale: str
    reason: str

    def normalizer(self, reference: np.ndarray, terms: list[np.ndarray] | None = None) -> float:
        """The number an absolute error is divided by."""
        ref = np.abs(np.asarray(reference, dtype=float))
        if self.scale == "absolute":
            return 1.0
        if self.scale == "max_abs":
            return float(ref.max()) or 1.0
        if self.scale == "max_abs_or_one":
            return max(1.0, float(ref.max()))
        parts = [np.abs(np.asarray(t, dtype=float)).max() for t in (terms or [reference])]
        return max(1.0, float(max(parts)))


def load_tolerances(path: Path | None = None) -> dict[str, Tolerance]:
    """All tolerances (from ``path``, else $BICYCLE_XVAL_TOLERANCES, else the shipped file); a
    malformed entry raises ToleranceError naming it."""
    path = Path(path or os.environ.get(TOLERANCES_ENV) or TOLERANCES_FILE)
    try:
        data = tomllib.loads(Path(path).read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ToleranceError(f"{path}: {exc}") from None
    out = {}
    for name, entry in data.items():
        if not isinstance(entry, dict):
            raise ToleranceError(f"{path}: [{name}] must be a table with tolerance, scale, reason")
        missing = {"tolerance", "scale", "reason"} - set(entry)
        if missing:
            raise ToleranceError(f"{path}: [{name}] lacks {', '.join(sorted(missing))}")
        tol = entry["tolerance"]
        if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not (0 < tol < 1):
            raise ToleranceError(f"{path}: {name}.tolerance must be a number in (0, 1); got {tol!r}")
        if entry["scale"] not in SCALES:
            raise ToleranceError(f"{path}: {name}.scale must be one of {SCALES}; got {entry['scale']!r}")
        if not str(entry["reason"]).strip():
            raise ToleranceError(f"{path}: {name}.reason is empty: say why the tolerance is that size")
        out[name] = Tolerance(name, float(tol), entry["scale"], str(entry["reason"]))
    return out
