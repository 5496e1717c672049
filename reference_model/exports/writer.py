"""Writing an export: :func:`export_model`, a model (named, a parameter file or `Parameters`) in
one of :data:`FORMATS` to a file, atomically.

    from reference_model.export import export_model
    export_model("thesis", "urdf", "bicycle.urdf")       # or "mjcf", "json"; a name or a .toml file
"""

from __future__ import annotations

import os
from pathlib import Path

from ..parameters.benchmark_files import _write_atomically
from ..parameters.loading import resolve_model
from ..parameters.values import Parameters
from .description import json_text
from .mjcf import mjcf_text
from .urdf import urdf_text

__all__ = ["FORMATS", "export_model"]

FORMATS = ("urdf", "mjcf", "json")


def export_model(model: str | os.PathLike[str] | Parameters, fmt: str, out: str | os.PathLike[str]) -> Path:
    """Write the model (a named model, a parameter .toml file or `Parameters`) as ``fmt``
    ('urdf', 'mjcf' or 'json') to ``out``; returns the path. MJCF gets the default contact
    settings (`mjcf.MjcfSettings`). The file is written to a temporary file
    beside ``out`` and renamed, so no half-written file is ever left. Raises ValueError for an
    unknown format, `ParameterError` for a bad model, OSError for an unwritable path."""
    if fmt not in FORMATS:
        raise ValueError(f"format {fmt!r} is not one of {', '.join(FORMATS)}; use --format "
                         f"{', '.join(FORMATS[:-1])} or {FORMATS[-1]}")
    p = resolve_model(model)
    text = {"urdf": urdf_text, "mjcf": mjcf_text, "json": json_text}[fmt](p)
    out = Path(out)
    _write_atomically(out, text, parents=False)
    return out
