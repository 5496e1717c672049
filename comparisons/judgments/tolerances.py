"""Tolerances of the comparisons, read from `tolerances.toml` (one table per quantity, each
with its reason), and the error metric each one uses.

The tolerances are data: `load_tolerances` reads a file once (the CLI, the conformance plugin,
a test) into a `Tolerances` value, a frozen mapping quantity -> `Tolerance` that pickles and
hashes, and every judgment takes it as an argument. No environment variable carries them, so a
worker process (a local pool's or a remote Dask worker's) judges with exactly the tolerances
its task was given.
"""

from __future__ import annotations

import tomllib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

TOLERANCES_FILE = Path(__file__).with_name("tolerances.toml")
PACKAGED = "comparisons/judgments/tolerances.toml"   # how messages name TOLERANCES_FILE
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


@dataclass(frozen=True, eq=False)
class Tolerances(Mapping):
    """Every tolerance of a run: a frozen, picklable, hashable mapping quantity -> `Tolerance`
    (the judgments' ``tolerances`` argument). ``source`` says where it was read from (for
    messages; not part of its value: two files with the same tables are equal)."""

    entries: tuple[Tolerance, ...]
    source: str = ""

    def __getitem__(self, quantity: str) -> Tolerance:
        for t in self.entries:
            if t.quantity == quantity:
                return t
        raise KeyError(quantity)

    def __iter__(self) -> Iterator[str]:
        return (t.quantity for t in self.entries)

    def __len__(self) -> int:
        return len(self.entries)

    def __eq__(self, other) -> bool:    # the tables, not where they were read (``source``)
        if isinstance(other, Tolerances):
            return self.entries == other.entries
        return isinstance(other, Mapping) and dict(self) == dict(other)

    def __hash__(self) -> int:
        return hash(self.entries)

    def as_json(self) -> dict:
        """quantity -> {tolerance, scale, reason}: what a sweep's spec hash covers."""
        return {t.quantity: {"tolerance": t.tolerance, "scale": t.scale, "reason": t.reason}
                for t in self.entries}


def load_tolerances(path: Path | str | None = None) -> Tolerances:
    """Every tolerance in ``path`` (default: the packaged `tolerances.toml`); a malformed
    entry raises ToleranceError naming it. Reading a file is I/O: the CLI and the tests call
    this once and pass the value on."""
    path = Path(path) if path is not None else TOLERANCES_FILE
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ToleranceError(f"{path}: {exc}") from None
    out = []
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
        out.append(Tolerance(name, float(tol), entry["scale"], str(entry["reason"])))
    return Tolerances(tuple(out), str(path))


def load_complete(path: Path | str) -> Tolerances:
    """A user's tolerance file (``--tolerances``): `load_tolerances`, and every table of the
    packaged file must be in it (a missing one would be a KeyError after the runs); else a
    ToleranceError naming the file and the first missing table."""
    path = Path(path)
    if not path.is_file():
        raise ToleranceError(f"no file {str(path)!r}; copy {PACKAGED} and edit it")
    mine, shipped = load_tolerances(path), load_tolerances(TOLERANCES_FILE)
    missing = [name for name in shipped if name not in mine]
    if missing:
        more = f" (and {len(missing) - 1} more)" if len(missing) > 1 else ""
        raise ToleranceError(f"{path} lacks [{missing[0]}]{more}; start from a copy of {PACKAGED}")
    return mine


__all__ = ["PACKAGED", "SCALES", "TOLERANCES_FILE", "Tolerance", "ToleranceError", "Tolerances",
           "load_complete", "load_tolerances"]
