"""The `Scenario` record built at run time, as a user's Python or a scenario file builds it: the
quantities compared by default for each kind (written here as docs/report.md names them, not
read from the module), an explicit list kept, an unknown quantity refused in one line naming
it and the choices, and the grid's duration and times (the thesis grid is 0:0.01:2*pi, 629
samples)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from reference_model.scenarios import Scenario


def test_an_inverse_scenario_compares_mass_matrix_torques_and_multipliers_by_default():
    sc = Scenario("mine", "a user's inverse scenario", "inverse")
    assert sc.compared == ("mass_matrix", "torques", "multipliers")


def test_a_forward_scenario_compares_mass_matrix_trajectory_and_residual_by_default():
    sc = Scenario("mine", "a user's forward scenario", "forward")
    assert sc.compared == ("mass_matrix", "trajectory", "constraint_residual")


def test_an_explicit_list_of_quantities_is_kept_as_given():
    sc = Scenario("mine", "", "forward", compared=("trajectory",))
    assert sc.compared == ("trajectory",)
    sc = Scenario("mine", "", "inverse", compared=("multipliers", "mass_matrix"))
    assert sc.compared == ("multipliers", "mass_matrix")


def test_an_unknown_quantity_is_refused_naming_it_the_scenario_and_the_choices():
    with pytest.raises(ValueError) as err:
        Scenario("mine", "", "forward", compared=("trajectory", "energy", "torque"))
    assert str(err.value) == (
        "scenario 'mine': unknown compared quantity 'energy'; choose from mass_matrix, torques, "
        "multipliers, trajectory, constraint_residual")


def test_duration_and_times_of_a_grid():
    sc = Scenario("mine", "", "forward", grid=(0.5, 0.25, 5))
    assert sc.duration == 1.0                       # 4 steps of 0.25 s
    assert np.array_equal(sc.t, [0.5, 0.75, 1.0, 1.25, 1.5])
    thesis = Scenario("mine", "", "inverse")        # the thesis grid 0:0.01:2*pi
    assert thesis.t.shape == (629,) and thesis.t[0] == 0.0
    assert math.isclose(thesis.duration, 6.28) and math.isclose(thesis.t[-1], 6.28)
