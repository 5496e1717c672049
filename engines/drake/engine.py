"""Drake's terms of the thesis tree (a MultibodyPlant from the URDF export), and forward runs
on Drake's own wheel-ground contact.

    from engines import load_engine
    eng = load_engine("drake", model)              # options: the contact run's, see options.py
    eng.mass_matrix(q); eng.inverse_dynamics(q, dq, ddq); eng.constraint_jacobian(q); ...
    traj = eng.simulate(SCENARIOS["stability-psid10"])   # disc-contact models only

What is Drake's and what is ours (the plant and its conventions: `engines.drake.plant`):

* ``mass_matrix``: ``CalcMassMatrix``.
* ``gravity``: ``CalcGravityGeneralizedForces``, tau_g, which Drake puts on the right-hand side
  of M vdot + C v = tau_g + tau_app: the thesis's Qgrav with no sign change.
* ``inverse_dynamics``: ``CalcInverseDynamics`` with no applied forces gives
  M vdot + C v - tau_app and leaves out the force elements, gravity among them; the thesis's
  M ddq - Qv - Qgrav is therefore Drake's result minus tau_g.
* Qv = -``CalcBiasTerm`` (C v); ``generalized_forces`` = Qv + Qgrav + Qaero + S T, the last two
  from Drake's Jacobians (`engines.drake.kinematics`).
* D and dD dq from Drake's point Jacobians and bias accelerations (`engines.drake.kinematics`);
  ``forward_acceleration`` the thesis's KKT system on these terms, solved here (numpy), and the
  duck-typed ``forward`` / ``constraint_residual`` the reference's solvers call.
* ``simulate`` (disc-contact models only; `engines.drake.run`): a discrete plant with a zc
  joint, the wheels as thin cylinders on a half-space with Coulomb friction, Drake's contact
  solver and time stepping.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from reference_model import Model
from reference_model.model import ForwardResult, raise_on_status, torque_array

from pydrake.multibody.tree import MultibodyForces

from ..base import CAPABILITIES, CapabilityError, Engine
from ..batching import batched
from ..facts import Costs, RunSetup
from ..linear import DifferenceEigenvalues
from .contact_study import SOFT_CONTACT
from .kinematics import Kinematics
from .options import DEFAULTS, RunSettings, settings_from
from .plant import refuse_non_physical_inertia, terms_plant

__all__ = ["DrakeEngine"]

N_Q, N_C = 8, 5
TERMS = frozenset(CAPABILITIES) - {"simulate"}


class DrakeEngine(DifferenceEigenvalues, Engine):
    """Drake's MultibodyPlant terms, all exact; forward runs on its own contact (disc only).

    The terms: mass matrix, inverse dynamics, gravity, bias term and frame kinematics; the runs:
    its point or hydroelastic contact on disc-contact models."""

    name = "drake"
    capabilities = frozenset(CAPABILITIES)
    run_difference = ("soft contact: Drake's wheels touch the ground through its compliant, "
                      "frictional, unilateral contact (point or hydroelastic, regularized "
                      "Coulomb friction), not the reference's ideal rolling constraint (they "
                      "slip, sink and can lift off)")
    label = "Drake"
    colour = "tab:green"
    marker = "*"
    run_setups = (RunSetup(kinds=("forward",), settings=(
        f"Drake's own wheel-ground contact (disc-contact models only): thin cylinders on a "
        f"half-space, {DEFAULTS.contact_model} contact, {DEFAULTS.approximation} solver, time "
        f"step {DEFAULTS.time_step:g} s, stiction tolerance {DEFAULTS.stiction_tolerance:g} m/s: "
        "the contact study's closest to ideal rolling; no inverse dynamics")),)
    costs = Costs(run_per_second=0.6, short_run=0.8, terms=2.0, faults=2.0)
    #: its soft contact's study (slip, penetration, lift-off, refinement): `contact_study`
    soft_contact = SOFT_CONTACT
    #: the conformance checks Drake is expected to fail, with the reason (read by the plugin)
    conformance_xfails = Path(__file__).with_name("conformance_xfails.txt")

    def __init__(self, model: Model, time_step: float = DEFAULTS.time_step,
                 approximation: str = DEFAULTS.approximation,
                 contact_model: str = DEFAULTS.contact_model,
                 stiction_tolerance: float = DEFAULTS.stiction_tolerance,
                 friction: float = DEFAULTS.friction,
                 point_stiffness: float = DEFAULTS.point_stiffness,
                 dissipation: float = DEFAULTS.dissipation,
                 hydroelastic_modulus: float = DEFAULTS.hydroelastic_modulus,
                 wheel_half_width: float = DEFAULTS.wheel_half_width):
        super().__init__(model)
        self.settings: RunSettings = settings_from(
            time_step=time_step, approximation=approximation, contact_model=contact_model,
            stiction_tolerance=stiction_tolerance, friction=friction,
            point_stiffness=point_stiffness, dissipation=dissipation,
            hydroelastic_modulus=hydroelastic_modulus, wheel_half_width=wheel_half_width)
        refuse_non_physical_inertia(model.params)
        self.plant, self.mapping = terms_plant(model.params)
        self.context = self.plant.CreateDefaultContext()
        self.kin = Kinematics(self.plant, self.context, self.mapping, model.params, model.contact)
        self._no_forces = MultibodyForces(self.plant)
        # duck-typed attributes the reference solvers read
        self.params, self.contact = model.params, model.contact
        # forward runs approximate the disc contact (a rolling cylinder); the thesis's
        # fork-axis front contact has no counterpart in Drake's contact
        if model.contact != "disc":
            self.capabilities = TERMS

    def __repr__(self) -> str:
        return (f"DrakeEngine(model={self.model.name!r}, contact={self.model.contact!r}, "
                f"time_step={self.settings.time_step!r}, "
                f"approximation={self.settings.approximation!r})")

    # -- batching ----------------------------------------------------------------------
    _batched = staticmethod(batched)

    def _set(self, q, dq=None) -> None:
        self.kin.set_state(self.mapping.q_to_drake(q),
                           self.mapping.v_to_drake(np.zeros(N_Q) if dq is None else dq))

    # -- rigid-body terms --------------------------------------------------------------
    def _M(self, q):
        self._set(q)
        return self.mapping.matrix_from_drake(self.plant.CalcMassMatrix(self.context))

    def mass_matrix(self, q):
        return self._batched(self._M, q)

    def _gravity(self):
        return self.mapping.v_from_drake(self.plant.CalcGravityGeneralizedForces(self.context))

    def gravity(self, q):
        def one(q):
            self._set(q)
            return self._gravity()
        return self._batched(one, q)

    def _inverse_one(self, q, dq, ddq):
        self._set(q, dq)
        tau = self.plant.CalcInverseDynamics(self.context, self.mapping.v_to_drake(ddq),
                                             self._no_forces)
        # Drake's inverse dynamics leaves gravity (a force element) out: subtract Qgrav
        return self.mapping.v_from_drake(tau) - self._gravity()

    def inverse_dynamics(self, q, dq, ddq):
        return self._batched(self._inverse_one, q, dq, ddq)

    def _bias_forces(self):
        """Qv + Qgrav = -C v + tau_g at the context's state."""
        return self.mapping.v_from_drake(-self.plant.CalcBiasTerm(self.context)) + self._gravity()

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        def one(q, dq, T):
            t = self.kin.terms(q, dq, False)
            return self._bias_forces() + t.Qaero + t.S @ T
        single = np.ndim(q) == 1
        T = torque_array(torques, 1 if single else np.shape(q)[0], single)
        return self._batched(one, q, dq, T[0] if single else T)

    # -- rolling constraints -----------------------------------------------------------
    def constraint_residual(self, q, dq):
        return self._batched(lambda a, b: self.kin.terms(a, b, False, False).C, q, dq)

    def constraint_jacobian(self, q):
        return self._batched(lambda a: self.kin.terms(a, np.zeros(N_Q), False, False).D, q)

    def constraint_bias(self, q, dq):
        return self._batched(lambda a, b: self.kin.terms(a, b, True, False).bias, q, dq)

    # -- the thesis's KKT system on Drake's terms ----------------------------------------
    def _forward_one(self, q, dq, T, a1, a2):
        if not (np.isfinite(q).all() and np.isfinite(dq).all() and np.isfinite(T).all()):
            return np.full(N_Q, np.nan), np.full(N_C, np.nan), 2
        t = self.kin.terms(q, dq, True)            # leaves the state set on the context
        M = self.mapping.matrix_from_drake(self.plant.CalcMassMatrix(self.context))
        F = self._bias_forces() + t.Qaero + t.S @ T
        A = np.zeros((N_Q + N_C, N_Q + N_C))
        A[:N_Q, :N_Q], A[:N_Q, N_Q:], A[N_Q:, :N_Q] = M, t.D.T, t.D
        b = np.concatenate([F, -t.bias - 2.0 * a1 * t.Ddq - a2 * a2 * t.C])
        try:
            x = np.linalg.solve(A, b)
        except np.linalg.LinAlgError:
            return np.full(N_Q, np.nan), np.full(N_C, np.nan), 1
        # a finite state whose solve overflows: 2, as the reference's kernel reports it
        return x[:N_Q], x[N_Q:], 0 if np.isfinite(x).all() else 2

    def forward(self, q, dq, torques=(0.0, 0.0, 0.0), baumgarte=(0.0, 0.0)) -> ForwardResult:
        """[M D'; D 0][ddq; lambda] = [F + S T; -dD dq - 2 a1 D dq - a2^2 C] on Drake's terms.
        Status per state: 0 ok, 1 singular, 2 the state or the result not finite (never raises)."""
        a1, a2 = (float(x) for x in baumgarte)
        q = np.asarray(q, dtype=float)
        single = q.ndim == 1
        n = 1 if single else q.shape[0]
        T = torque_array(torques, n, single)
        qs = q.reshape(n, N_Q)
        dqs = np.broadcast_to(np.asarray(dq, dtype=float), (n, N_Q))
        Ts = np.reshape(T, (n, 3))
        res = [self._forward_one(qs[i], dqs[i], Ts[i], a1, a2) for i in range(n)]
        ddq = np.array([r[0] for r in res])
        lam = np.array([r[1] for r in res])
        status = np.array([r[2] for r in res], dtype=np.intc)
        if single:
            return ForwardResult(ddq[0], lam[0], status)
        return ForwardResult(ddq, lam, status)

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        res = self.forward(q, dq, torques)
        if res.status.any():
            raise_on_status(res.status, "drake forward_acceleration")
        return res.ddq

    # -- forward runs on Drake's contact --------------------------------------------------
    def simulate(self, scenario, **options):
        from ..stepping import refuse_fork_axis_contact
        refuse_fork_axis_contact(self)
        from .run import simulate
        return simulate(self, scenario, **options)
