"""The bicycle for other tools, by format (each module imports only those above it):

* ``text``: numbers as exact text, shared by the writers;
* ``description``: the engine-neutral model as plain data (the thesis's tree, bodies, rolling
  contact, loads) and its JSON;
* ``urdf``: the rigid-body tree as URDF (no contact: a comment says so);
* ``mjcf``: the tree with MuJoCo's wheel-ground contact (`MjcfSettings`);
* ``writer``: :func:`export_model`, any of them to a file, atomically.

    from reference_model.export import export_model
    export_model("thesis", "urdf", "bicycle.urdf")       # or "mjcf", "json"; a name or a .toml file

The older modules ``reference_model.export`` and ``reference_model.export_mjcf`` re-export
from here.
"""

from .description import COORDINATE_MEANING, SCHEMA, json_text, model_description
from .mjcf import MjcfSettings, massless_links, mjcf_text
from .urdf import urdf_text
from .writer import FORMATS, export_model

__all__ = [
    "COORDINATE_MEANING", "FORMATS", "MjcfSettings", "SCHEMA", "export_model", "json_text",
    "massless_links", "mjcf_text", "model_description", "urdf_text",
]
