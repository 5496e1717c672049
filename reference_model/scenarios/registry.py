"""The built-in scenarios by name, read once from their files in ``reference_model/scenario_data/``
on first use (``reference_model.scenarios.SCENARIOS`` is :func:`builtin_scenarios`)."""

from __future__ import annotations

import functools

from .definition import Scenario

__all__ = ["UnknownScenarioError", "builtin_scenarios", "get_scenario"]


@functools.cache
def builtin_scenarios() -> dict[str, Scenario]:
    """The built-in scenarios, read once from their files in ``reference_model/scenario_data/``
    (`reference_model.scenarios.files.load_builtin_scenarios`), by name."""
    from .files import load_builtin_scenarios   # on first use: the files are read then
    return load_builtin_scenarios()


class UnknownScenarioError(KeyError):
    def __str__(self):
        return self.args[0]


def get_scenario(name: str) -> Scenario:
    scenarios = builtin_scenarios()
    try:
        return scenarios[name]
    except KeyError:
        raise UnknownScenarioError(f"unknown scenario {name!r}; choose one of: "
                                   f"{', '.join(scenarios)}") from None
