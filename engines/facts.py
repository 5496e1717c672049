"""What an engine declares about itself, and the harness reads: one place per engine.

Everything the harness needs to know about one engine beyond its methods is a class attribute
of its `engines.base.Engine` subclass, typed by the dataclasses here, and read through
`engine_facts` (the harness never names an engine; docs/engines.md, "An engine's facts"):

* ``label``, ``colour``, ``marker``: how reports and figures name and draw it;
* ``contacts``, ``run_difference``: the front contacts it models, and a declared model
  difference of its forward runs (e.g. a soft wheel-ground contact);
* ``trajectory_tolerance``: the table of ``tolerances.toml`` that judges its forward runs
  against the reference (``"trajectory"``: the reference's own solvers; the default
  ``"trajectory_conformance"``: its own integrator), or None when a study judges them instead
  (a fixed-step integrator: its convergence order), with ``trajectory_judged_by`` saying which;
* ``run_setups``: the labelled option sets its scenario runs use (default: one, its name, its
  defaults);
* ``costs``: rough run times for the scheduler's order;
* the studies it contributes, as facts the studies read: ``fixed_step`` (a fixed-step
  integrator: convergence order, energy drift, trajectories of each variant, the IFToMM
  manoeuvres) and ``soft_contact`` (a soft contact: slip, penetration, lift-off and the
  refinement of its settings), and ``option_studies`` (an option whose other values make
  another bicycle: each value's eigenvalues and critical speeds against the option, the
  reference's value judged, the others a declared model difference). A second engine
  declaring the same gets the same study.

Nothing here imports an engine's library: reading the facts is cheap.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Callable

__all__ = ["Costs", "EngineFacts", "FixedStep", "OptionStudy", "Refinement", "RunSetup",
           "SoftContact",
           "engine_facts", "options_dict"]

Options = tuple[tuple[str, object], ...]


def options_dict(options: Options) -> dict:
    """A declared option set ((name, value) pairs) as keyword arguments."""
    return dict(options)


@dataclass(frozen=True)
class RunSetup:
    """One labelled option set under which the engine's scenario runs appear in the report.
    ``suffix`` "" labels the runs by the engine's name, else ``name-suffix``; ``kinds`` None:
    from the capabilities (forward through ``simulate``, inverse through ``run_inverse``)."""

    suffix: str = ""
    options: Options = ()
    kinds: tuple[str, ...] | None = None
    settings: str = ""          # one line for the report's environment


@dataclass(frozen=True)
class Costs:
    """Rough wall times (s, the 2-core machine) for the scheduler's order only: the longest
    stages start first. Never a result."""

    run_per_second: float = 1.0     # per simulated second of a forward scenario
    short_run: float = 0.8          # an inverse scenario (check, zigzag)
    terms: float = 1.5              # the term-by-term stage
    faults: float = 2.0             # the fault-injection stage
    #: (scenario, s): measured times of runs the rate above misjudges (e.g. a manoeuvre that
    #: needs several times the Newton iterations of the others); they replace it
    scenario_runs: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True)
class FixedStep:
    """A fixed-step integrator: its forward runs are judged by their convergence order in
    ``option`` (the step, s) at ``step``, its default; ``variants`` are named option sets
    (e.g. two builds of the model) each study runs; ``thesis_variant`` the one that also
    models the thesis's front contact (the convergence study then checks it against the
    thesis-contact reference); ``benchmark_options`` extra options of its IFToMM runs;
    ``quick_variants`` the variants a ``--quick`` run uses."""

    option: str = "step"
    step: float = 1e-3
    order: float = 2.0
    variants: tuple[tuple[str, Options], ...] = (("", ()),)
    thesis_variant: str | None = None
    quick_variants: tuple[str, ...] = ()
    benchmark_options: Options = ()
    describe: str = ""          # the integrator in a phrase, for the report's text

    def variant_options(self, variant: str, **more) -> dict:
        opts = dict(dict(self.variants)[variant])
        opts.update(more)
        return opts

    @property
    def variant_names(self) -> tuple[str, ...]:
        return tuple(v for v, _ in self.variants)

    def runs(self, name: str, variants=None, sep: str = "-", **more) -> list[tuple[str, dict]]:
        """(label, options) of each of ``variants`` (default all) at the declared step:
        the label ``name{sep}variant`` (``name`` alone for an unnamed variant), the options the
        variant's with the step and ``more``."""
        return [(sep.join(x for x in (name, v) if x),
                 self.variant_options(v, **{self.option: self.step}, **more))
                for v in (self.variant_names if variants is None else variants)]


@dataclass(frozen=True)
class Refinement:
    """One series of the soft-contact refinement study: ``parameter`` (with its unit) is
    refined over ``values`` while ``held`` stays; ``options(value, defaults)`` gives the
    engine's options of one run (``defaults``: the run's ``settings`` at the defaults)."""

    parameter: str
    held: str
    values: tuple[float, ...]
    options: Callable[[float, dict], dict]
    quick_values: tuple[float, ...] | None = None   # None: not run in --quick


@dataclass(frozen=True)
class SoftContact:
    """A soft wheel-ground contact: the study (slip, penetration, normal forces, lift-off and
    the error against ideal rolling, at the defaults, then ``refinements``) that every such
    engine gets. ``settings_rows(settings)`` renders a run's ``settings`` as (name, value)
    rows; ``conclusion(studies, settings)`` an engine's own reading of its refinement series
    (optional)."""

    refinements: tuple[Refinement, ...] = ()
    settings_rows: Callable[[dict], list[tuple[str, str]]] | None = None
    conclusion: Callable[[list, dict], str] | None = None
    about: str = ""     # a sentence on what the contact is, for the study's text


@dataclass(frozen=True)
class OptionStudy:
    """An engine option whose values other than ``reference_value`` build another bicycle than
    the reference's (e.g. a tyre's crown radius): a declared model difference, quantified by
    the option study (the roll/steer eigenvalues against speed and the weave and capsize
    speeds at each of ``values``; needs the ``eigenvalues`` capability). At
    ``reference_value`` the engine's model is the reference's and is judged against it; at
    the others it is reported, never failed. ``values`` in SI (``unit``); ``quantity`` names
    the option in words, ``difference`` says in one line what the other values change,
    ``why`` why these values; ``quick_values`` the values a ``--quick`` run uses (None: not
    run in --quick); ``prepare`` the work every value's build shares (generating the code of
    a non-default variant), run once in the main process before the study's workers fork,
    only when the study runs (None: nothing)."""

    option: str
    quantity: str
    unit: str
    values: tuple[float, ...]
    reference_value: float
    difference: str
    why: str = ""
    quick_values: tuple[float, ...] | None = None
    prepare: Callable[[], None] | None = None

    def __post_init__(self):
        if self.reference_value not in self.values:
            raise ValueError(f"option study {self.option!r}: reference_value "
                             f"{self.reference_value!r} must be one of values {self.values!r}")


@dataclass(frozen=True)
class EngineFacts:
    """One engine's declarations, read from its class (`engine_facts`)."""

    name: str
    spec: str
    label: str
    colour: str | None
    marker: str | None
    capabilities: frozenset[str]
    contacts: tuple[str, ...]
    run_difference: str | None
    trajectory_tolerance: str | None
    trajectory_judged_by: str
    run_setups: tuple[RunSetup, ...]
    costs: Costs
    fixed_step: FixedStep | None = None
    soft_contact: SoftContact | None = None
    option_studies: tuple[OptionStudy, ...] = ()
    has_inverse_runs: bool = False
    requires: tuple[str, ...] = field(default=())

    @property
    def has_terms(self) -> bool:
        """Whether it computes a term (a capability beyond its runs and its linearization)."""
        return bool(self.capabilities - {"simulate", "eigenvalues"})

    def setup_label(self, setup: RunSetup) -> str:
        return self.name if not setup.suffix else f"{self.name}-{setup.suffix}"


@lru_cache(maxsize=None)   # a class's declarations do not change within a process
def engine_facts(spec: str) -> EngineFacts:
    """The facts the engine named by ``spec`` (a registered name or a ``module:Class`` /
    ``file.py:Class`` spec) declares; raises as `engines.registry.resolve` does."""
    import sys

    from .registry import resolve
    cls, label, _ = resolve(spec)
    name = label if ":" not in spec else spec.rsplit(":", 1)[-1]
    module = sys.modules.get(cls.__module__)
    package = sys.modules.get((cls.__module__ or "").rsplit(".", 1)[0]) if module else None
    requires = tuple(getattr(package, "REQUIRES", ()) or getattr(module, "REQUIRES", ()))
    return EngineFacts(
        name=name, spec=spec,
        label=getattr(cls, "label", "") or name,
        colour=getattr(cls, "colour", None),
        marker=getattr(cls, "marker", None),
        capabilities=frozenset(getattr(cls, "capabilities", ())),
        contacts=tuple(getattr(cls, "contacts", ())),
        run_difference=getattr(cls, "run_difference", None),
        trajectory_tolerance=getattr(cls, "trajectory_tolerance", "trajectory_conformance"),
        trajectory_judged_by=getattr(cls, "trajectory_judged_by", ""),
        run_setups=tuple(getattr(cls, "run_setups", ()) or (RunSetup(),)),
        costs=getattr(cls, "costs", None) or Costs(),
        fixed_step=getattr(cls, "fixed_step", None),
        soft_contact=getattr(cls, "soft_contact", None),
        option_studies=tuple(getattr(cls, "option_studies", ()) or ()),
        has_inverse_runs=callable(getattr(cls, "run_inverse", None)),
        requires=requires)
