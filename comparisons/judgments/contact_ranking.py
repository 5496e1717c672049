"""The soft-contact engines side by side: one row per engine on the same manoeuvre, ranked.

Each soft-contact engine's default run of the study's manoeuvre (`stages.soft_contact`) is
measured against the ideal-rolling reference up to one *shared horizon*: the last output-grid
time before the reference's ideal rolling needs the ground to pull a wheel down (a negative
normal force, which no unilateral contact can give), capped by the reference's meaningful
horizon and the window. It depends on the reference only, so every engine is measured over the
same interval of the same manoeuvre. The row:

* ``error_at_horizon``: max over the eight coordinates of |engine - reference| at that time
  (rad or m); None when the run ends before it (ranked last, the row says so);
* ``error_max``: the largest such error up to it;
* ``slip_rms`` (m/s) and ``penetration_max``/``penetration_rms`` (m) over both wheels' samples
  up to it (`contact.contact_fidelity`);
* ``lift_off_s``: the engine's first lift-off, if any (`contact.lift_off_time`);
* ``run_time_per_simulated_second``: wall time of the default run over its simulated time (a
  measurement: it varies with the machine and its load, and is the one number of the study
  that is not a function of its inputs).

`rank` orders the rows by the error at the horizon (closest to ideal rolling first), then by
slip RMS; a run that did not reach the horizon comes after every one that did.

    row = contact_row("mujoco", "MuJoCo", ref, run, horizon=0.43, seconds=0.36)
    table = rank([row, other_row])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from reference_model.solvers import Trajectory

from .contact import contact_fidelity, error_at

__all__ = ["ContactRow", "Ranked", "contact_row", "rank", "shared_horizon"]


@dataclass(frozen=True)
class ContactRow:
    """One engine's default run on the shared horizon (module docstring)."""

    engine: str                    # its registered name or spec's class
    label: str                     # how the report names it
    model: str
    scenario: str
    horizon: float                 # s: the shared horizon
    reached: bool                  # the run reaches the horizon
    error_at_horizon: float | None
    error_max: float
    slip_rms: float
    slip_max: float
    penetration_max: float
    penetration_rms: float
    lift_off_s: float | None
    simulated_s: float             # s of simulated time of the timed run
    run_seconds: float             # s of wall time of that run
    settings: str = ""             # the engine's defaults in one line

    @property
    def run_time_per_simulated_second(self) -> float:
        return self.run_seconds / self.simulated_s if self.simulated_s > 0 else float("nan")

    def as_dict(self) -> dict:
        return {"engine": self.engine, "label": self.label, "reached_horizon": self.reached,
                "error_at_horizon": self.error_at_horizon, "error_max": self.error_max,
                "slip_rms": self.slip_rms, "slip_max": self.slip_max,
                "penetration_max": self.penetration_max,
                "penetration_rms": self.penetration_rms, "lift_off_s": self.lift_off_s,
                "run_time_per_simulated_second": self.run_time_per_simulated_second,
                "settings": self.settings}


@dataclass(frozen=True)
class Ranked:
    """A row with its place (1 = closest to ideal rolling)."""

    rank: int
    row: ContactRow


def shared_horizon(t: np.ndarray, ideal_pull_s: float | None, meaningful_s: float,
                   window_s: float) -> float:
    """The last time of the output grid ``t`` before ``ideal_pull_s`` (the reference's first
    negative normal force; None: never), at most ``meaningful_s`` and ``window_s``."""
    t = np.asarray(t, dtype=float)
    dt = float(t[1] - t[0]) if t.size > 1 else 1.0
    end = min(float(meaningful_s), float(window_s))
    if ideal_pull_s is not None:
        before = t[t < float(ideal_pull_s) - 1e-9 * dt]
        if before.size:
            end = min(end, float(before[-1]))
    return float(t[t <= end + 1e-9 * dt][-1])


def contact_row(engine: str, label: str, ref: Trajectory, run: Trajectory, horizon: float,
                seconds: float, model: str = "", scenario: str = "", settings: str = "",
                lift_off_s: float | None = None) -> ContactRow:
    """``run``'s row on ``horizon`` (module docstring); ``seconds``: its wall time."""
    reached = run.t.size > 0 and float(run.t[-1]) >= horizon - 1e-9
    fid = contact_fidelity(ref, run, horizon=min(horizon, float(run.t[-1])))
    try:
        at = error_at(ref, run, horizon) if reached else None
    except ValueError:           # the runs share no sample at the horizon
        at, reached = None, False
    return ContactRow(engine=engine, label=label, model=model, scenario=scenario,
                      horizon=float(horizon), reached=reached, error_at_horizon=at,
                      error_max=fid.error_max, slip_rms=fid.slip_rms, slip_max=fid.slip_max,
                      penetration_max=fid.penetration_max, penetration_rms=fid.penetration_rms,
                      lift_off_s=lift_off_s, simulated_s=float(run.t_end),
                      run_seconds=float(seconds), settings=settings)


def _key(row: ContactRow):
    return (not row.reached,
            row.error_at_horizon if row.error_at_horizon is not None else float("inf"),
            row.slip_rms, row.engine)


def rank(rows: Sequence[ContactRow]) -> list[Ranked]:
    """``rows`` closest to ideal rolling first (module docstring). ValueError when they are not
    on one model, scenario and horizon (then they are not side by side), or an engine repeats."""
    rows = list(rows)
    if len({(r.model, r.scenario, round(r.horizon, 9)) for r in rows}) > 1:
        raise ValueError("the rows to rank are not on one model, scenario and horizon: "
                         + "; ".join(f"{r.engine}: {r.model}, {r.scenario}, {r.horizon:g} s"
                                     for r in rows))
    names = [r.engine for r in rows]
    if len(set(names)) != len(names):
        raise ValueError(f"an engine appears twice among the rows to rank: {names}")
    return [Ranked(i + 1, r) for i, r in enumerate(sorted(rows, key=_key))]
