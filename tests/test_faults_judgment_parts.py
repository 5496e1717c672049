"""The fault suite's plumbing (comparisons/judgments/faults.py) held to its docstrings, with
the engines, their terms, the localization and the runs stood in for (the real ones are
tests/test_faults.py's, seconds each): the suite's unknown-fault message names every fault;
each engine is built from the correct model with its own options, its terms evaluated once
and shared by every fault's localization; the states are the deterministic ones (16 by
default, from the seed: the fault section's "16 deterministic states"), for the suite and for
its control `unfaulted`; and `trajectory_result`'s two thresholds read as its docstring says:
detected when the runs part by *more than* TRAJECTORY_DETECTED, and a structural cause found
when undoing it makes them agree (not more than it apart), the gyroscopic terms undone by
toggling them, a fault of several causes expected as their labels joined by ' + '.

Each test names the planted bugs (mutmut's survivors of the module's first measurement) it
fails on.
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

import comparisons.judgments.convergence as convergence
import comparisons.judgments.faults as faults
from comparisons.judgments.diagnose import DEFAULT_SEED, Localization
from comparisons.judgments.faults import FAULTS, TRAJECTORY_DETECTED
from reference_model import load_model


@pytest.fixture(scope="module")
def thesis():
    return load_model("thesis")


def test_an_unknown_fault_is_refused_naming_every_fault():
    """run_fault_suite with a fault id not in FAULTS: the one-line message names it and lists
    the six faults (issue 5's list), comma separated, before any engine is built. Planted:
    the separator changed."""
    with pytest.raises(ValueError) as err:
        faults.run_fault_suite(("pinocchio",), faults=["I3xz-sign", "I3xz"], tolerances={})
    assert str(err.value) == ("unknown fault 'I3xz'; choose from I3xz-sign, I2xx-I2yy-swapped, "
                              "com-offset-1mm, z3-0.39647, gyroscopic-dropped, contact-switched")


class _Spy:
    """Stands in for load_engine, engine_terms and localize: records what each is given."""

    def __init__(self):
        self.loads, self.terms, self.localized = [], [], []

    def load_engine(self, name, model, **options):
        self.loads.append((name, model.name, options))
        return SimpleNamespace(name=name, supports=lambda what: False)

    def engine_terms(self, engine, states):
        values = {"M": f"{engine.name}'s M", "Qv": f"{engine.name}'s Qv"}
        self.terms.append((engine.name, states, values))
        return values

    def localize(self, model, states, built, values=None, *, tolerances):
        self.localized.append((model.name, states, [e.name for e in built], values, tolerances))
        return Localization(quantities=(), checks=(), explanation=None)


@pytest.fixture
def spy(monkeypatch):
    s = _Spy()
    monkeypatch.setattr(faults, "load_engine", s.load_engine)
    monkeypatch.setattr(faults, "engine_terms", s.engine_terms)
    monkeypatch.setattr(faults, "localize", s.localize)
    return s


def test_each_engine_is_built_with_its_options_and_its_terms_shared_by_every_fault(spy):
    """run_fault_suite: each engine built once from the correct base model with the options
    given for its spec (none for another), its terms evaluated once on the suite's states, and
    those very values handed to every fault's localization (the docstring's 'evaluated once
    and shared by every fault'), each broken copy localized against every engine. Planted: the
    options dropped or looked up under another key; the terms not passed (localize
    re-evaluating them for each fault)."""
    tols = {"a tolerance": 1}
    results = faults.run_fault_suite(("pinocchio", "exudyn"), n_states=4, base="thesis",
                                     faults=("I3xz-sign", "z3-0.39647"), tolerances=tols,
                                     options={"pinocchio": {"damping": 0.5}})
    assert spy.loads == [("pinocchio", "thesis", {"damping": 0.5}), ("exudyn", "thesis", {})]
    assert [name for name, _, _ in spy.terms] == ["pinocchio", "exudyn"]
    shared = {name: values for name, _, values in spy.terms}
    assert [m for m, *_ in spy.localized] == ["thesis+I3xz-sign", "thesis+z3-0.39647"]
    for _, states, built, values, tolerances in spy.localized:
        assert built == ["pinocchio", "exudyn"] and tolerances is tols
        assert values.keys() == shared.keys()
        assert all(values[k] is shared[k] for k in shared)
        assert states is spy.terms[0][1]
    assert [r.fault for r in results] == ["I3xz-sign", "z3-0.39647"]
    assert all(r.engines == ("pinocchio", "exudyn") and not r.detected for r in results)


def _states_of(run, seed=None, **kw):
    """The states the suite (or the control) hands to localize, for one call."""
    spy = _Spy()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(faults, "load_engine", spy.load_engine)
        mp.setattr(faults, "engine_terms", spy.engine_terms)
        mp.setattr(faults, "localize", spy.localize)
        if seed is None:
            run(("pinocchio",), tolerances={}, **kw)
        else:
            run(("pinocchio",), seed=seed, tolerances={}, **kw)
    return spy.localized[0][1]


@pytest.mark.parametrize("run", [
    lambda engines, **kw: faults.run_fault_suite(engines, faults=("I3xz-sign",), **kw),
    faults.unfaulted], ids=["suite", "unfaulted"])
def test_the_states_are_deterministic_from_the_seed(run):
    """The suite and its control use deterministic states: 16 by default (the fault section's
    '16 deterministic states'), the same for the same seed, others for another seed, the
    default seed diagnose's DEFAULT_SEED. Planted: the seed not passed (random_states' own
    default seed 0 for every seed) or passed as None (fresh random states every call)."""
    default = _states_of(run)
    assert default.q.shape == (16, 8) and default.dq.shape == (16, 8)
    same = _states_of(run, seed=DEFAULT_SEED)
    np.testing.assert_array_equal(same.q, default.q)
    np.testing.assert_array_equal(same.dq, default.dq)
    a, b = _states_of(run, seed=5), _states_of(run, seed=5)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.dq, b.dq)
    other = _states_of(run, seed=7)
    assert not np.array_equal(other.q, a.q) and not np.array_equal(a.q, default.q)
    assert _states_of(run, n_states=5).q.shape == (5, 8)


# -- the forward-run fallback's thresholds ----------------------------------------------------------

def _gaps(monkeypatch, table):
    """Stand in for the reference runs and their comparison: the gap between the engine's run
    and a model's is ``table[(contact, gyroscopic)]`` (0 where absent), reached at the last
    sample (0.5 s) in gamma."""
    monkeypatch.setattr(convergence, "reference_run", lambda m, sc: m)

    def error_vs_time(mine, theirs, coords):
        g = table.get((mine.contact, mine.gyroscopic), 0.0)
        out = {"t": np.array([0.0, 0.25, 0.5]), "max": np.array([0.0, g / 2, g])}
        out.update({c: (out["max"] if c == "gamma" else np.zeros(3)) for c in coords})
        return out
    monkeypatch.setattr(convergence, "error_vs_time", error_vs_time)


ENGINE = SimpleNamespace(name="fake", simulate=lambda sc: "the engine's run")


def test_a_gap_of_exactly_the_threshold_is_not_detected(monkeypatch, thesis):
    """trajectory_result: runs exactly TRAJECTORY_DETECTED apart do not part by *more than*
    it: not detected, not correct; a hair more is detected. Planted: '>=' for '>'."""
    faulty = FAULTS["contact-switched"].inject(thesis)
    _gaps(monkeypatch, {("disc", True): TRAJECTORY_DETECTED})
    r = faults.trajectory_result(FAULTS["contact-switched"], thesis, ENGINE, faulty=faulty)
    assert not r.detected and not r.correct and r.localized_to == "not detected"
    assert r.evidence == ("fake's stability-psid10 to 0.5 s parts from the faulty model's by "
                          "1.00e-03 (worst gamma at 0.50 s; detected above 0.001)")
    _gaps(monkeypatch, {("disc", True): TRAJECTORY_DETECTED * 1.001})
    assert faults.trajectory_result(FAULTS["contact-switched"], thesis, ENGINE,
                                    faulty=faulty).detected


def test_undoing_a_cause_to_exactly_the_threshold_is_agreeing(monkeypatch, thesis):
    """trajectory_result: the contact switch undone leaves the runs exactly TRAJECTORY_DETECTED
    apart, which is not more than the detection threshold: they agree, and the fault is
    localized to the contact model, body 5. Planted: '<' for '<='."""
    faulty = FAULTS["contact-switched"].inject(thesis)
    _gaps(monkeypatch, {("disc", True): 0.8, ("thesis", True): TRAJECTORY_DETECTED,
                        ("disc", False): 0.9})
    r = faults.trajectory_result(FAULTS["contact-switched"], thesis, ENGINE, faulty=faulty)
    assert r.detected and r.correct and r.causes == ("contact",), r.evidence
    assert r.localized_to == "trajectory via front contact model (body 5 front wheel)"
    assert r.evidence.endswith("; undoing the front contact model brings it to 1.0e-03")


def test_the_gyroscopic_terms_are_undone_by_toggling_them(monkeypatch, thesis):
    """An engine built without the gyroscopic terms (its runs those of the non-gyroscopic
    model) against the correct, gyroscopic, model: undoing the gyroscopic cause means dropping
    them, which makes the runs agree, so the cause found is the gyroscopic terms (all bodies).
    Planted: the undone model built with the default gyroscopic=True (nothing undone)."""
    _gaps(monkeypatch, {("thesis", True): 0.3, ("disc", True): 0.4})
    r = faults.trajectory_result(FAULTS["gyroscopic-dropped"], thesis, ENGINE, faulty=thesis)
    assert r.detected and r.causes == ("gyroscopic",), r.evidence
    assert r.localized_to == "trajectory via gyroscopic terms w x (I w) (all bodies)"
    assert r.correct


def test_a_fault_of_two_causes_is_expected_as_both_joined(monkeypatch, thesis):
    """A fault whose causes are the contact and the gyroscopic terms is expected as 'trajectory
    via <contact> + <gyroscopic> (<body>)'; one cause found is not it. Planted: the joining
    ' + ' changed."""
    both = dataclasses.replace(FAULTS["contact-switched"], causes=("contact", "gyroscopic"))
    _gaps(monkeypatch, {("disc", True): 0.8, ("disc", False): 0.8})
    r = faults.trajectory_result(both, thesis, ENGINE, faulty=FAULTS["contact-switched"]
                                 .inject(thesis))
    assert r.expected == ("trajectory via front contact model + gyroscopic terms w x (I w) "
                          "(body 5 front wheel)")
    assert r.causes == ("contact",) and not r.correct
