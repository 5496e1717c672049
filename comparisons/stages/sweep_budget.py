"""What a sweep will cost, said before it starts, and the limits that keep one from running away.

    refuse_huge(count_bicycles(varies, sample), max_bicycles)   # SweepTooLarge: names --max-bicycles
    limit = bicycle_limit(cost)                  # s a bicycle may take before it is given up
    print(estimate_line(estimate))               # bicycles, chunks, expected time

* **Cap**: a sweep of more than ``max_bicycles`` bicycles (`DEFAULT_MAX_BICYCLES` unless the
  user raises it, ``--max-bicycles``) is refused before anything is planned or started: at the
  measured ~0.1 s a bicycle, 10^5 bicycles are about 1.5 h on two cores and their merged
  results about 0.1-0.2 GB in memory; beyond, the user says so.
* **Per-bicycle time limit**: ``max(LIMIT_FLOOR, LIMIT_FACTOR * cost)``: the floor covers a
  worker's first bicycle, which also imports the engines and loads (on a cold cache: generates
  and compiles) the model's code, about 40 s at worst on the 2-core machine; the factor covers
  a bicycle 20x slower than the measured mean (the runs of a bicycle near a critical speed).
  ``--bicycle-timeout`` replaces it.
* **Estimate**: the per-bicycle cost is the mean measured ``task_seconds`` of the rows already
  computed under the same spec (a resume), else the table measured on the development machine
  (`sweep.COST`, benchmarks/sweep_timings.py); the expected time is that cost times the
  bicycles left, over the workers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["DEFAULT_MAX_BICYCLES", "Estimate", "LIMIT_FACTOR", "LIMIT_FLOOR", "SweepTooLarge",
           "bicycle_limit", "count_bicycles", "duration", "estimate_line", "refuse_huge"]

DEFAULT_MAX_BICYCLES = 100_000
LIMIT_FLOOR = 120.0        # s
LIMIT_FACTOR = 20.0


class SweepTooLarge(ValueError):
    """More bicycles than the cap: one line naming the option that raises it."""


def refuse_huge(n_bicycles: int, max_bicycles: int) -> None:
    """`SweepTooLarge` when ``n_bicycles`` exceeds ``max_bicycles``."""
    if n_bicycles > max_bicycles:
        raise SweepTooLarge(
            f"{n_bicycles} bicycles is more than --max-bicycles {max_bicycles}: give fewer "
            f"(--sample, --vary) or raise the cap with --max-bicycles {n_bicycles} if you mean it")


def bicycle_limit(cost: float, override: float | None = None) -> float:
    """Seconds one bicycle may take (module docstring); ``override`` when given."""
    if override is not None:
        return float(override)
    return max(LIMIT_FLOOR, LIMIT_FACTOR * cost)


@dataclass(frozen=True)
class Estimate:
    """A sweep before it starts: its size, what is left, and what that should cost."""

    n_bicycles: int
    chunks: int
    chunks_left: int
    bicycles_left: int
    cost: float               # s per bicycle
    measured_on: int          # rows the cost was measured on (0: the development table)
    workers: int | None       # None: not known yet (a cluster not started)
    limit: float              # s per bicycle before it is given up

    @property
    def seconds(self) -> float:
        return self.cost * self.bicycles_left / max(1, self.workers or 1)


def duration(seconds: float) -> str:
    """A duration for people: under a second, 40 s, 12 min, 3.5 h, 2.1 days."""
    if not math.isfinite(seconds):
        return "an unknown time"
    if seconds < 1:
        return "under a second"
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    if seconds < 172800:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def _about(when: str) -> str:
    return when if when.startswith("under") else f"about {when}"


def estimate_line(e: Estimate) -> str:
    """One line: bicycles, chunks, what is left and the expected time (module docstring)."""
    source = (f"measured on the {e.measured_on} bicycles done" if e.measured_on
              else "the development machine's measured cost")
    where = f"on {e.workers} worker{'s' if e.workers != 1 else ''}" if e.workers else "on one worker"
    done = e.chunks - e.chunks_left
    return (f"sweep: {e.n_bicycles} bicycles in {e.chunks} chunks ({done} already done); "
            f"{e.bicycles_left} to compute, {_about(duration(e.seconds))} {where} "
            f"at {e.cost:.3g} s a bicycle ({source}); each bicycle given up after "
            f"{e.limit:g} s")


def count_bicycles(varies, sample: int | None) -> int | None:
    """How many bicycles the options ask for, before the spec is built (a grid's points are
    validated one by one there, so a huge grid must be refused first); None when the options
    do not parse (`sweep_spec.make_spec` then says why)."""
    from .sweep_spec import SpecError, parse_vary
    if sample is not None:
        return sample
    try:
        return math.prod(parse_vary(v).n for v in varies) if varies else None
    except SpecError:
        return None
