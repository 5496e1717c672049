"""Where the printers of the generated code used to live; the code is now
``reference_model/equations/emit.py``. This module re-exports it (and imports sympy).
"""

from .equations.emit import *  # noqa: F401,F403
from .equations.emit import __all__  # noqa: F401
# the old module's imports
from .equations.emit import COORDINATES, POINT_NAMES, dv  # noqa: F401
