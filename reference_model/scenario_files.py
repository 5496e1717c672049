"""Where the scenario file format used to live; the code is now
``reference_model/scenarios/files.py``. This module re-exports it.
"""

from .scenarios.files import *  # noqa: F401,F403
from .scenarios.files import __all__  # noqa: F401
# the old module's other names (its constants, and what it imported), so every old import works
from .scenarios.files import (CONSTRAINT_HANDLING, COORDINATE_ORDER,  # noqa: F401
                              DEFAULT_FALL_LIMIT,
                              DEPENDENT_COORDINATES, FORWARD_QUANTITIES,
                              INDEPENDENT_COORDINATES, INTERPOLATIONS, INVERSE_QUANTITIES,
                              MOTIONS, NAMED_MODELS, QUANTITIES, RATES, THESIS_BAUMGARTE,
                              TORQUE_FUNCTIONS, TORQUES, ExpectedDifference, Scenario,
                              TorqueSamples)
