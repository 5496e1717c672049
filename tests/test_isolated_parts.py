"""The parts of `comparisons.stages.isolated` that run in the worker, run here in this process:
`_plain` gives back the plain setup `isolated` started from (so the worker builds the engine
itself, not another remote one); `_describe_built` builds the engine with its options and
returns its facts (name, declared capabilities in `engines.base.CAPABILITIES` order, contacts,
``run_difference``); `_call` builds it and calls the named capability with the positional and
keyword arguments given, through the guard; and a `RemoteEngine` forwards each of its nine
capabilities with every argument to the engine, whose value comes back unchanged.

`tests/test_isolated.py` runs these in forked workers (where mutation testing cannot see them)
and covers the deaths and time-outs; here the worker is replaced by an in-process stand-in for
`pool.call_in_worker` (``func(*args)``, the time limit recorded), so the forwarding itself is
what is checked. The test engine's every value is a different function of every argument and of
its option ``scale``, so an argument dropped, set to None or lost on the way shows; the expected
values are the same engine built in this process by `runs.EngineSetup.build` and called
directly, and for M the formula the engine states (``scale * diag(q)``).
"""

from __future__ import annotations

import numpy as np
import pytest

import comparisons.stages.isolated as iso
from comparisons.stages.isolated import IsolatedSetup, RemoteEngine, isolated
from comparisons.stages.runs import EngineSetup
from engines.base import CAPABILITIES, CONTACTS
from engines.guard import EngineCallError

ENGINES = '''
import types

import numpy as np

from engines.base import CAPABILITIES, Engine


class Echo(Engine):
    """Every capability; each value a different function of every argument and of scale."""

    name = "echo"
    capabilities = frozenset(CAPABILITIES)
    contacts = ("thesis",)
    run_difference = "a test engine: its runs are its own"

    def __init__(self, model, scale=1.0):
        super().__init__(model)
        self.scale = scale

    def mass_matrix(self, q):
        return self.scale * np.diag(q)

    def inverse_dynamics(self, q, dq, ddq):
        return self.scale * (q + 2.0 * dq + 3.0 * ddq)

    def gravity(self, q):
        return -self.scale * q

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self.scale * np.concatenate([q[:5] - dq[:5], np.asarray(torques, float)])

    def constraint_jacobian(self, q):
        return self.scale * np.outer(q[:5], q)

    def constraint_bias(self, q, dq):
        return self.scale * (q[:5] - 2.0 * dq[:5])

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self.scale * np.concatenate([q[:5] * dq[:5], 5.0 * np.asarray(torques, float)])

    def simulate(self, scenario, **options):
        n = options.get("samples", 2)
        t = np.arange(n) * self.scale
        q = np.outer(t, np.ones(8))
        return types.SimpleNamespace(t=t, q=q, dq=2.0 * q, status="completed",
                                     message=f"{scenario} with {sorted(options.items())}")

    def eigenvalues(self, speeds):
        return self.scale * np.outer(np.atleast_1d(speeds), [1.0, -1.0, 1j, -1j])


class Partial(Echo):
    name = "partial"
    capabilities = frozenset({"eigenvalues", "mass_matrix"})


class Bare(Engine):
    """Declares neither contacts nor run_difference: the base class's defaults."""

    name = "bare"
    capabilities = frozenset({"gravity"})

    def gravity(self, q):
        return np.zeros(8)


class Wrong(Bare):
    name = "wrong"

    def gravity(self, q):
        return np.zeros(3)
'''
Q = np.array([0.1, -0.2, 0.3, 0.05, 0.7, -0.4, 0.9, 1.1])
DQ = np.array([1.0, 0.5, -0.25, 2.0, -1.5, 0.75, 0.3, -0.6])
DDQ = np.array([0.2, 0.4, -0.8, 1.6, -0.1, 0.3, -0.5, 0.7])
TAU = (0.3, -0.7, 1.9)
#: a setup of the Echo engine with every field set and none at its default
OPTIONS = (("scale", 2.0),)
KINDS = ("forward",)
SETTINGS = "echo at twice its scale"


@pytest.fixture(scope="module")
def spec(tmp_path_factory):
    path = tmp_path_factory.mktemp("isolated_parts") / "echo_engines.py"
    path.write_text(ENGINES, "utf-8")
    return lambda cls: f"{path}:{cls}"


@pytest.fixture(scope="module")
def echo(spec):
    return EngineSetup("Echo-x2", spec("Echo"), OPTIONS, KINDS, SETTINGS)


@pytest.fixture
def inline(monkeypatch):
    """`call_in_worker` run in this process: ``func(*args)``; each call's time limit kept."""
    limits = []

    def call_here(func, *args, time_limit=None):
        limits.append(time_limit)
        return func(*args)

    monkeypatch.setattr(iso, "call_in_worker", call_here)
    return limits


def test_plain_gives_back_the_setup_isolated_started_from(echo):
    """`_plain(isolated(s))` is ``s`` again, a plain `EngineSetup` (whose build loads the
    engine itself) with the same label, engine, options, kinds and settings: every field set
    and none at its default, so each one is seen. Planted: any field dropped, set to None or
    shifted into its neighbour's place (e.g. the settings back at their default "")."""
    remote = isolated(echo, 5.0)
    assert isinstance(remote, IsolatedSetup)
    back = iso._plain(remote)
    assert type(back) is EngineSetup and back == echo
    assert (back.label, back.engine, back.options, back.kinds, back.settings) == (
        "Echo-x2", echo.engine, OPTIONS, KINDS, SETTINGS)


def test_describe_built_gives_the_engines_facts_in_capability_order(spec, thesis):
    """`_describe_built` builds the engine of the setup (a remote one too) and returns its name,
    its declared capabilities in the order of `engines.base.CAPABILITIES`, its contacts as a
    tuple and its ``run_difference``; an engine declaring neither of the last two has the
    base class's (`CONTACTS`, None). Planted: the capabilities it lacks listed instead, the
    contacts or run_difference read under another name (always the default), the model or the
    setup lost on the way to the build."""
    assert iso._describe_built(isolated(EngineSetup("Partial", spec("Partial")), 5.0),
                               thesis) == (
        "partial", ("mass_matrix", "eigenvalues"), ("thesis",),
        "a test engine: its runs are its own")
    assert iso._describe_built(EngineSetup("Echo", spec("Echo"), OPTIONS), thesis) == (
        "echo", CAPABILITIES, ("thesis",), "a test engine: its runs are its own")
    assert iso._describe_built(EngineSetup("Bare", spec("Bare")), thesis) == (
        "bare", ("gravity",), tuple(CONTACTS), None)


def test_call_builds_the_engine_and_calls_the_capability_with_every_argument(spec, echo,
                                                                           thesis):
    """`_call(setup, model, name, args, kwargs)` is ``name(*args, **kwargs)`` on the setup's
    engine built with its options: the value the engine built here returns, and for M the
    engine's own formula (2 diag(q) at scale 2). The call goes through the guard: an engine's
    value of the wrong shape is its one-line `EngineCallError`. Planted: the positional or the
    keyword arguments dropped, the name, model or setup lost."""
    here = echo.build(thesis)
    got = iso._call(isolated(echo, 5.0), thesis, "generalized_forces", (Q, DQ),
                    {"torques": TAU})
    assert np.array_equal(got, here.generalized_forces(Q, DQ, torques=TAU))
    assert np.array_equal(got[5:], 2.0 * np.array(TAU))          # the keyword reached it
    assert np.array_equal(iso._call(echo, thesis, "mass_matrix", (Q,), {}), 2.0 * np.diag(Q))
    run = iso._call(echo, thesis, "simulate", ("zigzag",), {"samples": 3})
    assert run.message == "zigzag with [('samples', 3)]" and np.array_equal(run.t, [0, 2, 4])
    with pytest.raises(EngineCallError) as err:
        iso._call(EngineSetup("Wrong", spec("Wrong")), thesis, "gravity", (Q,), {})
    assert str(err.value) == ("engine 'wrong': gravity returned shape (3,) for q of shape (8,); "
                              "expected (8,)")


def test_a_remote_engine_forwards_every_capability_and_its_value_comes_back(echo, thesis,
                                                                          inline):
    """With the worker replaced by a call in this process, `IsolatedSetup.build` gives a
    `RemoteEngine` with the engine's facts, and each of the nine capabilities returns what the
    engine built here returns for the same arguments (every one of them reaching it: q, dq,
    ddq, torques, the scenario, the run's options, the speeds); one call for the build and one
    per capability, each under the setup's time limit. Planted: a capability forwarded under
    another name or none, with an argument dropped or None (e.g. constraint_bias without dq),
    or simulate without its options."""
    here = echo.build(thesis)
    eng = isolated(echo, 7.0).build(thesis)
    assert isinstance(eng, RemoteEngine)
    assert (eng.name, eng.capabilities, eng.contacts, eng.run_difference) == (
        "echo", frozenset(CAPABILITIES), ("thesis",), "a test engine: its runs are its own")
    assert np.array_equal(eng.mass_matrix(Q), 2.0 * np.diag(Q))
    pairs = [
        (eng.mass_matrix(Q), here.mass_matrix(Q)),
        (eng.inverse_dynamics(Q, DQ, DDQ), here.inverse_dynamics(Q, DQ, DDQ)),
        (eng.gravity(Q), here.gravity(Q)),
        (eng.generalized_forces(Q, DQ, TAU), here.generalized_forces(Q, DQ, TAU)),
        (eng.generalized_forces(Q, DQ), here.generalized_forces(Q, DQ)),
        (eng.constraint_jacobian(Q), here.constraint_jacobian(Q)),
        (eng.constraint_bias(Q, DQ), here.constraint_bias(Q, DQ)),
        (eng.forward_acceleration(Q, DQ, TAU), here.forward_acceleration(Q, DQ, TAU)),
        (eng.forward_acceleration(Q, DQ), here.forward_acceleration(Q, DQ)),
        (eng.eigenvalues([1.0, 2.5]), here.eigenvalues([1.0, 2.5])),
    ]
    for got, want in pairs:
        assert got.shape == want.shape and np.array_equal(got, want)
    run, run_here = eng.simulate("zigzag", samples=4), here.simulate("zigzag", samples=4)
    assert run.message == run_here.message == "zigzag with [('samples', 4)]"
    assert np.array_equal(run.t, run_here.t) and np.array_equal(run.q, run_here.q)
    assert inline == [7.0] * 13 and eng.broken is None
