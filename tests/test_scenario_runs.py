"""How a scenario is run on the reference (`reference_model.scenarios.runs`): the refusals of
the wrong kind, word for word; the initial state built from the scenario's own fields (its
rates at theta, psi and gamma, kept by the projection); the torques as the scenario gives
them or as the spline of the named scenario's inverse dynamics, checked against that
inverse dynamics run here; and the forward run's settings, which the report prints: the
scenario's constraint handling, Baumgarte gains and fall limit unless the caller overrides
them, and the projection's correction. Short grids (0.1 s): ~1 s in all."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from reference_model.scenarios import SCENARIOS, Scenario
from reference_model.scenarios.runs import (SplineAtTime, initial_state, run_forward,
                                            run_inverse, torque_input)
from reference_model.solvers import consistent_state

COAST = Scenario("coast", "", "forward", grid=(0.0, 0.01, 11),
                 q0=(0.0, 0.0, 0.0, 0.02, 0.0, 0.0, 0.01, 0.0), dq_ind0=(0.1, 18.0, -0.05),
                 torques=(0.5, 0.0, -0.25), constraints="projection", baumgarte=(4.0, 6.0),
                 fall_limit=0.7)


def test_an_inverse_run_of_a_forward_scenario_is_refused(thesis):
    with pytest.raises(ValueError) as err:
        run_inverse(thesis, COAST)
    assert str(err.value) == "scenario 'coast' is a forward scenario; use simulate"


def test_the_initial_state_of_an_inverse_scenario_is_refused(thesis):
    with pytest.raises(ValueError) as err:
        initial_state(thesis, SCENARIOS["check"])
    assert str(err.value) == "scenario 'check' is an inverse scenario; it has no initial state"


def test_the_initial_state_puts_the_scenarios_rates_at_theta_psi_and_gamma(thesis):
    s = initial_state(thesis, COAST)
    dq = np.zeros(8)
    dq[3], dq[4], dq[6] = 0.1, 18.0, -0.05                  # dtheta, dpsi, dgamma by hand
    ref = consistent_state(thesis, np.array(COAST.q0), dq)
    assert np.array_equal(s.q, ref.q) and np.array_equal(s.dq, ref.dq)
    assert (s.dq[3], s.dq[4], s.dq[6]) == (0.1, 18.0, -0.05)  # the projection keeps them
    assert (s.q[3], s.q[6]) == (0.02, 0.01)


def test_constant_torques_are_given_as_the_scenario_has_them(thesis):
    assert torque_input(thesis, COAST) == (0.5, 0.0, -0.25)


def test_a_named_torque_history_is_the_spline_of_that_scenarios_inverse_dynamics(disc):
    sc = dataclasses.replace(COAST, torques="zigzag")
    f = torque_input(disc, sc)
    assert isinstance(f, SplineAtTime)
    ident = run_inverse(disc, SCENARIOS["zigzag"])          # on the model given, not the thesis
    for k in (0, 1, 157, 314, 628):                         # on the knots: the samples
        assert np.allclose(f(float(ident.motion.t[k])), ident.T[k], rtol=0, atol=1e-12)


def test_the_forward_run_takes_the_scenarios_settings_and_records_the_projection(thesis):
    traj = run_forward(thesis, COAST)
    init = initial_state(thesis, COAST)
    assert traj.settings["constraints"] == "projection"
    assert traj.settings["fall_limit"] == 0.7
    assert traj.settings["initial_correction"] == init.describe()
    assert traj.settings["beta_correction"] == init.beta_correction
    assert np.array_equal(traj.q[0], init.q) and traj.t.size == 11
    baum = run_forward(thesis, dataclasses.replace(COAST, constraints="baumgarte"))
    assert baum.settings["constraints"] == "baumgarte" and baum.settings["baumgarte"] == [4.0, 6.0]


def test_the_callers_options_override_the_scenarios(thesis):
    traj = run_forward(thesis, COAST, constraints="none", fall_limit=0.9, rtol=1e-8)
    assert traj.settings["constraints"] == "none"
    assert traj.settings["fall_limit"] == 0.9 and traj.settings["rtol"] == 1e-8


def test_the_torques_of_a_named_history_come_from_the_model_asked(thesis, disc):
    """torques_from: an engine without inverse dynamics has the reference make them; the
    history then is the reference's (the disc model's zigzag differs from the thesis's)."""
    sc = dataclasses.replace(COAST, torques="zigzag", q0=(0.0,) * 8, dq_ind0=(0.0, 18.0, 0.0))
    own = run_forward(thesis, sc)
    other = run_forward(thesis, sc, torques_from=disc)
    assert not np.allclose(own.q[-1], other.q[-1], rtol=0, atol=1e-12)
    again = run_forward(thesis, sc, torques_from=thesis)
    assert np.array_equal(own.q, again.q)


def test_the_inverse_run_integrates_beta_unless_asked_to_reproject(disc):
    """The thesis integrates the dependent coordinates (its beta drifts off [rD]_z = 0 by the
    integrator's error); reproject=True solves beta from the constraint at every evaluation.
    The default is the thesis's way: the run is the integrated one, bit for bit."""
    from reference_model.solvers import inverse_dynamics, inverse_kinematics
    sc = dataclasses.replace(SCENARIOS["zigzag"], grid=(0.0, 0.01, 101))
    integrated = inverse_dynamics(disc, inverse_kinematics(disc, sc.motion, sc.t,
                                                           reproject=False))
    solved = run_inverse(disc, sc, reproject=True)
    default = run_inverse(disc, sc)
    assert np.array_equal(default.motion.q, integrated.motion.q)
    assert not np.array_equal(solved.motion.q, integrated.motion.q)
