"""Where the reference bicycle's parameters used to live; the code is now in the package
``reference_model/parameters/``, by job (``schema``: names, units, bounds, errors and checks;
``values``: the :class:`Parameters` dataclass; ``model_file``: the TOML format; ``loading``:
named models, ``load_parameters``, ``resolve_model``). This module re-exports its old names.
"""

from .parameters.loading import *  # noqa: F401,F403
from .parameters.model_file import *  # noqa: F401,F403
from .parameters.schema import *  # noqa: F401,F403
from .parameters.schema import MEMORY_SOURCE  # noqa: F401
from .parameters.schema import closest as _closest  # noqa: F401 (comparisons' sweep spec uses it)
from .parameters.values import *  # noqa: F401,F403

__all__ = [
    "BENCHMARK_FILE",
    "BODY_NAMES",
    "CONTACT_MODELS",
    "NAMED_MODELS",
    "PARAMETERS_DIR",
    "PARAMETER_DESCRIPTIONS",
    "PARAMETER_GROUPS",
    "PARAMETER_NAMES",
    "PARAMETER_UNITS",
    "PARAMETER_BOUNDS",
    "ParameterError",
    "ParameterWarning",
    "Parameters",
    "THESIS_FILE",
    "TRIANGLE_MODES",
    "TriangleInequalityError",
    "load_parameters",
    "parameters_from_mapping",
    "resolve_model",
]
