"""Every scenario on every engine that can run it, the thesis's way.

An *engine setup* is an engine with its options, labelled as the report names it. Each engine
declares its setups itself (`engines.facts.RunSetup`: a label suffix, options, the kinds of
scenario it runs and its settings in a line; `bicycle-xval engines` lists them); an engine that
declares none has one, labelled by its name, at its defaults. Options given on the command line
(``--engine-option``) replace the declared ones. The kinds of scenario a setup runs follow the
engine's capabilities unless it declares them: forward through ``simulate``, inverse through a
``run_inverse(scenario)`` method (the reference runs both itself).

`run_one` is a top-level function of (setup, scenario, model spec), so the pipeline farms runs
out to worker processes: the report's numbers do not depend on the order or the process they
ran in.
"""

from __future__ import annotations

from dataclasses import dataclass

from engines.runs import Run, run_scenario


@dataclass(frozen=True)
class EngineSetup:
    """An engine and its options under the label the report uses."""

    label: str
    engine: str
    options: tuple[tuple[str, object], ...] = ()
    kinds: tuple[str, ...] = ("inverse", "forward")
    settings: str = ""

    def build(self, model):
        from engines import load_engine
        return load_engine(self.engine, model, **dict(self.options))


def label_of(spec: str) -> str:
    """The report's label of an engine spec: its name, or the class name of a
    ``module:Class`` / ``file.py:Class`` spec."""
    return spec.rsplit(":", 1)[-1] if ":" in spec else spec


def _kinds(facts, declared) -> tuple[str, ...]:
    if declared is not None:
        return tuple(declared)
    if facts.name == "reference":
        return ("inverse", "forward")
    return tuple(k for k, ok in (("inverse", facts.has_inverse_runs),
                                 ("forward", "simulate" in facts.capabilities)) if ok)


def engine_setups(spec: str, options: dict | None = None) -> list[EngineSetup]:
    """The setups of one engine (name or spec): those it declares, or, with ``options`` from
    the command line, one setup labelled by its name with those options."""
    from engines.facts import engine_facts
    facts = engine_facts(spec)
    label = label_of(spec)
    if options:
        opts = tuple(sorted(options.items()))
        kinds = _kinds(facts, facts.run_setups[0].kinds if len(facts.run_setups) == 1 else None)
        return [EngineSetup(label, spec, opts, kinds,
                            settings=f"{spec} with {', '.join(f'{k} = {v}' for k, v in opts)}")]
    return [EngineSetup(label if not s.suffix else f"{label}-{s.suffix}", spec, s.options,
                        _kinds(facts, s.kinds), s.settings or f"{spec} with its own defaults")
            for s in facts.run_setups]


def setups_for(engines, options: dict | None = None) -> list[EngineSetup]:
    """The setups of the selected engines (names or specs), in the given order (the reference
    first); ``options``: spec -> keyword options from the command line."""
    return [s for e in engines for s in engine_setups(e, (options or {}).get(e))]


def setup_of(spec: str, options: dict | None = None) -> EngineSetup:
    """An engine's first setup (the one its runs appear under when it declares several)."""
    return engine_setups(spec, options)[0]


def run_one(setup: EngineSetup, scenario, model: str | None = None) -> Run:
    """Run ``scenario`` (a built-in's name, or a `Scenario`) on ``setup`` and on ``model`` (a
    named model or a parameter-file path; default the scenario's own). A top-level function of
    picklable arguments: worker processes call it."""
    import dataclasses

    from engines import UnsupportedModel
    from engines.registry import resolve
    from reference_model import load_model
    from reference_model.scenarios import get_scenario

    sc = get_scenario(scenario) if isinstance(scenario, str) else scenario
    if model is not None and model != sc.model:
        sc = dataclasses.replace(sc, model=model)
    label = setup.label
    model = load_model(sc.model)
    if sc.kind not in setup.kinds:
        return run_scenario(label, None, model, sc, setup.kinds)
    try:
        engine = None if (label == "reference" and sc.kind == "inverse") else setup.build(model)
    except UnsupportedModel as exc:   # a declared limitation: not run, and why
        cls = resolve(setup.engine)[0]
        why = (_contact_reason(cls, setup, model) if model.contact not in
               getattr(cls, "contacts", ()) else f"not run on this model: {exc}")
        return Run(label, sc.name, model.name, sc.kind, "not run", why, 0.0)
    return run_scenario(label, engine, model, sc, setup.kinds)


def _contact_reason(cls, setup: EngineSetup, model) -> str:
    """Why an engine cannot run on ``model``'s front contact: the `CapabilityError` its
    constructor raises (the loader refuses the contact before asking it), or a plain
    statement."""
    from engines import CapabilityError
    try:
        cls(model, **dict(setup.options))
    except CapabilityError as exc:
        return f"CapabilityError: {' '.join(str(exc).split())}"
    except Exception:   # noqa: BLE001 - any other failure: the plain statement below
        pass
    return (f"{setup.label} models the front contact(s) {', '.join(cls.contacts)}, not "
            f"{model.contact!r} of model {model.name!r}")


def cost(setup: EngineSetup, scenario: str) -> float:
    """A rough run time for scheduling (s), from the engine's declared `engines.facts.Costs`."""
    from engines.facts import engine_facts
    c = engine_facts(setup.engine).costs
    scenario = scenario.split("-on-")[0]
    if scenario in dict(c.scenario_runs):
        return dict(c.scenario_runs)[scenario]
    if scenario in ("check", "zigzag"):
        return c.short_run
    length = 6.3 if scenario in ("replay", "check-forward") else 1.2
    return c.run_per_second * length
