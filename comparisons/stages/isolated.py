"""Engines the main process asks for terms, each call run in a worker of its own.

After the stages, `bicycle-xval run` still asks some engines for terms in its own process (M
along each scenario's reference run, `scenarios.compare_scenarios`; the localization of a
failed term, `faults.localization_lines`). An engine there that ends its process
(``os._exit``, a segfault in its library) or never returns would take the whole report with
it. `isolated(setup, timeout)` is the same `runs.EngineSetup` whose ``build`` returns a
`RemoteEngine`: each capability call builds the engine in a forked worker
(`pool.call_in_worker`), calls it there (guarded: `engines.guard`) and returns the value; a
worker that dies or runs past ``timeout`` becomes an `EngineCallError` naming the engine and
the call, like any other failure of that engine. A call costs a fork and a build (about 40 ms
for Pinocchio on the 2-core machine); the main process makes a handful per engine.

`failures_as_rows` runs one comparison per engine and turns an engine's failure into a failing
comparison row instead of an exception of the whole section.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from engines.base import CAPABILITIES, Engine
from engines.guard import EngineCallError, describe

from ..judgments.rows import Comparison
from .pool import StageTimeout, call_in_worker
from .runs import EngineSetup

__all__ = ["CALL_TIMEOUT", "EngineGone", "IsolatedSetup", "RemoteEngine", "failures_as_rows",
           "isolated", "unjudgeable"]

#: seconds one term call of the main process may take (a build and a batch of ~100 states:
#: well under a second for every engine here; the limit only stops one that never returns)
CALL_TIMEOUT = 60.0


def _plain(setup: EngineSetup) -> EngineSetup:
    return EngineSetup(setup.label, setup.engine, setup.options, setup.kinds, setup.settings)


def _describe_built(setup: EngineSetup, model) -> tuple:
    eng = _plain(setup).build(model)
    return (eng.name, tuple(c for c in CAPABILITIES if c in eng.capabilities),
            tuple(getattr(eng, "contacts", ())), getattr(eng, "run_difference", None))


def _call(setup: EngineSetup, model, name: str, args: tuple, kwargs: dict):
    return getattr(_plain(setup).build(model), name)(*args, **kwargs)


class EngineGone(EngineCallError):
    """An engine's call in a worker ran past its limit or ended the worker."""


def _in_worker(who: str, what: str, timeout: float, func, *args):
    try:
        return call_in_worker(func, *args, time_limit=timeout)
    except StageTimeout as exc:
        raise EngineGone(f"engine {who!r}: {what} {exc}") from None
    except RuntimeError as exc:
        if type(exc) is RuntimeError and "worker process died" in str(exc):
            raise EngineGone(f"engine {who!r}: {what}: {exc}") from None
        raise


class RemoteEngine(Engine):
    """An engine whose every capability runs in a worker of its own (module docstring)."""

    def __init__(self, setup: EngineSetup, model, info: tuple, timeout: float):
        super().__init__(model)
        self.setup, self.timeout = setup, timeout
        self.name, caps, self.contacts, self.run_difference = info
        self.capabilities = frozenset(caps)
        self.broken: str | None = None   # why the calls stopped: an earlier one hung or died

    def _remote(self, name: str, *args, **kwargs):
        if name not in self.capabilities:
            self._missing(name)
        if self.broken is not None:   # it hung or died once: not asked again
            raise EngineCallError(f"engine {self.name!r}: {name} skipped ({self.broken})")
        try:
            return _in_worker(self.name, name, self.timeout, _call, self.setup, self.model,
                              name, args, kwargs)
        except EngineGone as exc:
            self.broken = f"an earlier call failed: {exc}"
            raise

    def mass_matrix(self, q):
        return self._remote("mass_matrix", q)

    def inverse_dynamics(self, q, dq, ddq):
        return self._remote("inverse_dynamics", q, dq, ddq)

    def gravity(self, q):
        return self._remote("gravity", q)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._remote("generalized_forces", q, dq, torques)

    def constraint_jacobian(self, q):
        return self._remote("constraint_jacobian", q)

    def constraint_bias(self, q, dq):
        return self._remote("constraint_bias", q, dq)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._remote("forward_acceleration", q, dq, torques)

    def simulate(self, scenario, **options):
        return self._remote("simulate", scenario, **options)

    def eigenvalues(self, speeds):
        return self._remote("eigenvalues", speeds)


@dataclass(frozen=True)
class IsolatedSetup(EngineSetup):
    """A `runs.EngineSetup` whose engines are `RemoteEngine` s."""

    timeout: float = CALL_TIMEOUT

    def build(self, model):
        info = _in_worker(self.label, "__init__", self.timeout, _describe_built, self, model)
        return RemoteEngine(self, model, info, self.timeout)


def isolated(setup: EngineSetup, timeout: float | None = None) -> EngineSetup:
    """``setup`` with its engines' calls in workers; the reference (the harness's own model,
    the yardstick every comparison needs) stays in this process."""
    if setup.engine == "reference":
        return setup
    return IsolatedSetup(**{f.name: getattr(setup, f.name) for f in dataclasses.fields(setup)},
                         timeout=timeout or CALL_TIMEOUT)


def failures_as_rows(compare, engines: dict, quantity: str, scenario: str,
                     model: str) -> list[Comparison]:
    """``compare({label: engine})`` for each engine of ``engines``: its rows, or one failing row
    naming the engine and the cause when that engine failed (every other engine's rows stay)."""
    out = []
    for label, eng in engines.items():
        try:
            out += compare({label: eng})
        except Exception as exc:   # noqa: BLE001 - that engine's failure, counted
            out.append(Comparison.of({"quantity": "engine call", "scenario": scenario,
                                      "model": model, "engines": [label], "max_error": None,
                                      "tolerance": None, "passed": False,
                                      "localized_to": describe(exc),
                                      "note": f"{label} failed while its {quantity} was compared"}))
    return out


def unjudgeable(ref, scenario, horizons: dict) -> str:
    """Why no engine's run of ``scenario`` can be compared ('' when it can): the reference's
    own run failed or timed out (nothing to compare against), or a forward scenario's
    meaningful-horizon stage did (nothing says how far a comparison means anything)."""
    if not ref.t.size:
        return f"not compared: the reference's run failed ({ref.message})"
    if scenario.kind == "forward" and scenario.name not in horizons and ref.scenario not in horizons:
        return ("not compared: its meaningful-horizon stage failed (see that stage's line on "
                "the progress output; rerun, or give a larger --stage-timeout)")
    return ""
