"""The checked inputs of an engine's own time loop (`engines.stepping`), on hand-made
scenarios: the output grid cut at ``t_end`` (a grid time computed as 3 x 0.1 is
0.30000000000000004, so asking for t_end = 0.3 must still keep it: the 1e-12 allowance),
the fall limit, and the fixed step that must land on every output sample, each refused in the
one line the user reads, with the fix worked out by hand here."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from engines.base import CapabilityError, EngineUsageError
from engines.stepping import forward_grid, refuse_fork_axis_contact, steps_per_sample
from reference_model.scenarios import Scenario

FORWARD = Scenario("coast", "", "forward", grid=(0.0, 0.01, 101))   # 0 to 1 s
COARSE = Scenario("coarse", "", "forward", grid=(0.0, 0.1, 11))     # 0 to 1 s


def test_the_whole_grid_without_t_end_and_the_fall_limit_as_a_float():
    grid, fall = forward_grid(FORWARD, 1, None, "MuJoCo")
    assert np.array_equal(grid, FORWARD.t) and grid.size == 101
    assert fall == 1.0 and type(fall) is float


def test_t_end_on_a_grid_time_keeps_that_sample_despite_its_rounding():
    assert COARSE.t[3] > 0.3                    # the grid's own time is above the asked one
    grid, _ = forward_grid(COARSE, 0.5, 0.3, "MuJoCo")
    assert grid.size == 4 and grid[-1] == pytest.approx(0.3)
    grid, _ = forward_grid(COARSE, 0.5, 0.35, "MuJoCo")      # between samples: cut below
    assert grid.size == 4
    grid, _ = forward_grid(FORWARD, 0.5, 0.01, "MuJoCo")     # two samples: enough
    assert grid.size == 2


def test_t_end_leaving_one_sample_is_refused():
    with pytest.raises(EngineUsageError) as err:
        forward_grid(FORWARD, 0.5, 0.005, "MuJoCo")
    assert str(err.value) == "t_end = 0.005 leaves fewer than 2 grid samples"


@pytest.mark.parametrize("fall", [0, 0.0, -0.2, float("inf"), float("nan"), "0.5", None, True])
def test_a_fall_limit_that_is_not_a_positive_finite_angle_is_refused(fall):
    with pytest.raises(EngineUsageError) as err:
        forward_grid(FORWARD, fall, None, "MuJoCo")
    assert str(err.value) == f"fall_limit must be a positive angle in rad; got {fall!r}"


def test_an_inverse_scenario_is_refused_naming_it_and_the_engine():
    with pytest.raises(EngineUsageError) as err:
        forward_grid(Scenario("steer", "", "inverse"), 0.5, None, "DART")
    assert str(err.value) == ("scenario 'steer' is an inverse scenario; DART runs only forward "
                              "scenarios")


def test_steps_per_sample_when_the_step_divides_the_interval():
    assert steps_per_sample(0.001, 0.01, 1.0, "MuJoCo", "timestep") == 10
    assert steps_per_sample(0.01, 0.01, 1.0, "MuJoCo", "timestep") == 1
    assert steps_per_sample(0.0025, 0.01, 6.28, "MuJoCo", "timestep") == 4


def test_a_step_that_misses_the_samples_is_refused_with_the_two_nearest_steps_that_land():
    with pytest.raises(EngineUsageError) as err:
        steps_per_sample(0.003, 0.01, 1.0, "MuJoCo", "timestep")
    # 0.01 / 0.003 = 3.33: 3 or 4 steps per sample, 0.01/3 s or 0.01/4 s
    assert str(err.value) == (
        "MuJoCo timestep = 0.003 s must divide the output interval 0.01 s and the run's duration "
        "1 s (the steps must land on the output samples); fix: timestep=0.003333333333 or 0.0025")


def test_a_step_longer_than_the_interval_is_refused():
    with pytest.raises(EngineUsageError) as err:
        steps_per_sample(0.02, 0.01, 1.0, "Drake", "time_step")
    assert str(err.value).endswith("fix: time_step=0.01 or 0.005")


def test_a_step_that_divides_the_interval_but_not_the_run_is_refused():
    with pytest.raises(EngineUsageError, match=r"^DART step = 0\.005 s must divide"):
        steps_per_sample(0.005, 0.01, 0.0125, "DART", "step")   # 2.5 steps in the run


def test_the_fork_axis_contact_is_a_declared_limitation_naming_engine_and_model():
    engine = SimpleNamespace(name="mine", capabilities=frozenset({"mass_matrix"}),
                             model=SimpleNamespace(name="thesis"))
    with pytest.raises(CapabilityError) as err:
        refuse_fork_axis_contact(engine)
    assert str(err.value) == (
        "engine 'mine' cannot simulate model 'thesis': its forward runs approximate the "
        "rolling-disc contact, and this model has the thesis's fork-axis front contact; use a "
        "disc-contact model (thesis-disc, benchmark)")
    engine = SimpleNamespace(name="mine", capabilities=frozenset({"simulate"}),
                             model=SimpleNamespace(name="thesis-disc"))
    assert refuse_fork_axis_contact(engine) is None


def test_the_step_the_refusal_suggests_is_accepted_even_on_a_long_run():
    # the fix is printed to 10 significant digits: 0.003333333333 is 3.3e-13 s short of
    # 0.01/3, 1e-10 relative (within the 1e-9 allowance); over a 100 s run its 30000 steps
    # end 1e-8 s early, within 1e-9 x 100 s
    assert steps_per_sample(0.003333333333, 0.01, 1.0, "MuJoCo", "timestep") == 3
    assert steps_per_sample(0.003333333333, 0.01, 100.0, "MuJoCo", "timestep") == 3


def test_a_step_off_by_a_part_in_1e8_is_refused():
    # 0.0033333333 (8 digits) misses 0.01/3 by 3.3e-11 s: its 3 steps miss the sample by
    # 1e-10 s, 1e-8 of the interval, above the 1e-9 allowance (a run of one interval, so that
    # the run's own check, 1e-9 s on runs up to 1 s, does not refuse it first)
    with pytest.raises(EngineUsageError, match="must divide the output interval"):
        steps_per_sample(0.0033333333, 0.01, 0.01, "MuJoCo", "timestep")
    with pytest.raises(EngineUsageError, match="must divide the output interval"):
        steps_per_sample(0.0033333333, 0.01, 1.0, "MuJoCo", "timestep")


def test_a_step_that_fits_the_run_but_not_the_interval_is_refused():
    # 0.003 s x 10 = 0.03 s, the whole run, but 0.01 s is 3.33 of its steps: samples missed
    with pytest.raises(EngineUsageError, match="must divide the output interval"):
        steps_per_sample(0.003, 0.01, 0.03, "MuJoCo", "timestep")
