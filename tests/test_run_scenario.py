"""`engines.runs.run_scenario`: one scenario on one engine as a `Run` (issue 24). The
contract (its module docstring): a run that cannot be made is a `Run` too, 'not run' when the
engine lacks the dynamics or declares the model difference, 'failed' with the reason when it
raises; inverse runs go through the engine's run_inverse (the reference model's own when the
engine is None), forward ones through simulate. Expected arrays are the reference model's own
solvers called here. Planted bugs are named in each test."""

import time

import numpy as np
import pytest

from engines.base import CapabilityError
from engines.runs import Run, run_scenario
from reference_model import load_model
from reference_model.scenarios import SCENARIOS, run_forward, run_inverse


@pytest.fixture(scope="module")
def thesis():
    return load_model("thesis")


def test_a_kind_the_engine_lacks_is_not_run_and_says_which_dynamics(thesis):
    """Planted: the kinds' wording swapped."""
    fwd = run_scenario("eng", None, thesis, SCENARIOS["stability-psid5"], kinds=("inverse",))
    inv = run_scenario("eng", None, thesis, SCENARIOS["check"], kinds=("forward",))
    assert (fwd.status, fwd.message, fwd.seconds, fwd.kind) == (
        "not run", "eng has no forward dynamics (simulate)", 0.0, "forward")
    assert (inv.status, inv.message) == (
        "not run", "eng has no constrained inverse dynamics (run_inverse: the rider's torques "
                   "and the contact forces of a prescribed motion)")
    assert fwd.t.size == 0 and fwd.t_end == 0.0


def test_an_inverse_run_of_the_reference_is_its_own_solvers(thesis):
    """engine None: the reference model's run_inverse, every sample solved. Planted: the
    arrays or the message's verdict swapped."""
    sc = SCENARIOS["check"]
    t0 = time.perf_counter()
    run = run_scenario("reference", None, thesis, sc)
    took = time.perf_counter() - t0
    ref = run_inverse(thesis, sc)
    assert (run.status, run.message, run.kind, run.model) == ("completed", "solved at every "
                                                              "sample", "inverse", "thesis")
    np.testing.assert_array_equal(run.q, ref.motion.q)
    np.testing.assert_array_equal(run.T, ref.T)
    np.testing.assert_array_equal(run.lam, ref.lam)
    np.testing.assert_array_equal(run.ddq, ref.ddq)
    assert 0 <= run.seconds <= took and run.t_end == float(ref.motion.t[-1])


def test_a_start_that_needed_correcting_says_how(thesis):
    """The benchmark's upright pitch is not 0, so its inverse runs start by solving beta: the
    message says so (the correction's own text). Planted: the correction left out."""
    bench = load_model("benchmark")
    run = run_scenario("reference", None, bench, SCENARIOS["check"])
    ref = run_inverse(bench, SCENARIOS["check"])
    assert ref.motion.info["beta_correction"] != 0.0
    assert run.message == f"solved at every sample; {ref.motion.info['initial_correction']}"


class _Engine:
    def __init__(self, model, inverse_status=None, error=None):
        self.model, self.inverse_status, self.error = model, inverse_status, error

    def run_inverse(self, scenario):
        if self.error is not None:
            raise self.error
        res = run_inverse(self.model, scenario)
        res.status[:] = 0
        res.status[:self.inverse_status] = 1
        return res

    def simulate(self, scenario):
        if self.error is not None:
            raise self.error
        return run_forward(self.model, scenario)


def test_failed_samples_fail_the_inverse_run_and_are_counted(thesis):
    """Planted: the count, the status for bad samples."""
    run = run_scenario("eng", _Engine(thesis, inverse_status=2), thesis, SCENARIOS["check"])
    assert (run.status, run.message) == ("failed", "2 samples failed")


def test_a_forward_run_is_the_engine_s_trajectory(thesis):
    sc = SCENARIOS["stability-psid5"]
    run = run_scenario("eng", _Engine(thesis), thesis, sc)
    traj = run.trajectory
    assert (run.status, run.message, run.kind) == (traj.status, traj.message, "forward")
    np.testing.assert_array_equal(run.q, traj.q)
    np.testing.assert_array_equal(run.dq, traj.dq)
    np.testing.assert_array_equal(run.t, traj.t)


@pytest.mark.parametrize("kind", ["check", "stability-psid5"])
def test_a_declared_difference_is_not_run_and_an_error_is_a_failure(thesis, kind):
    """CapabilityError: the engine declares it cannot; any other exception: a failed run with
    its type and first line. Planted: the declaration reported as a failure, its whitespace
    kept, the failure's message lost."""
    sc = SCENARIOS[kind]
    declared = run_scenario("eng", _Engine(thesis, error=CapabilityError("no rolling\n   "
                                                                        "constraint here")),
                            thesis, sc)
    assert (declared.status, declared.message) == (
        "not run", "declared model difference: no rolling constraint here")
    broken = run_scenario("eng", _Engine(thesis, error=ZeroDivisionError("step 0")), thesis, sc)
    assert (broken.status, broken.message) == ("failed", "ZeroDivisionError: step 0")
    assert isinstance(broken, Run) and broken.seconds >= 0


def _identity(run):
    return (run.engine, run.scenario, run.model, run.kind)


class _NoDdq(_Engine):
    """An engine whose inverse result has no accelerations (an older engine's)."""

    def run_inverse(self, scenario):
        res = run_inverse(self.model, scenario)

        class Bare:
            motion, T, lam, status = res.motion, res.T, res.lam, res.status
        return Bare()


def test_every_path_keeps_the_run_s_identity_and_its_duration(thesis):
    """Each kind of outcome names its engine label, scenario, model and kind, and its wall
    time is a duration no longer than the call. Planted: any of them dropped (None), the time
    as perf_counter() + t0, the inverse run's rates lost, the ddq lookup without default."""
    inv, fwd = SCENARIOS["check"], SCENARIOS["stability-psid5"]
    cases = [
        (lambda: run_scenario("a", None, thesis, fwd, kinds=("inverse",)), ("a", fwd.name, "forward")),
        (lambda: run_scenario("b", _NoDdq(thesis), thesis, inv), ("b", inv.name, "inverse")),
        (lambda: run_scenario("c", _Engine(thesis), thesis, fwd), ("c", fwd.name, "forward")),
        (lambda: run_scenario("d", _Engine(thesis, error=CapabilityError("x")), thesis, fwd),
         ("d", fwd.name, "forward")),
        (lambda: run_scenario("e", _Engine(thesis, error=KeyError("k")), thesis, inv),
         ("e", inv.name, "inverse")),
    ]
    for make, (label, scenario, kind) in cases:
        t0 = time.perf_counter()
        run = make()
        took = time.perf_counter() - t0
        assert _identity(run) == (label, scenario, "thesis", kind)
        assert 0 <= run.seconds <= took, (label, run.seconds, took)
    run = run_scenario("b", _NoDdq(thesis), thesis, inv)
    assert run.ddq is None
    np.testing.assert_array_equal(run.dq, run_inverse(thesis, inv).motion.dq)


def test_an_engine_that_fails_to_resolve_does_not_hide_those_after_it(monkeypatch):
    """Planted: break for continue (every engine after a broken one left out)."""
    from engines import defaults
    monkeypatch.setattr(defaults, "available_engines",
                        lambda: ("reference", "no-such-engine-xyz", "reference"))
    assert defaults.installed_engines() == ("reference", "reference")
