"""MuJoCo's rigid-body terms of the thesis tree, and forward runs with MuJoCo's own contact.

    from engines import load_engine
    eng = load_engine("mujoco", model)                 # options: the MJCF settings, see below
    eng.mass_matrix(q); eng.inverse_dynamics(q, dq, ddq); eng.gravity(q)
    traj = eng.simulate(SCENARIOS["stability-psid5"])  # disc-contact models only

The model is compiled from the MJCF of `reference_model.export_mjcf` (``mujoco.MjModel.
from_xml_string``), whose joints are the thesis's coordinates in the thesis's order with the
thesis's axes and signs, so MuJoCo's qpos, qvel, qacc *are* q, dq, ddq (checked at build time).
The placeholder masses of the massless links (MuJoCo's compiler refuses a moving body without
mass) are set to exactly zero in the compiled model.

What is MuJoCo's and what is ours:

* ``mass_matrix``: MuJoCo's composite rigid body algorithm (``mj_crb`` after ``mj_kinematics``
  and ``mj_comPos``), made dense by ``mj_fullM``.
* ``inverse_dynamics``: ``mj_inverse`` with contacts disabled (``mjDSBL_CONTACT``; there are
  no other constraints, no springs, damping or armature), whose ``qfrc_inverse`` = M qacc +
  qfrc_bias is the thesis's M ddq - Qv - Qgrav with no sign change.
* ``gravity``: Qgrav = -``mj_rne`` at zero velocity and zero acceleration (MuJoCo's bias force
  there is the gravity *torque*, minus the thesis's generalised force).
* ``simulate`` (models with the disc contact only; see `engines.mujoco.run`): MuJoCo's own
  time stepping and soft frictional contact of two thin cylinders on the ground plane, the
  rider torques and the drag applied by us as body wrenches every step. The chain gets one
  extra joint for it, the rear contact's height ``zc`` (see `mjcf_text`'s ``rear_height``).

Options (each a field of `reference_model.export_mjcf.MjcfSettings`, validated there; a bad
value is an `EngineUsageError`): ``timestep``, ``integrator``, ``solref`` (time constant s,
damping ratio), ``solimp`` (dmin, dmax, width, midpoint, power), ``friction``, ``cone``,
``condim``, ``noslip_iterations``, ``solver``, ``iterations``, ``tolerance``,
``wheel_half_width``. ``solref`` and ``solimp`` also accept text ("2e-3,1" or "2e-3 1"), as
``--engine-option`` gives them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from reference_model import COORDINATES, Model
from reference_model.export_mjcf import MjcfSettings, massless_links, mjcf_text

from ..base import Engine, EngineError, EngineUsageError, UnsupportedModel
from ..facts import Costs, RunSetup
from .contact_study import SOFT_CONTACT
from .options import tuple_option

try:
    import mujoco
except ImportError as exc:  # pragma: no cover - mujoco is a declared dependency
    raise EngineError("the MuJoCo adapter needs the package 'mujoco' (pip install mujoco)") from exc

N_Q = 8
DEFAULTS = MjcfSettings()
TERMS = frozenset({"mass_matrix", "inverse_dynamics", "gravity"})


def compile_mjcf(text: str, links: tuple[str, ...]) -> "mujoco.MjModel":
    """MuJoCo's model of an MJCF text, the placeholder inertials of ``links`` set to zero."""
    try:
        m = mujoco.MjModel.from_xml_string(text)
    except ValueError as exc:
        text = " ".join(str(exc).split())
        if "inertia must satisfy" in text:   # a body MuJoCo cannot represent: declared limitation
            raise UnsupportedModel(
                "MuJoCo requires every body's principal moments of inertia to satisfy the "
                "triangle inequality A + B >= C, and this bicycle's measured inertia breaks it "
                f"(MuJoCo's compiler: {text})") from exc
        raise EngineError(f"MuJoCo did not compile the bicycle's MJCF: {text}") from exc
    for name in links:
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
        m.body_mass[b] = 0.0
        m.body_inertia[b] = 0.0
    return m


class MujocoEngine(Engine):
    """MuJoCo's CRB mass matrix, RNE inverse dynamics, gravity; runs on its contact (disc only).

    Forward runs use MuJoCo's soft wheel-ground contact, which approximates the rolling-disc
    contact; on a model with the thesis's fork-axis front contact the instance offers the
    three terms only."""

    name = "mujoco"
    capabilities = frozenset(TERMS | {"simulate"})
    run_difference = ("soft contact: MuJoCo's wheels touch the ground through a soft, frictional, "
                      "unilateral contact, not the reference's ideal rolling constraint (they "
                      "slip, sink and can lift off)")
    label = "MuJoCo"
    colour = "tab:red"
    marker = "v"
    run_setups = (RunSetup(kinds=("forward",), settings=(
        f"MuJoCo's own soft wheel-ground contact (disc-contact models only): cylinders on a "
        f"plane, {DEFAULTS.cone} cone, condim {DEFAULTS.condim}, solref "
        f"({DEFAULTS.solref[0]:g} s, {DEFAULTS.solref[1]:g}), timestep {DEFAULTS.timestep:g} s, "
        f"{DEFAULTS.integrator}: the contact study's closest to ideal rolling; no inverse "
        "dynamics")),)
    #: per simulated second: its contact study measured 1.6 s for 2.9 simulated s on the
    #: 2-core machine (5.4 s at a load of 6-8, when 1.0 s was declared); its thesis-contact
    #: scenario runs are refused at once
    costs = Costs(run_per_second=0.6, short_run=0.8, terms=1.5, faults=1.0)
    #: its soft contact's study (slip, penetration, lift-off, refinement): `contact_study`
    soft_contact = SOFT_CONTACT
    #: the conformance checks MuJoCo is expected to fail, with the reason (read by the plugin)
    conformance_xfails = Path(__file__).with_name("conformance_xfails.txt")

    def __init__(self, model: Model, timestep: float = DEFAULTS.timestep,
                 integrator: str = DEFAULTS.integrator, solref=DEFAULTS.solref,
                 solimp=DEFAULTS.solimp, friction: float = DEFAULTS.friction,
                 cone: str = DEFAULTS.cone, condim: int = DEFAULTS.condim,
                 noslip_iterations: int = DEFAULTS.noslip_iterations,
                 solver: str = DEFAULTS.solver, iterations: int = DEFAULTS.iterations,
                 tolerance: float = DEFAULTS.tolerance,
                 wheel_half_width: float = DEFAULTS.wheel_half_width):
        super().__init__(model)
        solref, solimp = tuple_option("solref", solref), tuple_option("solimp", solimp)
        try:
            self.settings = MjcfSettings(
                timestep=timestep, integrator=integrator, solref=solref,
                solimp=solimp, friction=friction, cone=cone,
                condim=condim, noslip_iterations=noslip_iterations, solver=solver,
                iterations=iterations, tolerance=tolerance, wheel_half_width=wheel_half_width)
        except (TypeError, ValueError) as exc:
            raise EngineUsageError(f"MuJoCo option: {exc}") from None
        # the thesis's tree, contacts off: the rigid-body terms
        self.mjcf = mjcf_text(model.params, self.settings)
        self.mj_model = m = compile_mjcf(self.mjcf, massless_links(False))
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        names = tuple(m.joint(i).name for i in range(m.njnt))
        if names != COORDINATES or list(m.jnt_qposadr) != list(range(N_Q)) \
                or list(m.jnt_dofadr) != list(range(N_Q)) or m.nq != N_Q or m.nv != N_Q:
            raise EngineError(f"MuJoCo joint order {names} / qpos {list(m.jnt_qposadr)} does not "
                              f"follow the thesis order {COORDINATES}")
        self.data = mujoco.MjData(m)
        self._M = np.zeros((N_Q, N_Q))
        self._rne = np.zeros(N_Q)
        # forward runs only approximate the disc contact (a rolling cylinder); the thesis's
        # fork-axis front contact has no MuJoCo counterpart
        if model.contact != "disc":
            self.capabilities = frozenset(TERMS)
        self._run_models: dict = {}

    def __repr__(self) -> str:
        return (f"MujocoEngine(model={self.model.name!r}, contact={self.model.contact!r}, "
                f"timestep={self.settings.timestep!r}, solref={self.settings.solref!r})")

    # -- batching ----------------------------------------------------------------------
    @staticmethod
    def _batched(fn, *arrays):
        first = np.asarray(arrays[0], dtype=float)
        if first.ndim == 1:
            return fn(*(np.asarray(a, dtype=float) for a in arrays))
        arrs = [np.broadcast_to(np.asarray(a, dtype=float), (first.shape[0], N_Q)) for a in arrays]
        return np.array([fn(*row) for row in zip(*arrs)])

    # -- rigid-body terms --------------------------------------------------------------
    def _mass_one(self, q):
        m, d = self.mj_model, self.data
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_crb(m, d)
        mujoco.mj_fullM(m, d, self._M)
        return self._M.copy()

    def mass_matrix(self, q):
        return self._batched(self._mass_one, q)

    def _inverse_one(self, q, dq, ddq):
        m, d = self.mj_model, self.data
        d.qpos[:], d.qvel[:], d.qacc[:] = q, dq, ddq
        mujoco.mj_inverse(m, d)
        return d.qfrc_inverse.copy()

    def inverse_dynamics(self, q, dq, ddq):
        return self._batched(self._inverse_one, q, dq, ddq)

    def _gravity_one(self, q):
        m, d = self.mj_model, self.data
        d.qpos[:] = q
        d.qvel[:] = 0.0
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_comVel(m, d)
        mujoco.mj_rne(m, d, 0, self._rne)
        return -self._rne.copy()

    def gravity(self, q):
        return self._batched(self._gravity_one, q)

    # -- forward runs ------------------------------------------------------------------
    def run_model(self, settings: MjcfSettings | None = None):
        """(MJCF text, MjModel) of the run's chain: the rear height joint zc, contacts on;
        built on first use per settings (the engine's own by default)."""
        settings = self.settings if settings is None else settings
        if settings not in self._run_models:
            text = mjcf_text(self.model.params, settings, rear_height=True)
            self._run_models[settings] = (text, compile_mjcf(text, massless_links(True)))
        return self._run_models[settings]

    def simulate(self, scenario, **options):
        from ..stepping import refuse_fork_axis_contact
        refuse_fork_axis_contact(self)
        from .run import simulate
        return simulate(self, scenario, **options)
