"""Hostile engines: the reference model as an engine, with one call made to misbehave.

Each class breaks the call named by its option ``call`` (default ``mass_matrix``; any
capability, ``simulate`` included) in one way an engine from someone else can: the wrong
shape, ``None``, a string, complex values, a NaN, an exception with a 10^6-character message,
``sys.exit(3)``, its own ``KeyboardInterrupt``, ``os._exit(7)`` (the process ends there and
then, like a segfault), or a sleep past any stage's time limit. Every other call is the
reference's, so the breakage is the only difference a run can see.
``SimulateDiverges`` raises "solver diverged" on every scenario, ``SimulateFailsEarly``
returns status 'failed' after 3 samples: runs that were asked for and not made; the
``...Trajectory`` / ``...InSimulate`` classes break ``simulate`` by default, ``ExitsInInit``
its constructor.

Self-contained (numpy and the project's packages only) so that each class loads from the
command line: ``bicycle-xval run --quick --engines pinocchio,tests/hostile/engines.py:Nan``.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import time

import numpy as np

from engines.reference import ReferenceEngine

__all__ = ["HOSTILE", "IN_ONE_RUN", "Complex", "ComplexTrajectory", "DeclaresLimit", "Dies",
           "DiesInSimulate",
           "Exits", "ExitsInInit", "Interrupts", "LongMessage", "Nan", "NanTrajectory",
           "ReturnsNone", "ReturnsString", "SimulateDiverges", "SimulateFailsEarly", "Sleeps",
           "WrongShape", "WrongShapeTrajectory"]

#: how long `Sleeps` sleeps (s): past the short --stage-timeout the tests give, far below the
#: time a test may take if the limit did not work (the test's own timeout then fails it)
SLEEP = 600.0


class _Broken(ReferenceEngine):
    """The reference with ``call`` replaced by `wrong`."""

    name = "hostile"
    CALL = "mass_matrix"     # the call broken unless the option says another

    def __init__(self, model, call: str = ""):
        super().__init__(model)
        call = call or self.CALL
        if call not in self.capabilities:
            raise ValueError(f"call {call!r} is not a capability")
        self.call = call

    def wrong(self, right):
        """What the broken call does instead, given the right value's thunk."""
        raise NotImplementedError

    def _do(self, call, *args, **kwargs):
        right = lambda: getattr(ReferenceEngine, call)(self, *args, **kwargs)  # noqa: E731
        return self.wrong(right) if call == self.call else right()

    def mass_matrix(self, q):
        return self._do("mass_matrix", q)

    def inverse_dynamics(self, q, dq, ddq):
        return self._do("inverse_dynamics", q, dq, ddq)

    def gravity(self, q):
        return self._do("gravity", q)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._do("generalized_forces", q, dq, torques)

    def constraint_jacobian(self, q):
        return self._do("constraint_jacobian", q)

    def constraint_bias(self, q, dq):
        return self._do("constraint_bias", q, dq)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._do("forward_acceleration", q, dq, torques)

    def simulate(self, scenario, **options):
        return self._do("simulate", scenario, **options)


class WrongShape(_Broken):
    name = "wrong-shape"

    def wrong(self, right):
        v = right()
        return v.t if self.call == "simulate" else np.asarray(v)[..., :3]


class ReturnsNone(_Broken):
    name = "returns-none"

    def wrong(self, right):
        return None


class ReturnsString(_Broken):
    name = "returns-string"

    def wrong(self, right):
        return "M"


class Complex(_Broken):
    """Complex values with a non-zero imaginary part (np.real would drop it silently)."""

    name = "complex"

    def wrong(self, right):
        v = right()
        if self.call == "simulate":
            return dataclasses.replace(v, q=v.q + 1e-3j)
        return np.asarray(v) + 1e-3j


class Nan(_Broken):
    name = "nan"

    def wrong(self, right):
        v = right()
        if self.call == "simulate":
            q = v.q.copy()
            q[-1, 3] = np.nan
            return dataclasses.replace(v, q=q)
        v = np.array(v, dtype=float)
        v.flat[0] = np.nan
        return v


class LongMessage(_Broken):
    """Raises with a message of 10^6 characters over 200,000 lines."""

    name = "long-message"

    def wrong(self, right):
        raise RuntimeError("solver diverged\n" + "x" * 4 + ("\nxxxx" * 199_999))


class Exits(_Broken):
    name = "exits"

    def wrong(self, right):
        sys.exit(3)


class Interrupts(_Broken):
    name = "interrupts"

    def wrong(self, right):
        raise KeyboardInterrupt


class Dies(_Broken):
    """Ends its process on the spot (as a segfault in a C library would)."""

    name = "dies"

    def wrong(self, right):
        os._exit(7)


class Sleeps(_Broken):
    name = "sleeps"

    def wrong(self, right):
        time.sleep(SLEEP)
        return right()


class SimulateDiverges(ReferenceEngine):
    """Every forward run raises."""

    name = "simulate-diverges"

    def simulate(self, scenario, **options):
        raise RuntimeError("solver diverged")


class SimulateFailsEarly(ReferenceEngine):
    """Every forward run returns status 'failed' after 3 samples."""

    name = "simulate-fails-early"

    def simulate(self, scenario, **options):
        traj = super().simulate(scenario, **options)
        cut = {f: getattr(traj, f)[:3] for f in ("t", "q", "dq", "ddq", "C", "T")}
        return dataclasses.replace(traj, **cut, status="failed", message="solver gave up",
                                   t_end=float(traj.t[2]), diagnostics={})


class WrongShapeTrajectory(WrongShape):
    name, CALL = "wrong-shape-trajectory", "simulate"


class ComplexTrajectory(Complex):
    name, CALL = "complex-trajectory", "simulate"


class NanTrajectory(Nan):
    name, CALL = "nan-trajectory", "simulate"


class DiesInSimulate(Dies):
    name, CALL = "dies-in-simulate", "simulate"


class DeclaresLimit(ReferenceEngine):
    """A control: simulate raises CapabilityError, a declared limitation (not a failure)."""

    name = "declares-limit"

    def simulate(self, scenario, **options):
        from engines.base import CapabilityError
        raise CapabilityError("declares-limit cannot run forward scenarios on this model")


class ExitsInInit(ReferenceEngine):
    """sys.exit(4) while being built."""

    name = "exits-in-init"

    def __init__(self, model):
        sys.exit(4)


HOSTILE = (WrongShape, ReturnsNone, ReturnsString, Complex, Nan, LongMessage, Exits, Interrupts,
           Dies, Sleeps)
#: what one `run` beside the reference and Pinocchio holds (tests/test_hostile_engines.py)
IN_ONE_RUN = HOSTILE + (WrongShapeTrajectory, ComplexTrajectory, NanTrajectory, DiesInSimulate,
                        SimulateDiverges, SimulateFailsEarly, ExitsInInit)
