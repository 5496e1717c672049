"""The thesis bicycle in MuJoCo: its tree from the MJCF export, its soft wheel-ground contact.

MuJoCo is not part of bicycle-xval's core: ``pip install 'bicycle-xval[mujoco]'``. Without it
this package still imports (without `MujocoEngine`), so the registry lists the engine as not
installed, with that line (``REQUIRES``/``EXTRA``: docs/engines.md)."""

from ..registry import missing_modules

#: the top-level modules the engine imports beyond the core, and the extra that installs them
REQUIRES = ("mujoco",)
EXTRA = "mujoco"

if not missing_modules(REQUIRES):
    from .engine import MujocoEngine

__all__ = ["EXTRA", "REQUIRES", "MujocoEngine"]
