"""`engines.batching.batched`, the per-state loop every engine method runs a batch through
(docs/engines.md, "The capabilities": q (8,) or (N, 8), and dq, ddq, torques alike), on a
hand-made function whose rows can be told apart: one state is passed through as the
function returns it, a batch is the stack of the rows' results, a 1-D companion (the
torques) is given to every row, a 2-D one row by row, and integers arrive as floats."""

from __future__ import annotations

import numpy as np
import pytest

from engines.batching import batched


def _calls():
    seen = []

    def fn(q, tau):
        seen.append((q.copy(), tau.copy(), q.dtype, tau.dtype))
        return q[:2] * 10 + tau[:2]          # a row's own result, told apart by its q

    return fn, seen


def test_one_state_is_passed_through_as_floats_and_returned_as_the_function_gives_it():
    fn, seen = _calls()
    out = batched(fn, [1, 2, 3, 4, 5, 6, 7, 8], [0, 1, 0])
    assert np.array_equal(out, [10.0, 21.0]) and out.shape == (2,)
    assert len(seen) == 1 and seen[0][2] == np.float64 and seen[0][3] == np.float64
    assert batched(lambda q: float(q.sum()), np.arange(8)) == 28.0      # a scalar stays one


def test_a_batch_is_each_rows_result_stacked_in_order_with_a_1d_companion_for_every_row():
    fn, seen = _calls()
    q = np.arange(24).reshape(3, 8)
    out = batched(fn, q, [0.5, 0.25, 0.0])
    assert out.shape == (3, 2)
    assert np.array_equal(out, [[0.5, 10.25], [80.5, 90.25], [160.5, 170.25]])
    assert [s[0][0] for s in seen] == [0.0, 8.0, 16.0]          # rows in order, one call each
    assert all(np.array_equal(s[1], [0.5, 0.25, 0.0]) for s in seen)
    assert all(s[2] == np.float64 and s[3] == np.float64 for s in seen)


def test_a_2d_companion_is_given_row_by_row():
    fn, seen = _calls()
    q = np.zeros((2, 8))
    tau = [[1, 2, 3], [4, 5, 6]]
    out = batched(fn, q, tau)
    assert np.array_equal(out, [[1.0, 2.0], [4.0, 5.0]])
    assert [s[1].tolist() for s in seen] == [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]


def test_a_batch_of_one_state_is_still_a_batch():
    fn, _ = _calls()
    out = batched(fn, np.ones((1, 8)), [0, 0, 0])
    assert out.shape == (1, 2)


def test_a_companion_with_the_wrong_number_of_rows_is_refused_by_numpy():
    fn, _ = _calls()
    with pytest.raises(ValueError):
        batched(fn, np.zeros((3, 8)), np.zeros((2, 3)))
