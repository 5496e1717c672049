"""Where the Meijaard et al. (2007) benchmark bicycle used to live; the code is now in the
package ``reference_model/parameters/``: ``benchmark`` (Table 1, its checks, the formulas to
and from the model's values), ``values`` (``parameters_from_benchmark``, ``to_benchmark``,
``attach_benchmark``) and ``model_file`` (``toml_text``, the parameter file's writer).
This module re-exports its old names; ``python -m reference_model.benchmark --write``
regenerates ``reference_model/parameters/benchmark.toml`` and ``--check`` compares
(``reference_model.parameters.loading.main``).
"""

import sys

from .parameters.benchmark import (BENCHMARK_DESCRIPTIONS, BENCHMARK_NAMES,  # noqa: F401
                                   FORMULAS_MODULE, TABLE1, Table1, reference_parameters,
                                   table1_from_mapping)
from .parameters.loading import BENCHMARK_FILE, main, named_model_text  # noqa: F401
# names the old module had by importing them, so every old import still works
from .parameters.schema import (MEMORY_SOURCE, PARAMETER_DESCRIPTIONS,  # noqa: F401
                                PARAMETER_GROUPS, PARAMETER_NAMES, PARAMETER_UNITS,
                                ParameterError, TriangleInequalityError)
from .parameters.values import Parameters  # noqa: F401
from .parameters.model_file import float_text, toml_string, toml_text  # noqa: F401
from .parameters.values import (attach_benchmark, parameters_from_benchmark,  # noqa: F401
                                to_benchmark)

__all__ = [
    "BENCHMARK_DESCRIPTIONS", "BENCHMARK_FILE", "BENCHMARK_NAMES", "TABLE1", "Table1",
    "attach_benchmark", "parameters_from_benchmark", "reference_parameters",
    "table1_from_mapping", "to_benchmark", "toml_text",
]

if __name__ == "__main__":
    sys.exit(main())
