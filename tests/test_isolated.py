"""Engines the main process asks for terms in workers of their own
(`comparisons.stages.isolated`), on engines written here: an engine's values come back from
its worker unchanged; one that ends its worker (os._exit) or never returns becomes an
`EngineGone` naming it, the call and how, and is not asked again; a capability it lacks is
the base class's refusal; the reference stays in this process; one engine's failure becomes
one failing row beside the others' rows; and a scenario with no reference run or no horizon
says why it is not compared."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from comparisons.judgments.rows import Comparison
from comparisons.stages.isolated import (CALL_TIMEOUT, EngineGone, IsolatedSetup,
                                         failures_as_rows, isolated, unjudgeable)
from comparisons.stages.runs import EngineSetup
from engines.base import CapabilityError
from engines.guard import EngineCallError
from reference_model.scenarios import SCENARIOS

ENGINES = '''
import os
import time

from engines.base import Engine


class Fine(Engine):
    name = "fine"
    capabilities = frozenset({"mass_matrix", "gravity", "constraint_jacobian"})
    contacts = ("thesis",)

    def mass_matrix(self, q):
        return self.model.mass_matrix(q) * 2.0

    def constraint_jacobian(self, q):
        return self.model.constraint_jacobian(q)

    def gravity(self, q):
        return self.model.Qgrav(q)


class Dies(Fine):
    name = "dies"

    def mass_matrix(self, q):
        os._exit(3)


class Raises(Fine):
    name = "raises"

    def mass_matrix(self, q):
        raise RuntimeError("boom")


class DiesBuilding(Fine):
    name = "dies-building"

    def __init__(self, model):
        os._exit(4)


class HangsBuilding(Fine):
    name = "hangs-building"

    def __init__(self, model):
        time.sleep(60)


class Hangs(Fine):
    name = "hangs"

    def mass_matrix(self, q):
        time.sleep(60)
'''
Q = np.array([0.0, 0.0, 0.1, 0.05, 0.3, 0.0, 0.2, 0.4])


@pytest.fixture(scope="module")
def spec(tmp_path_factory):
    path = tmp_path_factory.mktemp("isolated") / "remote_engines.py"
    path.write_text(ENGINES, "utf-8")
    return lambda cls: f"{path}:{cls}"


def _remote(spec, cls, model, timeout=5.0):
    return isolated(EngineSetup(cls, spec(cls)), timeout).build(model)


def test_values_come_back_from_the_worker_and_the_facts_are_the_engines(spec, thesis):
    eng = _remote(spec, "Fine", thesis)
    assert eng.name == "fine"
    assert eng.capabilities == frozenset({"mass_matrix", "gravity", "constraint_jacobian"})
    assert eng.contacts == ("thesis",) and eng.run_difference is None
    assert np.array_equal(eng.mass_matrix(Q), 2.0 * thesis.mass_matrix(Q))
    assert np.array_equal(eng.gravity(Q), thesis.Qgrav(Q))
    assert np.array_equal(eng.constraint_jacobian(Q), thesis.constraint_jacobian(Q))
    with pytest.raises(CapabilityError, match=r"^engine 'fine' cannot compute "
                                              r"constraint_bias; it provides: mass_matrix, "
                                              r"gravity, constraint_jacobian$"):
        eng.constraint_bias(Q, Q)


def test_an_engine_that_ends_its_worker_is_gone_and_not_asked_again(spec, thesis):
    eng = _remote(spec, "Dies", thesis)
    with pytest.raises(EngineGone) as err:
        eng.mass_matrix(Q)
    assert str(err.value) == "engine 'dies': mass_matrix: its worker process died (exit status 3)"
    with pytest.raises(EngineCallError) as again:
        eng.gravity(Q)                                   # it would work: not asked any more
    assert str(again.value) == ("engine 'dies': gravity skipped (an earlier call failed: engine "
                                "'dies': mass_matrix: its worker process died (exit status 3))")


def test_an_engine_that_never_returns_is_gone_after_its_limit(spec, thesis):
    eng = _remote(spec, "Hangs", thesis, timeout=0.5)
    with pytest.raises(EngineGone) as err:
        eng.mass_matrix(Q)
    assert str(err.value) == ("engine 'hangs': mass_matrix timed out after 0.5 s (its worker was "
                              "killed)")


def test_the_reference_stays_here_and_the_limit_defaults(spec):
    ref = EngineSetup("reference", "reference")
    assert isolated(ref) is ref
    s = isolated(EngineSetup("Fine", spec("Fine"), (("a", 1),), ("forward",), "x"))
    assert isinstance(s, IsolatedSetup) and s.timeout == CALL_TIMEOUT == 60.0
    assert (s.label, s.engine, s.options, s.kinds, s.settings) == (
        "Fine", spec("Fine"), (("a", 1),), ("forward",), "x")


def test_one_engines_failure_is_one_failing_row_beside_the_others_rows():
    good = Comparison.of({"quantity": "mass_matrix", "scenario": "zigzag", "model": "thesis",
                          "engines": ["ok"], "max_error": 1e-15, "tolerance": 1e-9,
                          "passed": True, "localized_to": None, "note": ""})

    def compare(engines):
        (label, eng), = engines.items()
        if eng == "broken":
            raise ValueError("M is not symmetric")
        return [good]

    rows = failures_as_rows(compare, {"ok": "fine", "bad": "broken"}, "mass matrix", "zigzag",
                            "thesis")
    assert rows[0] is good and len(rows) == 2
    bad = rows[1]
    assert (bad.quantity, bad.scenario, bad.model, list(bad.engines), bad.passed) == (
        "engine call", "zigzag", "thesis", ["bad"], False)
    assert bad.max_error is None and bad.tolerance is None
    assert bad.extra == {}                  # every field a common one: nothing else written
    assert bad.localized_to == "ValueError: M is not symmetric"
    assert bad.note == "bad failed while its mass matrix was compared"


class _Ref:
    def __init__(self, n, message="", scenario="stability-psid5"):
        self.t, self.message, self.scenario = np.zeros(n), message, scenario


def test_why_a_scenario_cannot_be_compared():
    sc = SCENARIOS["stability-psid5"]
    assert unjudgeable(_Ref(0, "solver failed at t = 1.2 s"), sc, {}) == (
        "not compared: the reference's run failed (solver failed at t = 1.2 s)")
    assert unjudgeable(_Ref(10), sc, {}) == (
        "not compared: its meaningful-horizon stage failed (see that stage's line on the "
        "progress output; rerun, or give a larger --stage-timeout)")
    assert unjudgeable(_Ref(10), sc, {"stability-psid5": 2.0}) == ""
    # a case on another model finds the horizon under the reference run's scenario name
    on_mine = dataclasses.replace(sc, name="stability-psid5-on-mine")
    assert unjudgeable(_Ref(10, scenario="stability-psid5"), on_mine,
                       {"stability-psid5": 2.0}) == ""
    assert unjudgeable(_Ref(10), SCENARIOS["zigzag"], {}) == ""     # inverse: no horizon needed


def test_an_engines_own_runtime_error_is_its_error_not_a_dead_worker(spec, thesis):
    eng = _remote(spec, "Raises", thesis)
    with pytest.raises(RuntimeError) as err:
        eng.mass_matrix(Q)
    assert type(err.value) is RuntimeError and str(err.value) == "boom"
    assert eng.broken is None and np.array_equal(eng.gravity(Q), thesis.Qgrav(Q))


def test_an_engine_that_dies_or_hangs_while_being_built_is_named_with_its_setup(spec, thesis):
    with pytest.raises(EngineGone) as err:
        _remote(spec, "DiesBuilding", thesis)
    assert str(err.value) == ("engine 'DiesBuilding': __init__: its worker process died (exit "
                              "status 4)")
    with pytest.raises(EngineGone) as err:
        _remote(spec, "HangsBuilding", thesis, timeout=0.5)
    assert str(err.value) == ("engine 'HangsBuilding': __init__ timed out after 0.5 s (its "
                              "worker was killed)")
