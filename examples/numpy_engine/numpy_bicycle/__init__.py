"""A plain-numpy bicycle engine for bicycle-xval (see engine.py)."""

from .engine import BuggyNumpyEngine, NumpyEngine

__all__ = ["BuggyNumpyEngine", "NumpyEngine"]
