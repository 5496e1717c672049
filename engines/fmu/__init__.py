"""Any FMI 2.0 Model-Exchange FMU as an engine (``--engine fmu --engine-option fmu=PATH.fmu
[--engine-option mapping=PATH.toml]``): forward accelerations from its derivatives, runs from
integrating them with the reference's solvers, the thesis's terms where the mapping names
outputs holding them. fmpy loads the FMU: ``pip install 'bicycle-xval[fmu]'``; without it this
package still imports (without `FmuEngine`), so the registry lists the engine as not
installed."""

from ..registry import missing_modules

#: the top-level modules the engine imports beyond the core, and the extra that installs them
REQUIRES = ("fmpy",)
EXTRA = "fmu"

if not missing_modules(REQUIRES):
    from .engine import FmuEngine

__all__ = ["EXTRA", "REQUIRES", "FmuEngine"]
