"""The thesis bicycle in MuJoCo: its tree from the MJCF export, its soft wheel-ground contact."""

from .engine import MujocoEngine

__all__ = ["MujocoEngine"]
