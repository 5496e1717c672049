"""Where the numpy backend's KKT solves used to live; the code is now
``reference_model/equations/numpy_runtime.py``. This module re-exports it.
"""

from .equations.numpy_runtime import *  # noqa: F401,F403
from .equations.numpy_runtime import __all__  # noqa: F401
