"""Where what a scenario is (`Scenario` and its parts) used to be defined; the code is now
``reference_model/scenarios/definition.py``. This module re-exports it.
"""

from .scenarios.definition import *  # noqa: F401,F403
from .scenarios.definition import __all__  # noqa: F401
from .scenarios.definition import (DEFAULT_FALL_LIMIT, THESIS_BAUMGARTE,  # noqa: F401
                                   IndependentMotion)  # (the old module's imports)
