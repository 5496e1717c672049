"""The thesis bicycle in Drake: a MultibodyPlant from the project's URDF export (its terms), and
forward runs on Drake's own wheel-ground contact.

Drake (the package ``drake``, module ``pydrake``) is not part of bicycle-xval's core:
``pip install 'bicycle-xval[drake]'``. Without it this package still imports (without
`DrakeEngine`), so the registry lists the engine as not installed, with that line
(``REQUIRES``/``EXTRA``: docs/engines.md)."""

from ..registry import missing_modules

#: the top-level modules the engine imports beyond the core, and the extra that installs them
REQUIRES = ("pydrake",)
EXTRA = "drake"

if not missing_modules(REQUIRES):
    from .engine import DrakeEngine

__all__ = ["EXTRA", "REQUIRES", "DrakeEngine"]
