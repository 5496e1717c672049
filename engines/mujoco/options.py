"""Options of the MuJoCo engine given as text (the CLI's ``--engine-option key=value``)."""

from __future__ import annotations

from reference_model.export_mjcf import MjcfSettings

from ..base import EngineUsageError


def tuple_option(name: str, value):
    """solref/solimp as given: a sequence, or text with commas or spaces (the CLI's)."""
    if isinstance(value, str):
        parts = value.replace(",", " ").split()
        try:
            return tuple(float(v) for v in parts)
        except ValueError:
            example = ",".join(map(repr, getattr(MjcfSettings(), name)))
            raise EngineUsageError(f"MuJoCo option {name} = {value!r}: not a list of numbers; "
                                   f"fix: e.g. {name}={example}") from None
    return value
