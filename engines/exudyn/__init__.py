"""The thesis bicycle in Exudyn: a minimal-coordinate kinematic-tree build (`tree.py`), a
redundant rigid-body build (`redundant.py`), the map from body poses back to the thesis's q
(`mapping.py`), and the engine that runs scenarios on either (`engine.py`).

Exudyn is not part of bicycle-xval's core: ``pip install 'bicycle-xval[exudyn]'``. Without it
this package still imports (without `ExudynEngine`), so the registry lists the engine as not
installed, with that line (``REQUIRES``/``EXTRA``: docs/engines.md)."""

from ..registry import missing_modules

#: the top-level modules the engine imports beyond the core, and the extra that installs them
REQUIRES = ("exudyn",)
EXTRA = "exudyn"

if not missing_modules(REQUIRES):
    from .engine import ExudynEngine

__all__ = ["EXTRA", "REQUIRES", "ExudynEngine"]
