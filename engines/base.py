"""The engine interface: one small set of methods, each optional and declared.

Every engine is built from a `reference_model.Model` (so from the same parameter file, never
from copied numbers) and declares in ``capabilities`` which of the methods below it provides;
the harness compares only what two engines both provide. Asking for anything else raises
`CapabilityError`, naming the engine and the capability.

Sign conventions are the thesis's (see `reference_model.model`):

* ``mass_matrix(q)``                      M (8, 8)
* ``inverse_dynamics(q, dq, ddq)``        unconstrained M ddq - Qv - Qgrav (8,)
* ``gravity(q)``                          Qgrav, the generalised gravity *force* (8,)
* ``generalized_forces(q, dq, torques)``  Qv + Qgrav + Qaero + S T (8,)
* ``constraint_jacobian(q)``              D (5, 8), rows [rD_z, vC_x, vC_y, vD_x, vD_y]
* ``constraint_bias(q, dq)``              dD dq (5,)
* ``forward_acceleration(q, dq, torques)`` exact constrained ddq (8,)
* ``simulate(scenario, **options)``       a `reference_model.solvers.Trajectory`
* ``eigenvalues(speeds)``                 the roll/steer eigenvalues (1/s) about upright
  straight running at each forward speed (m/s), (n, 4) complex, sorted as
  `reference_model.linearize.sort_eigenvalues` (`engines.linear` computes them from an
  engine's own constraints and accelerations)

Each term takes one state (8,) or a batch (N, 8). The full contract for engine authors (coordinates,
signs, units, shapes, the rolling contact, statuses, registration, errors) is docs/engines.md.
"""

from __future__ import annotations

from reference_model import Model

# The facts' attributes below are typed by `engines.facts` (RunSetup, Costs, FixedStep,
# SoftContact, OptionStudy), which reads them; not imported here, so the types stay free of
# the registry.

CAPABILITIES = (
    "mass_matrix", "inverse_dynamics", "gravity", "generalized_forces", "constraint_jacobian",
    "constraint_bias", "forward_acceleration", "simulate", "eigenvalues",
)


CONTACTS = ("thesis", "disc")   # the front-contact models a `reference_model.Model` can carry


class CapabilityError(NotImplementedError):
    """An engine was asked for something it does not provide."""


class EngineError(RuntimeError):
    """An engine could not be built or run (missing package, unsupported model...)."""


class EngineSpecError(EngineError):
    """The user named or configured an engine wrongly: an unknown name, a malformed spec, no
    such module, file or class, a class that is not an `Engine`, an option the engine does not
    take or a bad option value. A usage error (the CLI exits 2); the message says the fix.
    Engines raise it from ``__init__`` for a bad option value."""


class EngineLoadError(EngineError):
    """A correctly named engine failed: its module does not import, it lacks the method of a
    capability it declares, it does not support the model's contact, or it raised while being
    built. The CLI exits 1; a run drops the engine and reports why (`engines.load_engines`)."""


class UnsupportedModel(EngineLoadError):
    """A declared limitation: the engine cannot represent this model (a front contact it does
    not model, or a body MuJoCo's compiler refuses: principal moments that break A + B >= C).
    Not a failure of the engine: a run lists it as "not run on this model: <reason>" and goes
    on. Raise it from ``__init__`` with the reason; the loader raises it for an unsupported
    contact."""


class EngineUsageError(EngineSpecError, ValueError):
    """An engine option the user gave is invalid (unknown build, a time step that does not
    divide the output grid...): a usage error, exit status 2 in the CLI. Still an
    `EngineError`, so code that catches those keeps working."""


class Engine:
    """Base class: subclasses set ``name``, ``capabilities`` (and ``contacts`` if they support
    fewer than both front-contact models) and implement those methods. Keyword arguments of
    ``__init__`` after the model are the engine's options (``load_engine(spec, model, **options)``).
    An instance may narrow ``capabilities`` per its options (Exudyn's redundant build has no M);
    the class attribute is what `engines.engine_info` lists (the default options')."""

    name: str = "engine"
    capabilities: frozenset[str] = frozenset()
    contacts: tuple[str, ...] = CONTACTS
    #: a declared model difference of the engine's forward runs against the reference's ideal
    #: rolling (e.g. a soft wheel-ground contact), or None. A run of such an engine is never
    #: judged by the ideal-rolling tolerances: its departures (slip, penetration, error up to
    #: the meaningful horizon, lift-off) are measured and reported as that difference.
    run_difference: str | None = None
    #: options the engine cannot be built without (e.g. a file): it is left out of every
    #: default engine list (run's, diagnose's, the conformance suite's) and built only when
    #: named with them
    required_options: tuple[str, ...] = ()

    # -- the engine's facts (`engines.facts`; docs/engines.md, "An engine's facts") ----------
    #: how reports and figures name and draw the engine ("" : its registered name); a
    #: matplotlib colour and marker (None: one of `comparisons.report.styles`' fallbacks,
    #: distinct from every declared one)
    label: str = ""
    colour: str | None = None
    marker: str | None = None
    #: the table of tolerances.toml judging its forward runs against the reference's, or None
    #: when a study it contributes judges them (say which in ``trajectory_judged_by``)
    trajectory_tolerance: str | None = "trajectory_conformance"
    trajectory_judged_by: str = ""
    #: the labelled option sets of its scenario runs (empty: one, its name, its defaults)
    run_setups: tuple[RunSetup, ...] = ()
    costs: Costs | None = None      # None: `engines.facts.Costs`' defaults
    #: the studies it contributes: a fixed-step integrator's, a soft contact's (or None)
    fixed_step: FixedStep | None = None
    soft_contact: SoftContact | None = None
    #: options whose other values are another bicycle, each studied against the option
    #: (`engines.facts.OptionStudy`; needs the ``eigenvalues`` capability)
    option_studies: tuple[OptionStudy, ...] = ()

    def __init__(self, model: Model):
        self.model = model

    def __repr__(self) -> str:
        return f"{type(self).__name__}(model={self.model.name!r}, contact={self.model.contact!r})"

    @classmethod
    def prepare(cls) -> None:
        """Work every instance shares, done once in the main process before `run`'s worker
        processes fork, so they inherit it instead of each doing it (e.g. generating and
        loading cached code). Default: nothing."""

    def supports(self, capability: str) -> bool:
        return capability in self.capabilities

    def _missing(self, capability: str):
        have = ", ".join(c for c in CAPABILITIES if c in self.capabilities) or "nothing"
        raise CapabilityError(f"engine {self.name!r} cannot compute {capability}; it provides: {have}")

    def mass_matrix(self, q):
        self._missing("mass_matrix")

    def inverse_dynamics(self, q, dq, ddq):
        self._missing("inverse_dynamics")

    def gravity(self, q):
        self._missing("gravity")

    def generalized_forces(self, q, dq, torques=(0.0, 0.0, 0.0)):
        self._missing("generalized_forces")

    def constraint_jacobian(self, q):
        self._missing("constraint_jacobian")

    def constraint_bias(self, q, dq):
        self._missing("constraint_bias")

    def forward_acceleration(self, q, dq, torques=(0.0, 0.0, 0.0)):
        self._missing("forward_acceleration")

    def simulate(self, scenario, **options):
        self._missing("simulate")

    def eigenvalues(self, speeds):
        self._missing("eigenvalues")
