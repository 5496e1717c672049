"""The reference bicycle's parameters, by job (each module imports only those above it):

* ``schema``: the 30 names, their units, meanings and bounds, the errors, and the value checks;
* ``benchmark``: Meijaard et al. (2007) Table 1, its checks and the formulas to and from the
  model's values (plain values: no dataclass, no file);
* ``values``: :class:`Parameters`, the validated frozen set, and its ways to and from Table 1;
* the file formats, the only modules that import both the dataclass and the benchmark:
  ``model_file`` (the reference model's TOML layout, read and written), ``benchmark_files``
  (Table 1's own .txt/.json/.toml files: read, import, export) and ``loading`` (the named
  models, any file by what it holds, ``resolve_model``).

The TOML files beside these modules (``thesis.toml``, ``benchmark.toml``) are the named models'
(package data). The older flat modules ``reference_model.params``, ``reference_model.benchmark``
and ``reference_model.benchmark_files`` re-export from here.
"""

from .benchmark import (BENCHMARK_DESCRIPTIONS, BENCHMARK_NAMES, TABLE1, Table1,
                        reference_parameters, table1_from_mapping)
from .benchmark_files import (BENCHMARK_FORMATS, BenchmarkFile, ImportedBicycle, benchmark_text,
                              import_benchmark, parse_benchmark_text, read_benchmark_file,
                              write_benchmark, write_import)
from .loading import (BENCHMARK_FILE, NAMED_MODELS, PARAMETERS_DIR, THESIS_FILE, load_parameters,
                      resolve_model)
from .model_file import parameters_from_mapping, toml_text
from .schema import (BODY_NAMES, CONTACT_MODELS, PARAMETER_BOUNDS, PARAMETER_DESCRIPTIONS,
                     PARAMETER_GROUPS, PARAMETER_NAMES, PARAMETER_UNITS, TRIANGLE_MODES,
                     ParameterError, ParameterWarning, TriangleInequalityError)
from .values import Parameters, attach_benchmark, parameters_from_benchmark, to_benchmark

__all__ = [
    "BENCHMARK_DESCRIPTIONS", "BENCHMARK_FILE", "BENCHMARK_FORMATS", "BENCHMARK_NAMES",
    "BODY_NAMES", "BenchmarkFile", "CONTACT_MODELS", "ImportedBicycle", "NAMED_MODELS",
    "PARAMETERS_DIR", "PARAMETER_BOUNDS", "PARAMETER_DESCRIPTIONS", "PARAMETER_GROUPS",
    "PARAMETER_NAMES", "PARAMETER_UNITS", "ParameterError", "ParameterWarning", "Parameters",
    "TABLE1", "THESIS_FILE", "TRIANGLE_MODES", "Table1", "TriangleInequalityError",
    "attach_benchmark", "benchmark_text", "import_benchmark", "load_parameters",
    "parameters_from_benchmark", "parameters_from_mapping", "parse_benchmark_text",
    "read_benchmark_file", "reference_parameters", "resolve_model", "table1_from_mapping",
    "to_benchmark", "toml_text", "write_benchmark", "write_import",
]
