"""What the engine adapters' edge tests share (tests/test_dart_engine_edges.py,
tests/test_drake_engine_edges.py): the singular state and the closeness check against the
reference's terms."""

from __future__ import annotations

import numpy as np

__all__ = ["SINGULAR", "close"]

#: the flat bicycle (lean pi/2) with its frame pitched by pi/2: the thesis's constrained system
#: is singular there (the reference's forward reports status 1) and the LU factorization of an
#: engine's 13 x 13 KKT matrix meets an exactly zero pivot (np.linalg.solve raises)
SINGULAR = np.array([0.0, 0.0, 0.0, np.pi / 2, 0.0, np.pi / 2, 0.0, 0.0])


def close(mine, theirs, rel):
    """``mine`` is float64, of ``theirs``'s shape, and within ``rel`` of its largest entry."""
    mine, theirs = np.asarray(mine), np.asarray(theirs)
    assert mine.shape == theirs.shape and mine.dtype == np.float64
    assert np.abs(mine - theirs).max() <= rel * np.abs(theirs).max()
