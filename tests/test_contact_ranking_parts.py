"""The side-by-side ranking of the soft-contact engines (comparisons/judgments/contact_ranking.py)
held to the edges of its contract that tests/test_soft_contact_engines.py leaves open.

`shared_horizon` takes a time within a billionth of a grid step of a sample to be that sample
(the convention tests/test_soft_contact_engines.py states: "within", so the band is closed): a
pull exactly 1e-9 step after a sample is at that sample, a cap exactly 1e-9 step before a sample
keeps it; a one-sample grid's step is 1 s; and a single-precision grid is read at its values, not
in single precision (a billionth of a step is far below float32's resolution). `contact_row`
says a run reached the horizon when it does not end before it (docs/report.md: "a run that ends
before it comes last"), to 1e-9 s of round-off, on any grid: on a coarse (2 s) output grid, where
the comparison functions put both ends below on the horizon's sample, a run ending 1e-9 s short
reaches it and one ending 1.5e-9 s short does not. Expected values are the grid's own samples
and hand-set drifts. Each test names the planted bugs (mutmut's survivors of the module's
measurement) it fails on. ~0.1 s.
"""

from __future__ import annotations

import numpy as np
import pytest

from comparisons.judgments.contact_ranking import contact_row, rank, shared_horizon
from reference_model.solvers import Trajectory

T = np.round(np.arange(61) * 0.01, 12)       # 0 .. 0.6 s on the 0.01 s grid
DT = float(T[1] - T[0])


# -- shared_horizon: the round-off band of a billionth of a step ----------------------------------

def test_a_pull_exactly_a_billionth_of_a_step_after_a_sample_is_at_that_sample():
    """The ground must pull exactly 1e-9 step after t = 0.44 s: within the round-off band, so the
    pull is at 0.44 s and the last sample before it is 0.43 s (one 1.5e-9 step after it leaves
    0.44 s before the pull). Planted: the samples before the pull taken with <= (0.44 s kept)."""
    t44, t43 = float(T[44]), float(T[43])
    pull = t44 + 1e-9 * DT
    assert pull - 1e-9 * DT == t44               # the construction lands on the band's edge
    assert shared_horizon(T, pull, 0.6, 0.6) == t43
    assert shared_horizon(T, t44 + 1.5e-9 * DT, 0.6, 0.6) == t44


def test_a_cap_exactly_a_billionth_of_a_step_before_a_sample_keeps_that_sample():
    """A meaningful horizon (or window) exactly 1e-9 step short of t = 0.44 s is 0.44 s up to
    round-off: the shared horizon is 0.44 s, not 0.43 s. Planted: the samples up to the cap taken
    with < (0.44 s dropped)."""
    t44 = float(T[44])
    cap = t44 - 1e-9 * DT
    assert cap + 1e-9 * DT == t44                # the construction lands on the band's edge
    assert shared_horizon(T, None, cap, 0.6) == t44
    assert shared_horizon(T, None, 0.6, cap) == t44
    assert shared_horizon(T, 0.5, cap, 0.6) == t44


def test_a_one_sample_grid_has_a_one_second_step():
    """With one sample (t = 2 s) there is no step to read, and the module takes 1 s: a cap
    0.5e-9 s short of the sample keeps it; one 1.5e-9 s short leaves no grid time at most the
    cap, so there is no shared horizon (refused; today numpy's IndexError). Planted: a 2 s step
    for the one-sample grid (its band of 2e-9 s then took the sample)."""
    one = np.array([2.0])
    assert shared_horizon(one, None, 2.0 - 0.5e-9, 5.0) == 2.0
    with pytest.raises((IndexError, ValueError)):
        shared_horizon(one, None, 2.0 - 1.5e-9, 5.0)


def test_a_single_precision_grid_is_read_at_its_values():
    """A float32 output grid (0 .. 0.6 s by 0.01 s): its samples are exact numbers, read in double
    precision, and the band is a billionth of its step (1e-11 s), far below float32's resolution
    near 0.44 s (3e-8 s). A pull 1.5e-9 step after the sample at 0.44 s is after it (horizon: that
    sample); a cap 1.5e-9 step before it excludes it (horizon: the sample at 0.43 s). Planted: the
    grid kept in float32 (the dtype dropped or None), which rounded both times onto the sample."""
    t32 = (np.arange(61) * 0.01).astype(np.float32)
    t64 = t32.astype(float)
    dt = float(t64[1] - t64[0])
    t44, t43 = float(t64[44]), float(t64[43])
    assert shared_horizon(t32, t44 + 1.5e-9 * dt, 0.6, 0.6) == t44
    assert shared_horizon(t32, None, t44 - 1.5e-9 * dt, 0.6) == t43


# -- contact_row: reaching the horizon, to 1e-9 s, on a coarse grid ------------------------------

COARSE = np.array([0.0, 2.0, 4.0, 6.0, 8.0])      # a 2 s output grid: its band is 2e-9 s
DRIFT = np.array([0.0, 1e-3, 2e-3, 3e-3, 4e-3])    # the run's yc at each sample (m)


def _traj(t, yc):
    t = np.asarray(t, dtype=float)
    q = np.zeros((t.size, 8))
    q[:, 1] = yc
    z = np.zeros_like(q)
    diag = {"slip_speed_rear": np.full(t.size, 1e-3), "slip_speed_front": np.zeros(t.size),
            "penetration_rear": np.zeros(t.size), "penetration_front": np.zeros(t.size)}
    return Trajectory(t=t, q=q, dq=z, ddq=z, C=np.zeros((t.size, 5)), T=np.zeros((t.size, 3)),
                      status="completed", message="", t_end=float(t[-1]), diagnostics=diag)


REF = _traj(COARSE, np.zeros(COARSE.size))


def _ending(end):
    """The drifting run on the coarse grid, its last sample (the horizon's, 6 s) moved to end."""
    return _traj(np.array([0.0, 2.0, 4.0, end]), DRIFT[:4])


def test_a_run_ending_the_round_off_short_of_the_horizon_reaches_it():
    """Horizon 6 s; the run's last sample is exactly 1e-9 s before it (the round-off the row
    allows): it reaches the horizon, and its error there is its drift at that sample, 3e-3 m.
    Planted: reaching tested with > (the edge of the band excluded: not reached, no error)."""
    end = 6.0 - 1e-9
    row = contact_row("edge", "Edge", REF, _ending(end), horizon=6.0, seconds=0.1)
    assert row.reached and row.error_at_horizon == 3e-3
    assert row.error_max == 3e-3 and row.simulated_s == end


def test_a_run_ending_before_the_horizon_does_not_reach_it_even_on_its_grid_sample():
    """Horizon 6 s; the run ends 1.5e-9 s before it. On the 2 s grid that last sample lies within
    a billionth of a step (2e-9 s) of the horizon's sample, so the trajectory comparison can read
    an error there, but the run ends before the horizon by more than the 1e-9 s round-off: not
    reached, no error at the horizon, ranked after a run that reaches it whatever its numbers
    (docs/report.md). It is still measured up to its own end (error max 3e-3 m). Planted: the
    'and' of reaching written 'or' (every non-empty run reached), a band of 1 s instead of 1e-9 s,
    the error at the horizon read even when the run did not reach it."""
    short = contact_row("short", "Short", REF, _ending(6.0 - 1.5e-9), horizon=6.0, seconds=0.1)
    assert not short.reached and short.error_at_horizon is None
    assert short.error_max == 3e-3
    # a run that reaches 6 s with twice the drift still ranks first
    worse = contact_row("worse", "Worse", REF, _traj(COARSE, 2 * DRIFT), horizon=6.0, seconds=0.1)
    assert worse.reached and worse.error_at_horizon == 6e-3
    assert [(r.rank, r.row.engine) for r in rank([short, worse])] == [(1, "worse"), (2, "short")]
