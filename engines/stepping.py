"""The checked inputs of an engine's own time loop (a simulator stepping a scenario itself
rather than through the reference's solvers): the output grid up to ``t_end`` and the fall
limit, each refused in one line naming the option when it cannot be used."""

from __future__ import annotations

import numpy as np

from reference_model.solvers import checked_fall_limit

from .base import CapabilityError, EngineUsageError

__all__ = ["forward_grid", "refuse_fork_axis_contact", "steps_per_sample"]


def forward_grid(scenario, fall_limit, t_end, who: str) -> tuple[np.ndarray, float]:
    """(the scenario's grid cut at ``t_end`` (None: the whole grid), the fall limit in rad);
    ``who`` names the engine in the messages."""
    try:
        fall_limit = checked_fall_limit(fall_limit)
    except ValueError as err:
        raise EngineUsageError(str(err)) from None
    if scenario.kind != "forward":
        raise EngineUsageError(f"scenario {scenario.name!r} is an inverse scenario; {who} runs "
                               "only forward scenarios")
    grid = scenario.t
    if t_end is not None:
        grid = grid[grid <= float(t_end) + 1e-12]
        if grid.size < 2:
            raise EngineUsageError(f"t_end = {t_end!r} leaves fewer than 2 grid samples")
    return grid, fall_limit


def refuse_fork_axis_contact(engine) -> None:
    """Raise `CapabilityError` when ``engine`` (an engine whose own runs approximate the
    rolling-disc contact) is asked to simulate a model with the thesis's fork-axis front
    contact: a declared limitation, not a failure."""
    if "simulate" not in engine.capabilities:
        raise CapabilityError(
            f"engine {engine.name!r} cannot simulate model {engine.model.name!r}: its forward "
            f"runs approximate the rolling-disc contact, and this model has the thesis's "
            f"fork-axis front contact; use a disc-contact model (thesis-disc, benchmark)")


def steps_per_sample(h: float, interval: float, span: float, who: str, option: str) -> int:
    """Fixed steps of ``h`` per output ``interval``: `EngineUsageError` unless ``h`` divides the
    interval (the steps must land on the output samples) and the run's ``span``; ``who`` and
    ``option`` name the engine and its step option in the message."""
    per = int(round(interval / h))
    if per < 1 or abs(per * h - interval) > 1e-9 * interval \
            or abs(round(span / h) * h - span) > 1e-9 * max(span, 1.0):
        k = max(1, int(interval / h))
        raise EngineUsageError(
            f"{who} {option} = {h:g} s must divide the output interval {interval:g} s and the "
            f"run's duration {span:g} s (the steps must land on the output samples); fix: "
            f"{option}={interval / k:.10g} or {interval / (k + 1):.10g}")
    return per
