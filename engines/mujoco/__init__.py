"""The thesis bicycle in MuJoCo: its tree from the MJCF export, MuJoCo's soft wheel-ground contact."""

from .engine import MujocoEngine

__all__ = ["MujocoEngine"]
