"""The thesis bicycle rebuilt in Pinocchio (`engine.py`: CRBA, RNEA, and rolling constraints
from its kinematics alone; its module docstring describes the tree).

Pinocchio (the package ``pin``) is not part of bicycle-xval's core:
``pip install 'bicycle-xval[pinocchio]'``. Without it this package still imports (without
`PinocchioEngine`), so the registry lists the engine as not installed, with that line
(``REQUIRES``/``EXTRA``: docs/engines.md)."""

from ..registry import missing_modules

#: the top-level modules the engine imports beyond the core, and the extra that installs them
REQUIRES = ("pinocchio",)
EXTRA = "pinocchio"

if not missing_modules(REQUIRES):
    from .engine import PinocchioEngine, build_pinocchio_model

__all__ = ["EXTRA", "REQUIRES", "PinocchioEngine", "build_pinocchio_model"]
