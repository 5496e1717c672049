"""The thesis bicycle in Exudyn: a minimal-coordinate kinematic-tree build (`tree.py`), a
redundant rigid-body build (`redundant.py`), the map from body poses back to the thesis's q
(`mapping.py`), and the engine that runs scenarios on either (`engine.py`)."""

from .engine import ExudynEngine

__all__ = ["ExudynEngine"]
