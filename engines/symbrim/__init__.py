"""Moore's Whipple bicycle from SymBRiM's published parts (TU Delft's bicycle-rider modelling
library) as an engine.

SymBRiM is not part of bicycle-xval's core: ``pip install 'bicycle-xval[symbrim]'``. Without it
this package still imports (without `SymbrimEngine`), so the registry lists the engine as not
installed, with that line (``REQUIRES``/``EXTRA``: docs/engines.md)."""

from ..registry import missing_modules

#: the top-level modules the engine imports beyond the core, and the extra that installs them
REQUIRES = ("symbrim", "bicycleparameters")
EXTRA = "symbrim"
#: imported before `run`'s workers fork: BicycleParameters' parameter sets (the parameter
#: conversion of every build, `engines.symbrim.parameters`; 1.2 s with the matplotlib.pyplot
#: and scipy.optimize it imports, once in the main process instead of in every worker).
#: symbrim (and sympy with it, 0.3-0.5 s) is needed only to derive the equations on a cold
#: cache; the cached code needs neither, and the run path imports no sympy
#: (tests/test_codegen.py)
WARM: tuple[str, ...] = ("bicycleparameters.parameter_sets",)

if not missing_modules(REQUIRES):
    from .engine import SymbrimEngine

__all__ = ["EXTRA", "REQUIRES", "SymbrimEngine", "WARM"]
