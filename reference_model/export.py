"""Where the bicycle's exports (URDF, MJCF, JSON) used to be written; the code is now in the
package ``reference_model/exports/`` (``description``: the model as plain data and JSON;
``urdf``; ``mjcf``; ``writer``: ``export_model``). This module re-exports its old names.

    from reference_model.export import export_model
    export_model("thesis", "urdf", "bicycle.urdf")       # or "mjcf", "json"; a name or a .toml file
"""

from .exports import *  # noqa: F401,F403
from .exports import __all__  # noqa: F401
# names the old module had by importing them, so every old import still works
from .names import BODY_NAMES, COORDINATES, TORQUE_NAMES  # noqa: F401
from .parameters import PARAMETER_NAMES, Parameters, resolve_model  # noqa: F401
