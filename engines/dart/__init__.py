"""The thesis bicycle in DART (dartpy): its skeleton from the URDF export (`skeleton`), the
thesis's terms from DART's dynamics and Jacobians (`terms`), forward runs on DART's own
frictional contact (`run`).

DART is not part of bicycle-xval's core: ``pip install 'bicycle-xval[dart]'``. Without it this
package still imports (without `DartEngine`), so the registry lists the engine as not
installed, with that line (``REQUIRES``/``EXTRA``: docs/engines.md)."""

from ..registry import missing_modules

#: the top-level modules the engine imports beyond the core, and the extra that installs them
REQUIRES = ("dartpy",)
EXTRA = "dart"

if not missing_modules(REQUIRES):
    from .engine import DartEngine

__all__ = ["EXTRA", "REQUIRES", "DartEngine"]
