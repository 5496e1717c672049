"""The convergence study's parts the other convergence tests leave open
(comparisons/judgments/convergence.py): the given reference handed down to the horizon search
when no horizon is given, the shortest reference cut (two grid samples), and the study's
one-line description, asserted as a user reads it.

Expected values are the module's documented contract, worked out here by hand. The reference
runs are 0.3 s of stability-psid10 on thesis-disc (DOP853 with projection): a few hundredths
of a second in all; the engines are synthetic.
"""

import dataclasses

import numpy as np
import pytest

from comparisons.judgments.convergence import (ConvergenceStudy, convergence_study,
                                               reference_run)
from reference_model import COORDINATES, load_model
from reference_model.scenarios import SCENARIOS

THETA, PSI = COORDINATES.index("theta"), COORDINATES.index("psi")
STEPS = (4e-3, 2e-3, 1e-3, 5e-4)
SHORT = dataclasses.replace(SCENARIOS["stability-psid10"], grid=(0.0, 0.01, 31))   # 0.3 s


class _Offset:
    """An 'engine' whose run is ``ref`` up to ``t_end`` plus ``error`` in theta and
    ``error / 2`` in psi."""

    def __init__(self, ref, error):
        self.ref, self.error = ref, error

    def simulate(self, scenario, t_end=None):
        k = self.ref.t <= t_end + 1e-12
        q = self.ref.q[k].copy()
        q[:, THETA] += self.error
        q[:, PSI] += self.error / 2
        return dataclasses.replace(self.ref, t=self.ref.t[k], q=q, dq=self.ref.dq[k],
                                   t_end=float(self.ref.t[k][-1]), settings={"engine": "fake"})


@pytest.fixture(scope="module")
def short_reference(disc):
    return reference_run(disc, SHORT)


def test_without_a_horizon_the_given_reference_is_the_one_the_horizon_reads(disc,
                                                                             short_reference):
    """``reference`` given and no horizon: the horizon is that of the given run against its
    twin (theta_dot(0) + 1e-9 rad/s), not of a fresh reference. The given run here is the
    reference plus 1e-3 rad in theta from 0.1 s on: the twin stays within 1e-6 of the true
    reference over the 0.3 s (the control below: horizon at the end), so it parts from the
    given run at 0.10 s and the horizon is the grid time before, 0.09 s; every step is then
    judged up to 0.09 s, where the planted engine errors (40 h^2 in theta) are all there is.
    Planted: ``reference=None`` (or the argument dropped) on the way to `reference_horizon`,
    which then runs a fresh reference and finds the horizon at 0.3 s."""
    q = short_reference.q.copy()
    q[short_reference.t >= 0.1 - 1e-12, THETA] += 1e-3
    given = dataclasses.replace(short_reference, q=q)
    s = convergence_study(disc, lambda h: _Offset(given, 40.0 * h ** 2), SHORT, steps=STEPS,
                          reference=given)
    assert s.horizon == pytest.approx(0.09)
    assert s.horizon_reason.startswith(
        "two reference runs (rtol 1e-11) 1e-09 rad/s apart in theta_dot(0) separate by more "
        "than 1e-06 in theta, gamma, xc, yc at t = 0.10 s (1.0e-03)")
    np.testing.assert_allclose(s.errors, [40.0 * h ** 2 for h in STEPS], rtol=1e-9)
    # control: the true reference given, its twin never parts from it within the 0.3 s
    free = convergence_study(disc, lambda h: _Offset(short_reference, 40.0 * h ** 2), SHORT,
                             steps=STEPS, reference=short_reference)
    assert free.horizon == pytest.approx(0.3)
    assert "stay within 1e-06" in free.horizon_reason


@pytest.mark.parametrize("t_end", [0.01, 0.015, 0.01 - 1e-12])
def test_a_reference_cut_to_two_grid_samples_is_run(disc, t_end):
    """Two samples define the output grid (fewer are refused): a t_end at or just past the
    first grid step (0.01 s on stability-psid10), or short of it by far less than 1e-9 of the
    step, leaves the samples at 0 and 0.01 s and the run is made. Planted: two samples refused
    (``n_cut <= 2`` or ``n_cut < 3``)."""
    ref = reference_run(disc, SCENARIOS["stability-psid10"], rtol=1e-9, t_end=t_end)
    np.testing.assert_allclose(ref.t, [0.0, 0.01], rtol=0, atol=1e-15)
    assert ref.status == "completed"


def test_the_description_of_a_study_reads_as_documented():
    """The one line a user prints: engine vs reference, scenario and horizon (2 decimals), the
    max error in the compared coordinates joined by '/', the errors by step in braces as
    'h: e' pairs (h as %g, e with 3 significant figures) separated by ', ', the fitted order
    (2 decimals), the verdict and its reason. Planted: the pairs not joined (None), joined by
    'XX, XX', or the coordinates joined by 'XX/XX'."""
    s = ConvergenceStudy(
        scenario="stability-psid10", engine="fake", reference="reference thesis-disc",
        coordinates=("theta", "psi"), steps=(1e-3, 5e-4), errors=(1e-3, 2.5e-4),
        errors_all=(1e-3, 2.5e-4), worst=("theta", "theta"), order=2.0, intercept=0.0,
        order_all=2.0, horizon=0.5, horizon_reason="given",
        statuses=("completed", "completed"), verdict="inconclusive",
        verdict_reason="2 steps spanning 2x")
    assert s.describe() == (
        "fake vs reference thesis-disc, stability-psid10 up to 0.50 s: max error in theta/psi "
        "by step {0.001: 1.00e-03, 0.0005: 2.50e-04}, fitted order 2.00 -> inconclusive "
        "(2 steps spanning 2x)")


def test_the_description_of_a_study_on_synthetic_runs():
    """A study made end to end (errors 40 h^2 in theta, half that in psi, against a zero
    reference, theta and psi compared): 6.4e-4, 1.6e-4, 4e-5, 1e-5 at the four steps, order
    2, below 1e-3 at the smallest step: 'converges', said in one line. Planted: as the test
    above (the pairs or coordinates joined wrongly)."""
    from reference_model.solvers import Trajectory
    t = 0.01 * np.arange(51)
    z8 = np.zeros((t.size, 8))
    ref = Trajectory(t=t, q=z8, dq=z8, ddq=z8, C=np.zeros((t.size, 5)),
                     T=np.zeros((t.size, 3)), status="completed", message="", t_end=0.5,
                     settings={"integrator": "exact", "rtol": 1e-13, "constraints": "none"})
    s = convergence_study(load_model("thesis-disc"), lambda h: _Offset(ref, 40.0 * h ** 2),
                          SCENARIOS["stability-psid10"], steps=STEPS, horizon=0.5,
                          reference=ref, coords=("theta", "psi"))
    assert s.describe() == (
        "fake vs reference thesis-disc (disc contact), exact rtol 1e-13, none, "
        "stability-psid10 up to 0.50 s: max error in theta/psi by step {0.004: 6.40e-04, "
        "0.002: 1.60e-04, 0.001: 4.00e-05, 0.0005: 1.00e-05}, fitted order 2.00 -> converges "
        "(order 2.00 in [1.5, 2.5] and error 1.0e-05 < 1e-03 at h = 0.0005)")
