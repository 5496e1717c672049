"""The thesis bicycle: minimal-coordinate model, derived with sympy, evaluated by generated C.

    from reference_model import load_model
    model = load_model("thesis")        # or "thesis-disc", or a path to a .toml file
    model.mass_matrix(q); model.forward_acceleration(q, dq, torques)
"""

from .names import BODY_NAMES, COORDINATES, TORQUE_NAMES
from .model import (CONSTRAINT_NAMES, DEPENDENT, INDEPENDENT, Model, ModelEvaluationError,
                    load_model)
from .parameters import NAMED_MODELS, ParameterError, Parameters, load_parameters, resolve_model

__all__ = [
    "BODY_NAMES", "CONSTRAINT_NAMES", "COORDINATES", "DEPENDENT", "INDEPENDENT", "NAMED_MODELS",
    "Model", "ModelEvaluationError", "ParameterError", "Parameters", "TORQUE_NAMES",
    "load_model", "load_parameters", "resolve_model",
]
