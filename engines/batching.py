"""One state or a batch: the engines' per-state loop over a batch (docs/engines.md, "The
capabilities": every method takes q (8,) or (N, 8), and dq, ddq, torques alike)."""

from __future__ import annotations

import numpy as np

__all__ = ["batched"]


def batched(fn, *arrays):
    """``fn`` of one state's arrays, on one state or on each row of a batch: the first array
    decides (1-D: one state, returned as ``fn`` gives it; 2-D: N states, the others broadcast to
    N rows of their own width), and the results are stacked."""
    if np.ndim(arrays[0]) == 1:
        return fn(*(np.asarray(a, dtype=float) for a in arrays))
    n = np.shape(arrays[0])[0]
    arrs = [np.broadcast_to(np.asarray(a, dtype=float), (n, np.shape(a)[-1])) for a in arrays]
    return np.array([fn(*row) for row in zip(*arrs)])
