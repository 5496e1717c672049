"""Numbers in every exported file: the shortest text that reads back as the same double
(deterministic, exact), the parameter file's ``float_text``."""

from __future__ import annotations

from collections.abc import Iterable

from ..parameters.model_file import float_text

__all__ = ["float_text", "vec"]


def vec(v: Iterable[float]) -> str:
    """A vector as its entries' :func:`float_text`, space-separated (URDF and MJCF attributes)."""
    return " ".join(float_text(x) for x in v)
