"""The energy judgment (comparisons/judgments/energy.py) held to the parts of its contract that
tests/test_energy_drift.py leaves open: the two refusals of `energy_drift` say exactly what is
wrong (a run with no samples; E0 = 0, where the IFToMM drift, normalised by E0, is undefined),
the reference row of `energy_drifts` is always a *projection* run ("DOP853 at reference_rtol,
projection", whatever constraint handling the scenario given carries: the energy stage hands it
a Baumgarte scenario for an engine that refuses projection), and its default scenario is the
free roll *on the model given* (the engine asked to run it is told that model's name, as the
energy stage does with `free_roll_scenario(model=free.name)`). Each test names the planted bugs
(mutmut's survivors of the module's first measurement) it fails on. ~0.2 s.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from comparisons.judgments.energy import (energy_drift, energy_drifts, free_roll_model,
                                          free_roll_scenario)
from reference_model.scenarios import run_forward
from reference_model.solvers import Trajectory


class _Oscillator:
    """A unit mass on a unit spring about q[0] = 1/2 (energies by hand): T = dq[0]^2 / 2,
    V = (q[0] - 1/2)^2 / 2 - 1/8, so that V = 0 at q[0] = 0 and the rest state there has
    E = T + V = 0 exactly."""

    def kinetic_energy(self, q, dq):
        return 0.5 * np.asarray(dq)[..., 0] ** 2

    def potential_energy(self, q):
        return 0.5 * (np.asarray(q)[..., 0] - 0.5) ** 2 - 0.125


def _traj(q, dq):
    q, dq = np.asarray(q, float), np.asarray(dq, float)
    t = np.arange(float(len(q))) if q.ndim == 2 else np.zeros(1)
    return Trajectory(t=t, q=q, dq=dq, ddq=np.zeros_like(q), C=np.zeros((t.size, 5)),
                      T=np.zeros((t.size, 3)), status="completed", message="",
                      t_end=float(t[-1]) if t.size else 0.0)


def test_a_run_with_no_samples_is_refused_in_words():
    """An empty trajectory (0 rows) and a single state not written as a row (1-D q) have no
    samples to take a max - min over: both refused with the message, exactly. Planted: the
    message wrapped in 'XX' (a match on 'no samples' alone let it through)."""
    exact = "^" + re.escape("the trajectory has no samples") + "$"
    with pytest.raises(ValueError, match=exact):
        energy_drift(_Oscillator(), _traj(np.zeros((0, 8)), np.zeros((0, 8))))
    with pytest.raises(ValueError, match=exact):
        energy_drift(_Oscillator(), _traj(np.zeros(8), np.zeros(8)))


def test_a_zero_initial_energy_is_refused_as_an_undefined_drift():
    """The oscillator released from q[0] = 0 at rest has E0 = T0 + V0 = 0 + 0 = 0, while at
    q[0] = 1/2 with dq[0] = 1 it has E = 1/2 - 1/8 = 3/8 (a drift of 3/8 J, but no percentage
    of E0): refused, with the reason in the module's words. Planted: the message wrapped in
    'XX'; its text upper-cased ('E0 = 0: THE IFTOMM DRIFT ...')."""
    q, dq = np.zeros((2, 8)), np.zeros((2, 8))
    q[1, 0], dq[1, 0] = 0.5, 1.0
    with pytest.raises(ValueError, match="^" + re.escape(
            "E0 = 0: the IFToMM drift (normalised by E0) is undefined") + "$"):
        energy_drift(_Oscillator(), _traj(q, dq))
    # the same run started a step later (E0 = 3/8 J) is measured: the check is on E0 only
    d = energy_drift(_Oscillator(), _traj(q[::-1], dq[::-1]))
    assert d["E0"] == pytest.approx(0.375) and d["drift_J"] == pytest.approx(0.375)
    assert d["drift_percent"] == pytest.approx(100.0)


@pytest.fixture(scope="module")
def free_disc(disc):
    return free_roll_model(disc)


def test_the_reference_row_is_a_projection_run_whatever_the_scenario_says(free_disc):
    """docs/report.md and the docstring: the reference is DOP853 at ``reference_rtol`` with
    projection. The same 0.2 s free roll given with Baumgarte stabilisation, with no constraint
    handling ('none') and with projection gives one and the same reference row (numbers and
    all), though the reference's own runs of the scenario as it stands drift differently
    (checked here, so that the equality means something). A loose rtol (1e-4) makes the
    schemes' drifts differ by orders of magnitude. Planted: the scenario's own constraint
    handling used (constraints=None, or the keyword left out of run_forward)."""
    sc = free_roll_scenario(duration=0.2, sample=0.01)
    rtol = 1e-4
    rows = {c: energy_drifts(free_disc, dataclasses.replace(sc, constraints=c),
                             reference_rtol=rtol)[0]
            for c in ("projection", "baumgarte", "none")}
    assert rows["projection"]["settings"] == "DOP853 rtol 1e-04, projection"
    assert rows["baumgarte"] == rows["projection"]
    assert rows["none"] == rows["projection"]
    own = {c: energy_drift(free_disc, run_forward(free_disc, dataclasses.replace(
        sc, constraints=c), rtol=rtol))["drift_J"] for c in ("baumgarte", "none")}
    for c, drift in own.items():
        assert abs(drift - rows["projection"]["drift_J"]) > 1e-3 * rows["projection"]["drift_J"], c


class _Replay:
    """An 'engine' that records the scenario it is asked to run and returns a fixed run."""

    def __init__(self, traj):
        self.traj, self.asked = traj, []

    def simulate(self, sc):
        self.asked.append(sc)
        return self.traj


def test_the_default_scenario_is_the_free_roll_on_the_model_given(thesis):
    """With no scenario, the engines are asked for the 1 s free roll of the model handed in:
    on the thesis's fork-contact model (cv set to 0), a scenario naming 'thesis' (not the
    free roll's default 'thesis-disc'), equal to free_roll_scenario(model='thesis'); the
    reference row covers that whole second (1001 samples). Planted: the default scenario
    built with model=None (an engine that loads the scenario's model gets none)."""
    free = free_roll_model(thesis)
    assert free.name == "thesis" and free.params.cv == 0.0
    q = np.zeros((2, 8))
    q[:, 3] = 1.0                       # any run with E0 != 0: the row is not what is tested
    engine = _Replay(_traj(q, np.zeros((2, 8))))
    ref, row = energy_drifts(free, engines=[("replay", engine)], reference_rtol=1e-6)
    assert [sc.model for sc in engine.asked] == ["thesis"]
    assert engine.asked[0] == free_roll_scenario(model="thesis")
    assert (ref["samples"], ref["t_end"], ref["status"]) == (1001, 1.0, "completed")
    assert row["engine"] == "replay"
