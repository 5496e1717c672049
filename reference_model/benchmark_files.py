"""Where the files of Meijaard et al. (2007) benchmark parameters used to be read and written;
the code is now ``reference_model/parameters/benchmark_files.py``. This module re-exports it.
"""

from .parameters.benchmark_files import *  # noqa: F401,F403
from .parameters.benchmark_files import __all__  # noqa: F401
# names the old module had by importing them, so every old import still works
from .parameters.benchmark_files import (BENCHMARK_DESCRIPTIONS, BENCHMARK_NAMES,  # noqa: F401
                                         ParameterError, Parameters, float_text,
                                         parameters_from_benchmark, parameters_from_mapping,
                                         to_benchmark, toml_text)
