"""The sweep's budget (comparisons/stages/sweep_budget.py): the cap on bicycles, the time limit
of one bicycle, and the one line said before a sweep starts. Expected values come from the
module's documented rules (its docstring and docs/sweep.md: the cap names --max-bicycles, the
limit is max(120 s, 20 x cost), durations for people) worked out by hand here: each unit's
boundary and the text around each number. Each test names the planted bugs (mutmut's mutants
of the module) it was seen failing on."""

from __future__ import annotations

import math

import pytest

from comparisons.stages.sweep_budget import (DEFAULT_MAX_BICYCLES, LIMIT_FACTOR, LIMIT_FLOOR,
                                             Estimate, SweepTooLarge, bicycle_limit,
                                             count_bicycles, duration, estimate_line,
                                             refuse_huge)


@pytest.mark.parametrize("seconds, text", [
    (0.0, "under a second"), (0.999, "under a second"), (1.0, "1 s"), (40.2, "40 s"),
    (89.4, "89 s"), (90.0, "2 min"), (720.0, "12 min"), (5399.0, "90 min"),
    (5400.0, "1.5 h"), (12600.0, "3.5 h"), (172799.0, "48.0 h"), (172800.0, "2.0 days"),
    (181440.0, "2.1 days"), (10981.0, "3.1 h"), (177121.0, "2.1 days"),
    (math.inf, "an unknown time"), (math.nan, "an unknown time")])
def test_a_duration_is_said_in_the_unit_people_use(seconds, text):
    """Under a second; seconds below 90 s; minutes below 1.5 h; hours (one decimal) below two
    days; days beyond; an infinite or undefined time is unknown. Planted: each threshold moved
    (< for <=, 91, 5401, 172801), minutes by 3600, hours by 60, the decimals dropped, the
    unknown case lost (a crash on inf); an hour of 3601 s or a day of 86401 s (10981 s is
    3.0503 h, 3.0494 with the wrong hour; 177121 s is 2.05001 days, 2.04999 with the wrong
    day: each rounds the other way)."""
    assert duration(seconds) == text


def test_the_cap_refuses_one_bicycle_more_naming_the_option_and_the_number_to_give():
    """Exactly the cap runs; one more is refused in one line naming --max-bicycles with the
    number that would allow it. The default cap is 100 000 (docs/sweep.md). Planted: >= for >
    (the cap itself refused); the message's numbers swapped or lost."""
    refuse_huge(5, 5)
    refuse_huge(DEFAULT_MAX_BICYCLES, DEFAULT_MAX_BICYCLES)
    with pytest.raises(SweepTooLarge) as err:
        refuse_huge(6, 5)
    assert str(err.value) == ("6 bicycles is more than --max-bicycles 5: give fewer (--sample, "
                              "--vary) or raise the cap with --max-bicycles 6 if you mean it")
    assert DEFAULT_MAX_BICYCLES == 100_000
    assert isinstance(err.value, ValueError)


def test_a_bicycles_time_limit_is_twenty_costs_at_least_two_minutes_unless_given():
    """max(120 s, 20 x cost): a cheap bicycle gets the floor (its worker's first bicycle imports
    the engines), a costly one 20 times its cost; --bicycle-timeout replaces either, as a
    float. Planted: min for max; the override ignored; the override returned as given (an
    int)."""
    assert (LIMIT_FLOOR, LIMIT_FACTOR) == (120.0, 20.0)
    assert bicycle_limit(0.1) == 120.0
    assert bicycle_limit(6.0) == 120.0
    assert bicycle_limit(10.0) == 200.0
    assert bicycle_limit(10.0, override=3) == 3.0 and isinstance(bicycle_limit(1, 3), float)
    assert bicycle_limit(10.0, override=0.5) == 0.5


def _estimate(**changes) -> Estimate:
    base = dict(n_bicycles=12, chunks=4, chunks_left=3, bicycles_left=9, cost=0.25,
                measured_on=0, workers=2, limit=120.0)
    return Estimate(**{**base, **changes})


def test_the_expected_time_is_the_cost_of_what_is_left_over_the_workers():
    """cost x bicycles left / workers; an unknown number of workers (None) or none counts as
    one. Planted: the bicycles of the whole sweep for those left; times the workers."""
    assert _estimate().seconds == pytest.approx(0.25 * 9 / 2)
    assert _estimate(workers=None).seconds == pytest.approx(0.25 * 9)
    assert _estimate(workers=0).seconds == pytest.approx(0.25 * 9)


def test_the_estimate_line_of_a_fresh_sweep_on_the_development_table():
    """The whole line for a sweep not started, costed from the development machine's table,
    on two workers: bicycles, chunks and those done, what is left, the expected time as
    'about ...', the cost to three digits, where it comes from, the time limit. Planted: the
    done chunks as those left; 'worker' for two; the source text swapped; the limit's format."""
    line = estimate_line(_estimate(n_bicycles=12000, chunks=40, chunks_left=40,
                                   bicycles_left=12000, cost=0.1234, workers=2, limit=120.0))
    assert line == ("sweep: 12000 bicycles in 40 chunks (0 already done); 12000 to compute, "
                    "about 12 min on 2 workers at 0.123 s a bicycle (the development "
                    "machine's measured cost); each bicycle given up after 120 s")


def test_the_estimate_line_of_a_resumed_sweep_on_one_worker():
    """A resume (cost measured on the rows done), one worker, a time under a second (said
    without 'about'), a limit given in seconds with decimals. Planted: 'workers' for one; the
    measured count lost; 'about under a second'."""
    line = estimate_line(_estimate(measured_on=3, workers=1, bicycles_left=2, cost=0.2,
                                   limit=2.5))
    assert line == ("sweep: 12 bicycles in 4 chunks (1 already done); 2 to compute, under a "
                    "second on 1 worker at 0.2 s a bicycle (measured on the 3 bicycles done); "
                    "each bicycle given up after 2.5 s")


def test_the_estimate_line_before_the_cluster_is_known():
    """Workers not known yet (a cluster not started): 'on one worker', the time for one.
    Planted: the None case said as 'on None workers'."""
    line = estimate_line(_estimate(workers=None, bicycles_left=600, cost=0.1))
    assert "about 60 s on one worker at 0.1 s a bicycle" in line


def test_the_bicycles_are_counted_before_the_spec_is_built():
    """--sample N is N bicycles; a --vary grid is the product of its N's; no --vary and no
    --sample, or an option that does not parse, is None (make_spec then says why). Planted:
    the sum for the product; the sample ignored; a parse error raised here."""
    assert count_bicycles([], 7) == 7
    assert count_bicycles(["m3=80:90:400", "trail=0.05:0.1:300"], None) == 120_000
    assert count_bicycles(["m3=80:90:3"], None) == 3
    assert count_bicycles([], None) is None
    assert count_bicycles(["m3=80:90"], None) is None
    assert count_bicycles(["nope=1:2:3"], None) is None
