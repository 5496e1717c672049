"""Where the scenario file format used to live; the code is now
``reference_model/scenarios/files.py``. This module re-exports it.
"""

from .scenarios.files import *  # noqa: F401,F403
from .scenarios.files import __all__  # noqa: F401
