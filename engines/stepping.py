"""The arguments every engine with its own time loop checks before a forward run (a soft-contact
simulator stepping on the scenario's grid): the fall limit, the scenario's kind and the output
grid up to ``t_end``. A bad value is an `EngineUsageError`, one line naming it."""

from __future__ import annotations

import math

import numpy as np

from .base import EngineUsageError

__all__ = ["forward_grid"]


def forward_grid(scenario, t_end, fall_limit, who: str) -> tuple[np.ndarray, float]:
    """(the output grid up to ``t_end``, the fall limit as a float) of a forward run of
    ``scenario`` by the engine labelled ``who``."""
    if not (isinstance(fall_limit, (int, float)) and math.isfinite(fall_limit) and fall_limit > 0):
        raise EngineUsageError(f"fall_limit must be a positive angle in rad; got {fall_limit!r}")
    if scenario.kind != "forward":
        raise EngineUsageError(f"scenario {scenario.name!r} is an inverse scenario; {who} runs only "
                               "forward scenarios")
    grid = scenario.t
    if t_end is not None:
        grid = grid[grid <= float(t_end) + 1e-12]
        if grid.size < 2:
            raise EngineUsageError(f"t_end = {t_end!r} leaves fewer than 2 grid samples")
    return grid, float(fall_limit)
