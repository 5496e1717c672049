"""The energy judgment's pure parts (comparisons/judgments/energy.py) on hand-made inputs: which
scenarios can do work (a torque of any one of the three, as constants, samples or a named
function), the free-roll scenario's start (the stability study's: theta = gamma = pi/16, no
torques, one sample per millisecond so an Exudyn run's every step is seen), the drift's edge
cases, and the settings phrase of the energy table. Expected values are written from the
docstrings and the IFToMM definition, not from the code. Pure, ~20 ms."""

import math

import numpy as np
import pytest

from comparisons.judgments.energy import (FREE_ROLL_DURATION, applies_torques,
                                          describe_drift, describe_run_settings, energy_drift,
                                          free_roll_scenario)
from reference_model.scenarios import TorqueSamples
from reference_model.solvers import Trajectory


def _with(torques):
    import dataclasses
    return dataclasses.replace(free_roll_scenario(), torques=torques)


@pytest.mark.parametrize("torques, works", [
    ((0.0, 0.0, 0.0), False), ((0.0, 0.0, 1e-3), True), ((-2.0, 0.0, 0.0), True),
    ("inverse", True),
    (TorqueSamples(t=(0.0, 2.0), T=((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))), False),
    (TorqueSamples(t=(0.0, 2.0), T=((0.0, 0.0, 0.0), (0.0, 0.5, 0.0))), True),
])
def test_a_scenario_applies_torques_when_any_can_do_work(torques, works):
    assert applies_torques(_with(torques)) is works


def test_the_free_roll_starts_as_the_stability_study_and_samples_every_millisecond():
    sc = free_roll_scenario()
    lean = math.pi / 16
    assert sc.q0 == (0, 0, 0, lean, 0, 0, lean, 0)
    assert sc.dq_ind0 == (0.0, 10.0, 0.0) and sc.torques == (0.0, 0.0, 0.0)
    t0, dt, n = sc.grid
    assert (t0, dt, n) == (0.0, 1e-3, 1001) and FREE_ROLL_DURATION == 1.0
    assert sc.name == "free-roll-psid10" and sc.model == "thesis-disc"
    assert sc.constraints == "projection" and sc.kind == "forward"
    assert free_roll_scenario(psi_dot=4.5, duration=0.5, sample=0.01).grid == (0.0, 0.01, 51)


class _Toy:
    """T = sum(dq^2)/2, V = q[0] (energies chosen by hand)."""

    def kinetic_energy(self, q, dq):
        return 0.5 * (np.asarray(dq) ** 2).sum(axis=-1)

    def potential_energy(self, q):
        return np.asarray(q)[..., 0]


def _traj(q, dq):
    q, dq = np.asarray(q, float), np.asarray(dq, float)
    t = np.arange(float(len(q)))
    return Trajectory(t=t, q=q, dq=dq, ddq=np.zeros_like(q), C=np.zeros((t.size, 5)),
                      T=np.zeros((t.size, 3)), status="completed", message="",
                      t_end=float(t[-1]) if t.size else 0.0)


def test_drift_edge_cases():
    # at rest (T0 = 0): the drift relative to T0 is undefined, said as nan
    d = energy_drift(_Toy(), _traj([[3.0] + [0] * 7, [2.0] + [0] * 7], np.zeros((2, 8))))
    assert math.isnan(d["drift_percent_of_T0"]) and d["drift_percent"] == pytest.approx(100 / 3)
    assert d["samples"] == 2 and d["t_end"] == 1.0 and d["E_end_minus_E0"] == -1.0
    with pytest.raises(ValueError, match="E0 = 0"):
        energy_drift(_Toy(), _traj(np.zeros((2, 8)), np.zeros((2, 8))))
    with pytest.raises(ValueError, match="no samples"):
        energy_drift(_Toy(), _traj(np.zeros((0, 8)), np.zeros((0, 8))))


def test_the_settings_phrase_names_the_step_and_the_scheme():
    assert describe_run_settings({}) == "its defaults"
    assert describe_run_settings({"step": 1e-3}) == "h = 0.001"
    assert describe_run_settings({"step": 1e-3, "solver_type": "GeneralizedAlpha",
                                  "spectral_radius": 0.8}) == \
        "h = 0.001, GeneralizedAlpha spectral radius 0.8"
    assert describe_run_settings({"solver_type": "RK44"}) == "RK44"
    assert describe_run_settings({"integrator": "DOP853", "rtol": 1e-10}) == "DOP853 rtol 1e-10"
    assert describe_run_settings({"integrator": "RK4"}) == "RK4"
    # a generalized-alpha run names its solver, not an integrator key it may also carry
    assert describe_run_settings({"solver_type": "GA", "integrator": "x"}) == "GA"


def test_the_drift_line_reports_e0_the_drift_and_both_percentages():
    row = {"engine": "e", "settings": "h = 0.001", "status": "ok", "t_end": 1.0, "E0": 1472.0,
           "drift_J": 0.01472, "drift_percent": 1e-3, "drift_percent_of_T0": 2.94e-3}
    assert describe_drift(row) == ("e (h = 0.001; ok at 1.00 s): E0 = 1472.0000 J, "
                                   "Emax - Emin = 1.472e-02 J, drift 1.00e-03 % of E0 "
                                   "(2.94e-03 % of T0)")


class _Mass:
    """T = (1 + q[1]^2) dq[0]^2 / 2 (a mass that grows with the second coordinate), V = 0: the
    kinetic energy needs q as well as dq."""

    def kinetic_energy(self, q, dq):
        q, dq = np.asarray(q), np.asarray(dq)
        return 0.5 * (1.0 + q[..., 1] ** 2) * dq[..., 0] ** 2

    def potential_energy(self, q):
        return np.zeros(np.asarray(q).shape[:-1])


def test_the_drift_reads_every_sample_and_t0_is_the_first():
    """Three samples by hand: q1 = 0, 1, 0 and dq0 = 1, 1, sqrt(2)/2 give T = 0.5, 1, 0.25 (J):
    E0 = T0 = 0.5 (so the T0 percentage exists below 1 J), Emax - Emin = 0.75 at t = 1 and 2,
    the end 2 s after the start; a single sample (a run that stopped at once) drifts by 0."""
    q = np.zeros((3, 8))
    q[1, 1] = 1.0
    dq = np.zeros((3, 8))
    dq[:, 0] = (1.0, 1.0, math.sqrt(0.5))
    d = energy_drift(_Mass(), _traj(q, dq))
    assert set(d) == {"E0", "Emax", "Emin", "drift_J", "drift_percent", "T0",
                      "drift_percent_of_T0", "E_end_minus_E0", "t_Emax", "t_Emin", "samples",
                      "t_end", "zero_level"}
    assert d["T0"] == pytest.approx(0.5) and d["E0"] == pytest.approx(0.5)
    assert (d["Emax"], d["Emin"]) == (pytest.approx(1.0), pytest.approx(0.25))
    assert d["drift_J"] == pytest.approx(0.75)
    assert d["drift_percent"] == pytest.approx(150.0)
    assert d["drift_percent_of_T0"] == pytest.approx(150.0)
    assert (d["t_Emax"], d["t_Emin"], d["t_end"], d["samples"]) == (1.0, 2.0, 2.0, 3)
    assert d["E_end_minus_E0"] == pytest.approx(-0.25)
    # the module docstring's zero level of the potential energy
    assert d["zero_level"] == "potential energy sum m_i g z_Gi, z = 0 at the ground"
    one = energy_drift(_Mass(), _traj(q[:1], dq[:1]))
    assert one["samples"] == 1 and one["drift_J"] == 0.0 and one["t_end"] == 0.0


def test_the_free_roll_scenario_says_what_it_is():
    sc = free_roll_scenario(psi_dot=4.5, duration=0.5, sample=0.01, lean=0.25)
    assert sc.tags == ("energy",)
    assert "psi_dot(0) = 4.5 rad/s" in sc.description and "0.5 s" in sc.description
    assert "0.25 rad" in sc.description and sc.q0 == (0, 0, 0, 0.25, 0, 0, 0.25, 0)


class _Replay:
    """An 'engine' that returns a given trajectory for the scenario it is asked to run."""

    def __init__(self, traj):
        self.traj, self.asked = traj, []

    def simulate(self, sc):
        self.asked.append(sc)
        return self.traj


def test_energy_drifts_runs_the_reference_and_each_engine_on_the_scenario(disc):
    """The reference's free roll conserves energy (no torque, no drag, rolling constraints do no
    work): its drift at DOP853 rtol 1e-10 is below 1e-7 % of E0 (4e-8 % measured; the bound
    leaves a factor 2), and a looser rtol (1e-4) reaches the run: a larger drift (5e-6 %).
    Each engine's row is energy_drift of the trajectory it returned for that very scenario,
    with its label, status and settings phrase. The default scenario is the 1 s free roll."""
    from comparisons.judgments.energy import energy_drifts, free_roll_model
    model = free_roll_model(disc)
    rows = energy_drifts(model)
    assert (rows[0]["samples"], rows[0]["t_end"]) == (1001, 1.0)
    assert rows[0]["drift_percent"] < 1e-7
    short = free_roll_scenario(duration=0.2, sample=0.01)
    q = np.zeros((3, 8))
    q[:, 3] = (0.0, 0.1, 0.2)
    mine = _traj(q, np.ones((3, 8)))
    mine.settings["step"] = 1e-3
    engine = _Replay(mine)
    ref, row = energy_drifts(model, short, engines=[("mine", engine)])
    assert engine.asked == [short]
    assert (ref["engine"], ref["status"]) == ("reference thesis-disc", "completed")
    assert ref["settings"] == "DOP853 rtol 1e-10, projection"
    assert (ref["samples"], ref["t_end"]) == (21, pytest.approx(0.2))
    assert ref["drift_percent"] < 1e-7
    assert row == {"engine": "mine", "status": "completed", "settings": "h = 0.001",
                   **energy_drift(model, mine)}
    loose = energy_drifts(model, short, reference_rtol=1e-4)[0]
    assert loose["settings"] == "DOP853 rtol 1e-04, projection"
    assert loose["drift_percent"] > 100 * ref["drift_percent"]
