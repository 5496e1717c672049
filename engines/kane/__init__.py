"""Moore's Whipple bicycle by Kane's method (sympy.physics.mechanics) as an engine."""

from .engine import KaneEngine, moore_parameters

__all__ = ["KaneEngine", "moore_parameters"]
