"""Planted user bugs: ports of the bicycle, each correct but for one mistake a researcher makes.

Every engine here is the third-party numpy port (`examples/numpy_engine`: Newton-Euler on joint
axes, its own kinematics, its own constrained solve) with one function written wrong, the way
the mistake is made in a port: a sign in the gravity of the generalized forces only, a torque
applied to the frame instead of the wheel, M filled as its upper triangle, a forward solve
without the constraint rows, the head angle converted to radians twice in the port's own
conversion of the benchmark's Table 1, ... The port's functions call each other as a real
engine's do (the forward solve uses the same M, F, D and dD dq its methods return), so the
mistake shows wherever it would. `tests/test_diagnose_planted.py` checks that ``bicycle-xval
diagnose`` names each one.

Self-contained (numpy, `engines.base` and the example; no relative imports) so that each class
also loads from the command line:
``bicycle-xval diagnose --model thesis --engine tests/planted/engines.py:GravitySignInForces``.
"""

from __future__ import annotations

import contextlib
import importlib.util
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from engines.base import EngineError

__all__ = ["PLANTED", "CONTROLS", "PortedBicycle", "Table1Port"]

_EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "numpy_engine" / "numpy_bicycle" / "engine.py"


def _example():
    name = "planted_numpy_bicycle"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, _EXAMPLE)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


_np = _example()
_State, N_Q, E_X, E_Y, E_Z = _np._State, _np.N_Q, _np.E_X, _np.E_Y, _np.E_Z
THETA, PSI, BETA, GAMMA = _np.THETA, _np.PSI, _np.BETA, _np.GAMMA
NAMES = ("R_rear", "R_front", "x3", "z3", "xa", "za", "dx4", "dz4", "x5", "z5", "m2", "m3", "m4",
         "m5", "I2xx", "I2yy", "I2zz", "I3xx", "I3yy", "I3zz", "I3xz", "I4xx", "I4yy", "I4zz",
         "I4xz", "I5xx", "I5yy", "I5zz", "g", "cv")


class PortedBicycle(_np.NumpyEngine):
    """The port without a mistake (a control): its parameters come from `values`, and its
    forces, M, D and dD dq go through one function each, which the forward solve reuses."""

    name = "ported"
    option = None      # the example's own planted-bug option, if any

    def __init__(self, model):
        super().__init__(model, bug=self.option)
        p = self.p = SimpleNamespace(**self.values(model))
        self.mass = {2: p.m2, 3: p.m3, 4: p.m4, 5: p.m5}
        self.inertia = {2: np.diag([p.I2xx, p.I2yy, p.I2zz]),
                        3: np.array([[p.I3xx, 0, p.I3xz], [0, p.I3yy, 0], [p.I3xz, 0, p.I3zz]]),
                        4: np.array([[p.I4xx, 0, p.I4xz], [0, p.I4yy, 0], [p.I4xz, 0, p.I4zz]]),
                        5: np.diag([p.I5xx, p.I5yy, p.I5zz])}

    def values(self, model) -> dict[str, float]:
        """The port's parameter table (here: read from the model)."""
        return {n: float(getattr(model.params, n)) for n in NAMES}

    @contextlib.contextmanager
    def _using(self, **changes):
        """Run with some parameters read differently (a port that types one value twice)."""
        saved = self.p
        self.p = SimpleNamespace(**{**vars(saved), **changes})
        try:
            yield
        finally:
            self.p = saved

    def _F(self, s, T):
        return self._Qv(s) + self._Qgrav(s) + self._applied(s, T)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        return self._each(lambda q, dq, T: self._F(_State(self, q, dq), T), q, dq, torques)

    def _accelerations(self, q, dq, T, a1=0.0, a2=0.0):
        s = _State(self, q, dq)
        M, D, bias = self._M(q, s), self._D(q, s), self._bias(s)
        Ddq = D @ dq
        C = np.concatenate([[(s.rG5 - self.p.R_front * self._front_direction(s))[2]], Ddq[1:]])
        K = np.zeros((N_Q + 5, N_Q + 5))
        K[:N_Q, :N_Q], K[:N_Q, N_Q:], K[N_Q:, :N_Q] = M, D.T, D
        rhs = np.concatenate([self._F(s, T), -bias - 2.0 * a1 * Ddq - a2 * a2 * C])
        return np.linalg.solve(K, rhs)[:N_Q], C


class Table1Port(PortedBicycle):
    """A port of the benchmark bicycle that converts Table 1 (Meijaard et al. 2007) to the
    thesis's parameters itself, by geometry: the frame's axes are the global ones tilted back
    by lam, A is the foot of the perpendicular from the front hub to the steering axis, every
    offset is taken in frame axes, the tensors (z down in Table 1) rotated into them."""

    name = "ported-table1"

    def table(self, model) -> dict[str, float]:
        """Table 1 as the port reads it (lam in rad)."""
        if model.params.benchmark is None:
            raise EngineError(f"{type(self).__name__} converts Table 1 itself: load a model built "
                              "from Table 1 (e.g. 'benchmark')")
        return model.params.benchmark.as_dict()

    def values(self, model) -> dict[str, float]:
        t = SimpleNamespace(**self.table(model))
        x = np.array([math.cos(t.lam), 0.0, math.sin(t.lam)])       # frame x, global (z up)
        z = np.array([-math.sin(t.lam), 0.0, math.cos(t.lam)])      # steering axis
        G2, G5 = np.array([0.0, 0.0, t.rR]), np.array([t.w, 0.0, t.rF])
        B, H = np.array([t.xB, 0.0, -t.zB]), np.array([t.xH, 0.0, -t.zH])
        P = np.array([t.w + t.c, 0.0, 0.0])                         # axis meets the ground
        A = P + ((G5 - P) @ z) * z

        def comps(d):
            return float(d @ x), float(d @ z)

        def tensor(xx, yy, zz, xz_down):
            I = np.array([[xx, 0.0, -xz_down], [0.0, yy, 0.0], [-xz_down, 0.0, zz]])
            R = np.column_stack([x, [0.0, 1.0, 0.0], z])
            J = R.T @ I @ R
            return J[0, 0], J[1, 1], J[2, 2], J[0, 2]

        v = dict(R_rear=t.rR, R_front=t.rF, m2=t.mR, m3=t.mB, m4=t.mH, m5=t.mF, g=t.g, cv=0.0,
                 I2xx=t.IRxx, I2yy=t.IRyy, I2zz=t.IRxx, I5xx=t.IFxx, I5yy=t.IFyy, I5zz=t.IFxx)
        v["x3"], v["z3"] = comps(B - G2)
        v["xa"], v["za"] = comps(A - G2)
        v["dx4"], v["dz4"] = comps(H - A)
        v["x5"], v["z5"] = comps(G5 - A)
        v["I3xx"], v["I3yy"], v["I3zz"], v["I3xz"] = tensor(t.IBxx, t.IByy, t.IBzz, t.IBxz)
        v["I4xx"], v["I4yy"], v["I4zz"], v["I4xz"] = tensor(t.IHxx, t.IHyy, t.IHzz, t.IHxz)
        return {n: float(v[n]) for n in NAMES}


# -- the terms' signs and missing terms -------------------------------------------------------

class GravitySignInForces(PortedBicycle):
    """gravity() is right; generalized_forces subtracts the gravity instead of adding it."""

    name = "planted-gravity-sign-in-forces"

    def _F(self, s, T):
        return self._Qv(s) - self._Qgrav(s) + self._applied(s, T)


class GravityMissingInForces(PortedBicycle):
    """generalized_forces forgets the gravity (gravity() has it)."""

    name = "planted-gravity-missing-in-forces"

    def _F(self, s, T):
        return self._Qv(s) + self._applied(s, T)


class GravitySign(PortedBicycle):
    """The weight taken as +m g e_z (z up) everywhere."""

    name = "planted-gravity-sign"

    def _Qgrav(self, s):
        return -super()._Qgrav(s)


class VelocityForcesSign(PortedBicycle):
    """Qv with the sign of the bias accelerations' side: +sum m Jv^T a + Jw^T (...)."""

    name = "planted-qv-sign"

    def _Qv(self, s):
        return -super()._Qv(s)


class VelocityForcesMissing(PortedBicycle):
    """No velocity-product forces at all (a 'quasi-static' port)."""

    name = "planted-qv-missing"

    def _Qv(self, s):
        return np.zeros(N_Q)


class _Applied(PortedBicycle):
    """The drag and rider torques written out, so one of them can be got wrong."""

    drag_sign = -1.0
    bodies = {"Mdir": 4, "Mped": 2, "Mvue": 3}
    signs = {"Mdir": 1.0, "Mped": 1.0, "Mvue": 1.0}
    AXES = {"Mdir": E_Z, "Mped": E_Y, "Mvue": E_X}

    def _applied(self, s, T):
        Jv3, _ = s.jacobians(3, s.com[3])
        v3 = Jv3 @ s.dq
        Q = self.drag_sign * self.p.cv * np.sqrt(v3 @ v3) * (Jv3.T @ v3)
        for k, name in enumerate(("Mdir", "Mped", "Mvue")):
            b = self.bodies[name]
            Jw = s.jacobians(b, s.com[b])[1]
            Q = Q + self.signs[name] * (Jw.T @ (s.A[b] @ self.AXES[name])) * T[k]
        return Q


class DragSign(_Applied):
    """The drag pushes forward: +cv |v| v."""

    name = "planted-drag-sign"
    drag_sign = 1.0


class DragMissing(_Applied):
    """No drag."""

    name = "planted-drag-missing"
    drag_sign = 0.0


class SteerTorqueSign(_Applied):
    """The steer torque Mdir applied the other way round."""

    name = "planted-steer-torque-sign"
    signs = {**_Applied.signs, "Mdir": -1.0}


class PedalTorqueOnFrame(_Applied):
    """The pedal torque Mped applied to the frame instead of the rear wheel."""

    name = "planted-pedal-on-frame"
    bodies = {**_Applied.bodies, "Mped": 3}


class RollTorqueOnFork(_Applied):
    """The anti-roll torque Mvue applied to the fork (about its x) instead of the frame."""

    name = "planted-roll-on-fork"
    bodies = {**_Applied.bodies, "Mvue": 4}


# -- the constraints --------------------------------------------------------------------------

class ConstraintJacobianSign(PortedBicycle):
    """D with every row's sign flipped (the constraints written as 0 = -v)."""

    name = "planted-d-sign"

    def _D(self, q, s=None):
        return -super()._D(q, s)


class BiasSign(PortedBicycle):
    """dD dq with its sign flipped (moved to the other side of D ddq = -dD dq twice)."""

    name = "planted-bias-sign"

    def _bias(self, s):
        return -super()._bias(s)


class BiasMissing(PortedBicycle):
    """dD dq left out (D ddq = 0)."""

    name = "planted-bias-missing"

    def _bias(self, s):
        return np.zeros(5)


class BiasRearRadius(Table1Port):
    """dD dq written with the rear wheel's radius for the front contact; D has the front's."""

    name = "planted-bias-rear-radius"

    def _bias(self, s):
        with self._using(R_front=self.p.R_rear):
            return super()._bias(s)


# -- the mass matrix and the solve ------------------------------------------------------------

class MassMatrixSwapped(PortedBicycle):
    """M evaluated with theta and gamma swapped (the state unpacked in the wrong order)."""

    name = "planted-m-swapped"

    def _M(self, q, s=None):
        q = np.array(q, dtype=float)
        q[[THETA, GAMMA]] = q[[GAMMA, THETA]]
        return super()._M(q)


class MassMatrixUpper(PortedBicycle):
    """M filled for j >= i only (a symmetric matrix's upper triangle, the lower left zero)."""

    name = "planted-m-upper"

    def _M(self, q, s=None):
        return np.triu(super()._M(q, s))


class UnconstrainedSolve(PortedBicycle):
    """forward_acceleration solves M ddq = F, forgetting the constraint rows."""

    name = "planted-unconstrained-solve"

    def _accelerations(self, q, dq, T, a1=0.0, a2=0.0):
        s = _State(self, q, dq)
        C = np.zeros(5)
        return np.linalg.solve(self._M(q, s), self._F(s, T)), C


class MassMatrixLower(PortedBicycle):
    """M filled for j <= i only (its lower triangle, the upper right zero): the mirror image
    of `MassMatrixUpper`'s mistake."""

    name = "planted-m-lower"

    def _M(self, q, s=None):
        return np.tril(super()._M(q, s))


class SolveBiasSign(PortedBicycle):
    """forward_acceleration solves the constraint rows as D ddq = +dD dq, the bias's sign
    flipped in the solve alone (constraint_bias itself is right)."""

    name = "planted-solve-bias-sign"

    def _accelerations(self, q, dq, T, a1=0.0, a2=0.0):
        s = _State(self, q, dq)
        F = self._Qv(s) + self._Qgrav(s) + self._applied(s, T)
        D = self._D(q, s)
        K = np.zeros((N_Q + 5, N_Q + 5))
        K[:N_Q, :N_Q], K[:N_Q, N_Q:], K[N_Q:, :N_Q] = self._M(q, s), D.T, D
        ddq = np.linalg.solve(K, np.concatenate([F, +self._bias(s)]))[:N_Q]
        return ddq, np.zeros(5)


class InverseDynamicsSign(PortedBicycle):
    """inverse_dynamics returns -M ddq - Qv - Qgrav: the inertial term's sign flipped there
    alone (mass_matrix and the forward solve are right)."""

    name = "planted-inverse-dynamics-sign"

    def inverse_dynamics(self, q, dq, ddq):
        def one(q, dq, ddq):
            s = _State(self, q, dq)
            return -self._M(q, s) @ ddq - self._Qv(s) - self._Qgrav(s)
        return self._each(one, q, dq, ddq)


# -- the parameters ---------------------------------------------------------------------------

class _Typo(PortedBicycle):
    changes: dict = {}

    def values(self, model):
        v = super().values(model)
        return {**v, **{k: (f(v) if callable(f) else f) for k, f in self.changes.items()}}


class FrameProductSign(_Typo):
    """I3xz with the other sign convention."""

    name = "planted-i3xz-sign"
    changes = {"I3xz": lambda v: -v["I3xz"]}


class WheelInertiasSwapped(_Typo):
    """The rear wheel's diametral and polar inertias swapped."""

    name = "planted-i2-swapped"
    changes = {"I2xx": lambda v: v["I2yy"], "I2yy": lambda v: v["I2xx"]}


class StandardGravity(_Typo):
    """g = 9.80665 (standard gravity) for the thesis's 9.81."""

    name = "planted-standard-gravity"
    changes = {"g": 9.80665}


class DragCoefficient(_Typo):
    """cv = 0.08 for 0.8 (a digit dropped)."""

    name = "planted-drag-coefficient"
    changes = {"cv": lambda v: v["cv"] / 10}


class ForkMass(_Typo):
    """m4 = 1.275 kg for 1.725 kg (two digits exchanged)."""

    name = "planted-fork-mass"
    changes = {"m4": 1.275}


class ForkMassForward(_Typo):
    """The fork's centre of mass put 5 mm ahead of the steering axis (dx4 = 0.005 m for the
    thesis's 0: a parameter whose value is zero, where diagnose's derivative takes an
    absolute step)."""

    name = "planted-fork-mass-forward"
    changes = {"dx4": 0.005}


class NoGyroscopic(PortedBicycle):
    """The gyroscopic torques w x (I w) left out of Qv (the example's own option)."""

    name = "planted-no-gyroscopic"
    option = "gyroscopic"


# -- the benchmark's Table 1, converted by the port ------------------------------------------

class _Table1Slip(Table1Port):
    slip: dict = {}

    def table(self, model):
        t = super().table(model)
        return {**t, **{k: f(t[k]) for k, f in self.slip.items()}}


class HeadAngleTwice(_Table1Slip):
    """lam converted to radians although Table 1 gives it in radians already."""

    name = "planted-head-angle-twice"
    slip = {"lam": math.radians}


class HeadAngleForTilt(_Table1Slip):
    """The head angle pi/2 - lam taken for the steer axis tilt lam."""

    name = "planted-head-angle-for-tilt"
    slip = {"lam": lambda lam: math.pi / 2 - lam}


class TrailSign(_Table1Slip):
    """The trail c entered with its sign flipped (the axis meets the ground behind the contact)."""

    name = "planted-trail-sign"
    slip = {"c": lambda c: -c}


class WheelbaseTypo(_Table1Slip):
    """w = 1.03 m for 1.02 m."""

    name = "planted-wheelbase"
    slip = {"w": lambda w: w + 0.01}


#: planted engine -> (model it is built from, the cause(s) diagnose must name, the terms
#: that must differ); worked out from what each mistake does to the equations, not from
#: diagnose's output
PLANTED = {
    GravitySignInForces: ("thesis", ("sign:Qgrav[F]",), ("Qgrav",)),
    GravityMissingInForces: ("thesis", ("missing:Qgrav[F]",), ("Qgrav",)),
    GravitySign: ("thesis", ("sign:Qgrav",), ("Qgrav",)),
    VelocityForcesSign: ("thesis", ("sign:Qv",), ("Qv",)),
    VelocityForcesMissing: ("thesis", ("missing:Qv",), ("Qv",)),
    DragSign: ("thesis", ("sign:Qaero",), ("Qaero",)),
    DragMissing: ("thesis", ("missing:Qaero",), ("Qaero",)),
    SteerTorqueSign: ("thesis", ("sign:S[Mdir]",), ("S",)),
    PedalTorqueOnFrame: ("thesis", ("body:S[Mped]->3",), ("S",)),
    RollTorqueOnFork: ("thesis", ("body:S[Mvue]->4",), ("S",)),
    ConstraintJacobianSign: ("thesis", ("sign:D",), ("D",)),
    BiasSign: ("thesis", ("sign:dD dq",), ("dD dq",)),
    BiasMissing: ("thesis", ("missing:dD dq",), ("dD dq",)),
    BiasRearRadius: ("benchmark", ("R_front@dD dq",), ("dD dq",)),
    MassMatrixSwapped: ("thesis", ("swap:M:theta,gamma",), ("M",)),
    MassMatrixUpper: ("thesis", ("triangle:M:upper",), ("M",)),
    MassMatrixLower: ("thesis", ("triangle:M:lower",), ("M",)),
    UnconstrainedSolve: ("thesis", ("solve:unconstrained",), ("ddq",)),
    SolveBiasSign: ("thesis", ("solve:bias-sign",), ("ddq",)),
    InverseDynamicsSign: ("thesis", ("sign:M[ID]",), ("M",)),
    FrameProductSign: ("thesis", ("I3xz",), ("M", "Qv")),
    WheelInertiasSwapped: ("thesis", ("I2xx", "I2yy"), ("M", "Qv")),
    StandardGravity: ("thesis", ("g",), ("Qgrav",)),
    DragCoefficient: ("thesis", ("cv",), ("Qaero",)),
    ForkMass: ("thesis", ("m4",), ("M", "Qv", "Qgrav")),
    ForkMassForward: ("thesis", ("dx4",), ("M", "Qv", "Qgrav")),
    NoGyroscopic: ("thesis", ("gyroscopic",), ("Qv",)),
    HeadAngleTwice: ("benchmark", ("table1:lam-deg2rad",), ("M", "Qv", "Qgrav", "D", "dD dq")),
    HeadAngleForTilt: ("benchmark", ("table1:lam-head-angle",), ("M", "Qv", "Qgrav", "D", "dD dq")),
    TrailSign: ("benchmark", ("table1:c-sign",), ("M", "Qv", "Qgrav", "D", "dD dq")),
    WheelbaseTypo: ("benchmark", ("table1:w",), ("M", "Qv", "Qgrav", "D", "dD dq")),
}
#: the ports without a mistake: they must agree
CONTROLS = {PortedBicycle: "thesis", Table1Port: "benchmark"}


class TwoMistakes(GravitySignInForces, DragSign):
    """Two mistakes at once (gravity's sign in the forces, the drag's sign): no single cause
    explains it, and diagnose must say so."""

    name = "planted-two-mistakes"


class RearWheelWeight(PortedBicycle):
    """The rear wheel's weight taken 1.5 times (its tyre and tube counted twice) in the gravity
    alone. In Qgrav the rear wheel's mass and the rear radius act alike: the hub's height is
    R_rear cos(theta), and R_rear lifts every body by the same cos(theta), so both changes are
    one vector, ``-g (dm2 R_rear + M dR_rear) d cos(theta)/dq``; no comparison of the terms can
    tell them apart, and diagnose must say so instead of naming one."""

    name = "planted-rear-wheel-weight"

    def _Qgrav(self, s):
        saved = self.mass
        self.mass = {**saved, 2: 1.5 * saved[2]}
        try:
            return super()._Qgrav(s)
        finally:
            self.mass = saved


class CannotRepresent(PortedBicycle):
    """A port that declares it cannot represent the model (as MuJoCo for an inertia that breaks
    A + B >= C): diagnose leaves it out with the reason, as a run does."""

    name = "planted-cannot-represent"

    def __init__(self, model):
        from engines import UnsupportedModel
        raise UnsupportedModel("its bodies cannot take this model's inertias (declared for the "
                               "test)")


class LinearDrag(_Applied):
    """The drag as -cv v instead of -cv |v| v. No candidate is this mistake; at the states'
    speeds (10 to 40 m/s at the frame) it is nearly a much smaller cv, which diagnose may name,
    but it must say that the cause is near, not exact."""

    name = "planted-linear-drag"

    def _applied(self, s, T):
        Jv3, _ = s.jacobians(3, s.com[3])
        v3 = Jv3 @ s.dq
        return super()._applied(s, T) + self.p.cv * (np.sqrt(v3 @ v3) - 1.0) * (Jv3.T @ v3)
