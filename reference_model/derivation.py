"""Where the symbolic derivation used to live; the code is now
``reference_model/equations/derivation.py``. This module re-exports it (and imports sympy).
"""

from .equations.derivation import *  # noqa: F401,F403
from .equations.derivation import __all__  # noqa: F401
# the old module's imports
from .equations.derivation import CONTACT_MODELS, PARAMETER_NAMES  # noqa: F401
