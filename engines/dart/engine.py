"""DART's terms of the thesis tree, and forward runs with DART's own contact.

    from engines import load_engine
    eng = load_engine("dart", model)                # options: the run's settings (`options`)
    eng.mass_matrix(q); eng.constraint_bias(q, dq); eng.forward_acceleration(q, dq)
    traj = eng.simulate(SCENARIOS["stability-psid5"])   # disc-contact models only

The skeleton is DART's URDF loader's reading of the project's own URDF export, with the loader's
defaults that do not fit the bicycle set explicitly (`skeleton`: zero default inertia, a welded
root, the thesis's order of the coordinates); the terms are DART's dynamics and Jacobians
(`terms`); ``forward`` solves the thesis's constrained system on them, so the reference's
solvers (`reference_model.scenarios.run_forward`) can integrate DART's terms. ``simulate`` is
DART's own time stepping with its frictional LCP contact of two thin cylinders on a ground box
(`run`), a declared model difference (``run_difference``), studied by the soft-contact study
(`contact_study`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from reference_model import Model
from reference_model.model import ForwardResult, torque_array

from ..base import CAPABILITIES, CapabilityError, Engine
from ..facts import Costs, RunSetup
from ..linear import DifferenceEigenvalues
from .contact_study import SOFT_CONTACT
from .options import DEFAULTS, RunSettings
from .skeleton import build_skeleton
from .terms import N_C, N_Q, TermsOf

__all__ = ["DartEngine"]

RUN_ONLY = frozenset({"simulate"})


def _each(fn, n_vectors: int, *arrays):
    """fn on one state, or row by row on a batch (the first array's leading axis); the first
    ``n_vectors`` arguments are (8,)-vectors per state, the rest are passed as they are."""
    first = np.asarray(arrays[0], dtype=float)
    if first.ndim == 1:
        return fn(*(np.asarray(a, dtype=float) for a in arrays[:n_vectors]), *arrays[n_vectors:])
    n = first.shape[0]
    rows = [np.broadcast_to(np.asarray(a, dtype=float), (n, N_Q)) for a in arrays[:n_vectors]]
    return np.array([fn(*(r[i] for r in rows), *(x[i] for x in arrays[n_vectors:]))
                     for i in range(n)])


class DartEngine(DifferenceEigenvalues, Engine):
    """M, inverse dynamics, gravity, forces, rolling constraints and constrained accelerations
    from DART; forward runs on DART's contact (disc-contact models)."""

    name = "dart"
    capabilities = frozenset(CAPABILITIES)
    run_difference = ("LCP contact: DART's wheels touch the ground through its rigid, frictional, "
                      "unilateral contact (time-stepped, an LCP per step), not the reference's "
                      "ideal rolling constraint (they slip, sink by the solver's error and can "
                      "lift off)")
    label = "DART"
    colour = "tab:brown"
    marker = "h"
    run_setups = (RunSetup(kinds=("forward",), settings=(
        f"DART's own contact (disc-contact models only): cylinders of half-width "
        f"{DEFAULTS.wheel_half_width:g} m on a ground box, {DEFAULTS.collision_detector} collision "
        f"detector, {DEFAULTS.solver} boxed LCP, friction {DEFAULTS.friction:g}, time step "
        f"{DEFAULTS.timestep:g} s (semi-implicit Euler)")),)
    #: measured (load 6): 1.1 s per simulated second, terms 1.6 s, faults 5.4 s (run --quick)
    costs = Costs(run_per_second=1.1, short_run=0.8, terms=1.6, faults=5.4)
    soft_contact = SOFT_CONTACT
    #: the conformance checks DART is expected to fail, with the reason (read by the plugin)
    conformance_xfails = Path(__file__).with_name("conformance_xfails.txt")

    def __init__(self, model: Model, timestep: float = DEFAULTS.timestep,
                 collision_detector: str = DEFAULTS.collision_detector,
                 friction: float = DEFAULTS.friction, solver: str = DEFAULTS.solver,
                 wheel_half_width: float = DEFAULTS.wheel_half_width,
                 split_impulse: bool = DEFAULTS.split_impulse):
        super().__init__(model)
        self.settings = RunSettings.checked(
            timestep=timestep, collision_detector=collision_detector, friction=friction,
            solver=solver, wheel_half_width=wheel_half_width, split_impulse=split_impulse)
        self.skeleton, self.dofs = build_skeleton(model.params)
        self._terms = TermsOf(self.skeleton, self.dofs, model.params,
                              model.contact == "disc")
        # duck-typed attributes the reference solvers read
        self.params, self.contact = model.params, model.contact
        # DART's runs approximate the rolling disc (cylinders on the ground); the thesis's
        # fork-axis front contact has no counterpart in a collision detector
        if model.contact != "disc":
            self.capabilities = frozenset(CAPABILITIES) - RUN_ONLY

    def __repr__(self) -> str:
        return (f"DartEngine(model={self.model.name!r}, contact={self.model.contact!r}, "
                f"timestep={self.settings.timestep!r}, "
                f"collision_detector={self.settings.collision_detector!r})")

    # -- rigid-body terms --------------------------------------------------------------
    def mass_matrix(self, q):
        return _each(self._terms.mass_matrix, 1, q)

    def inverse_dynamics(self, q, dq, ddq):
        return _each(self._terms.inverse_dynamics, 3, q, dq, ddq)

    def gravity(self, q):
        return _each(self._terms.gravity, 1, q)

    def S(self, q):
        return _each(self._terms.S, 1, q)

    def _forces(self, q, dq, T):
        return self._terms.kinematics(q, dq, T, False).Q + self._terms.bias_forces(q, dq)

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        single = np.ndim(q) == 1
        T = torque_array(torques, 1 if single else np.shape(q)[0], single)
        return _each(self._forces, 2, q, dq, T[0] if single else T)

    # -- rolling constraints -----------------------------------------------------------
    def constraint_residual(self, q, dq):
        return _each(lambda a, b: self._terms.kinematics(a, b, (), False, False).C, 2, q, dq)

    def constraint_jacobian(self, q):
        return _each(lambda a: self._terms.kinematics(a, np.zeros(N_Q), (), False, False).D,
                     1, q)

    def constraint_bias(self, q, dq):
        return _each(lambda a, b: self._terms.kinematics(a, b, (), True, False).bias, 2, q, dq)

    # -- the thesis's constrained system on DART's terms ----------------------------------
    def _forward_one(self, q, dq, T, a1, a2):
        if not (np.isfinite(q).all() and np.isfinite(dq).all() and np.isfinite(T).all()):
            return np.full(N_Q, np.nan), np.full(N_C, np.nan), 2
        k = self._terms.kinematics(q, dq, T, True)
        F = k.Q + self._terms.bias_forces(q, dq)
        A = np.zeros((N_Q + N_C, N_Q + N_C))
        A[:N_Q, :N_Q] = self._terms.mass_matrix(q)
        A[:N_Q, N_Q:], A[N_Q:, :N_Q] = k.D.T, k.D
        b = np.concatenate([F, -k.bias - 2.0 * a1 * k.Ddq - a2 * a2 * k.C])
        try:
            x = np.linalg.solve(A, b)
        except np.linalg.LinAlgError:
            return np.full(N_Q, np.nan), np.full(N_C, np.nan), 1
        # a finite state whose solve overflows: 2, as the reference's kernel reports it
        return x[:N_Q], x[N_Q:], 0 if np.isfinite(x).all() else 2

    def forward(self, q, dq, torques=(0.0, 0.0, 0.0), baumgarte=(0.0, 0.0)) -> ForwardResult:
        """[M D'; D 0][ddq; lambda] = [F + S T; -dD dq - 2 a1 D dq - a2^2 C] on DART's M, F, D
        and dD dq (the duck-typed method the reference's solvers call). Status per state: 0 ok,
        1 singular, 2 the state or the result not finite; never raises."""
        a1, a2 = float(baumgarte[0]), float(baumgarte[1])
        q = np.asarray(q, dtype=float)
        single = q.ndim == 1
        n = 1 if single else q.shape[0]
        T = torque_array(torques, n, single)
        qs = q.reshape(n, N_Q)
        dqs = np.broadcast_to(np.asarray(dq, dtype=float), (n, N_Q))
        res = [self._forward_one(qs[i], dqs[i], T.reshape(n, 3)[i], a1, a2) for i in range(n)]
        ddq, lam = np.array([r[0] for r in res]), np.array([r[1] for r in res])
        status = np.array([r[2] for r in res], dtype=np.intc)
        return ForwardResult(ddq[0], lam[0], status) if single else ForwardResult(ddq, lam, status)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        res = self.forward(q, dq, torques)
        if res.status.any():
            k = int(np.flatnonzero(res.status)[0])
            raise ArithmeticError(f"engine 'dart': at state {k} " + (
                "the constrained system is singular" if res.status[k] == 1
                else "the state or the result is not finite"))
        return res.ddq

    # -- scenarios ---------------------------------------------------------------------
    def simulate(self, scenario, **options):
        from ..stepping import refuse_fork_axis_contact
        refuse_fork_axis_contact(self)
        from .run import simulate
        return simulate(self, scenario, **options)
