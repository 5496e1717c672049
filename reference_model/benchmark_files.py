"""Where the files of Meijaard et al. (2007) benchmark parameters used to be read and written;
the code is now ``reference_model/parameters/benchmark_files.py``. This module re-exports it.
"""

from .parameters.benchmark_files import *  # noqa: F401,F403
from .parameters.benchmark_files import __all__  # noqa: F401
