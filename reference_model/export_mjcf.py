"""Where the MJCF export used to live; the code is now ``reference_model/exports/mjcf.py``. This
module re-exports it.

    from reference_model.export_mjcf import MjcfSettings, mjcf_text
"""

from .exports.mjcf import *  # noqa: F401,F403
from .exports.mjcf import __all__  # noqa: F401
from .exports.mjcf import Parameters  # noqa: F401 (the old module's import)
