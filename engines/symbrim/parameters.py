"""The model's parameters as Moore's (SymBRiM's `WhippleBicycleMoore`), through BicycleParameters'
own conversion.

The route: the model's Table 1 values (`reference_model.parameters.to_benchmark`, with the drag
coefficient set aside: cv is not a Whipple parameter), then BicycleParameters'
``Meijaard2007ParameterSet(...).to_parameterization("Moore2012")`` (its ``benchmark_to_moore``,
from DynamicistToolKit), whose d1..d3, l1..l4, masses and tensor entries (``ic11`` ... ``if33``)
are Moore's, in Moore's body frames; cv is then the model's own. So the equations SymBRiM's parts
build and the numbers they are evaluated at both come from outside this project.

A bicycle with no Table 1 counterpart (a wheel whose three moments differ, as the conformance
suite's general bicycle has; Table 1's wheels are axisymmetric) cannot take that route: it gets
the project's own conversion (`engines.kane.moore_parameters`), and `parameter_route` says so.
On every bicycle that has a counterpart the two routes agree to rounding (tests/test_symbrim.py:
the benchmark, thesis-disc and BicycleParameters' measured bicycles)."""

from __future__ import annotations

import dataclasses

import numpy as np

from reference_model.parameters import ParameterError, to_benchmark

from ..kane.engine import moore_parameters as project_moore_parameters
from ..kane.names import MOORE_PARAMETERS

__all__ = ["BICYCLEPARAMETERS_ROUTE", "MOORE2012_NAMES", "moore_parameters", "parameter_route"]

#: MOORE_PARAMETERS' names -> BicycleParameters' Moore2012 names (Moore's wheel D rear, F front,
#: frame C, fork E; the tensor entries 11, 22, 33, 31 are xx, yy, zz, xz in Moore's frames)
MOORE2012_NAMES: dict[str, str] = {
    "rr": "rr", "rf": "rf", "d1": "d1", "d2": "d2", "d3": "d3",
    "l1": "l1", "l2": "l2", "l3": "l3", "l4": "l4",
    "mc": "mc", "md": "md", "me": "me", "mf": "mf",
    "IDxx": "id11", "IDyy": "id22", "IDzz": "id33",
    "ICxx": "ic11", "ICyy": "ic22", "ICzz": "ic33", "ICxz": "ic31",
    "IExx": "ie11", "IEyy": "ie22", "IEzz": "ie33", "IExz": "ie31",
    "IFxx": "if11", "IFyy": "if22", "IFzz": "if33", "g": "g",
}
BICYCLEPARAMETERS_ROUTE = ("BicycleParameters' conversion (its Table 1 values through "
                           "Meijaard2007ParameterSet.to_parameterization('Moore2012'))")


def _through_bicycleparameters(table: dict[str, float]) -> dict[str, float]:
    from bicycleparameters.parameter_sets import Meijaard2007ParameterSet
    values = {k: float(v) for k, v in table.items()}
    values["v"] = 0.0   # the parameter set carries a speed; Moore's parameters do not use it
    return Meijaard2007ParameterSet(values, True).to_parameterization("Moore2012").parameters


def _table(params) -> dict[str, float] | str:
    """The model's Table 1 values without its drag, or why it has none."""
    try:
        return to_benchmark(dataclasses.replace(params, cv=0.0))
    except ParameterError as exc:
        return " ".join(str(exc).split())


def parameter_route(params) -> str:
    """Which conversion `moore_parameters` takes for ``params``, in words."""
    table = _table(params)
    if isinstance(table, dict):
        return BICYCLEPARAMETERS_ROUTE
    return f"the project's own conversion: no Table 1 counterpart ({table})"


def moore_parameters(params) -> np.ndarray:
    """Moore's parameters of ``params`` in `MOORE_PARAMETERS` order (module docstring): through
    BicycleParameters when the model has Table 1 values, else the project's conversion."""
    table = _table(params)
    if not isinstance(table, dict):
        return project_moore_parameters(params)
    moore = _through_bicycleparameters(table)
    values = {k: float(moore[b]) for k, b in MOORE2012_NAMES.items()}
    values["cv"] = float(params.cv)
    return np.array([values[k] for k in MOORE_PARAMETERS])
