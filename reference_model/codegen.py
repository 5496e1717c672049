"""Where the generated code's build, cache and loading used to live; the code is now
``reference_model/equations/codegen.py``. This module re-exports it (``_commit`` too, which
the cache's robustness tests drive directly).
"""

from .equations.codegen import *  # noqa: F401,F403
from .equations.codegen import __all__, _commit  # noqa: F401
# the old module's imports
from .equations.codegen import COORDINATES, PARAMETER_NAMES  # noqa: F401
