"""The shape of a stage of `bicycle-xval run`: what tasks it needs, and how it assembles their
results into report sections.

A stage is one module with one `Stage` subclass. `tasks(plan)` lists the calls to farm out
(each a `pool.Task` whose key is the stage's own, any hashable); `assemble(plan, results)`
turns their `pool.TaskResult`s (keyed as given) into sections, in this process. The pipeline
namespaces the keys by the stage's name, so a stage never sees another's, and never parses
keys. Which engines a stage concerns is read from their declared facts
(`engines.facts.engine_facts`) in `Plan.facts`; no stage names an engine. The stages are listed
once, in `comparisons.stages.catalog`, in report order.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..judgments.rows import Comparison
from .results import Section

__all__ = ["Assembled", "Plan", "Stage", "failed_section"]


@dataclass(frozen=True)
class Plan:
    """What every stage reads to say its tasks: the run's options (`pipeline.Options`), its
    engine setups, the facts of each selected engine (by spec, reference included), the cases
    (`cases.Case`) and each ``--model``'s critical speeds."""

    opts: object
    setups: tuple
    facts: dict
    cases: tuple = ()
    critical: dict = field(default_factory=dict)

    @property
    def tolerances(self):
        return self.opts.tolerances

    @property
    def quick(self) -> bool:
        return self.opts.quick

    def wants(self, section: str | None) -> bool:
        return section is None or section in self.opts.sections

    def engines(self, where=lambda f: True) -> list:
        """The selected engines' facts (the reference excluded) that satisfy ``where``, in
        the order given."""
        return [f for spec, f in self.facts.items() if spec != "reference" and where(f)]

    def options_for(self, spec: str) -> dict:
        return self.opts.options_for().get(spec, {})


@dataclass
class Assembled:
    """A stage's share of the report: its sections, fault-injection entries (the fault
    table's rows, which summary.json lists apart) and ``summary``: keys it adds to summary.json
    (plain data; a key the pipeline or another stage already wrote is refused)."""

    sections: list[Section] = field(default_factory=list)
    faults: list[dict] = field(default_factory=list)
    summary: dict = field(default_factory=dict)


def failed_section(title: str, error: str) -> Section:
    """A stage that raised, as a section with one failing row (counted in the verdict)."""
    sec = Section(title)
    sec.text(f"**This stage failed**: {error}")
    sec.comparisons.append(Comparison.of({"quantity": "stage", "scenario": title, "model": "-",
                            "engines": ["-"], "max_error": None, "tolerance": None,
                            "passed": False, "localized_to": error}))
    return sec


class Stage:
    """Base class (module docstring). ``name`` namespaces its tasks; ``section`` is the
    ``--sections`` word that selects it (None: always run)."""

    name: str = "stage"
    section: str | None = None

    def tasks(self, plan: Plan) -> list:
        return []

    def prepare(self, plan: Plan) -> None:
        """Work this stage's tasks share (e.g. an engine's generated code for an option it
        does not build by default), done once in the main process before the workers fork,
        only when the stage runs. Default: nothing."""

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        return Assembled()

    def revise_claims(self, plan: Plan, results: dict, claims: list[dict]) -> list[dict]:
        """The thesis's claims as this stage's results revise them (default: unchanged)."""
        return claims

    @staticmethod
    def value(results: dict, key, title: str):
        """(value, None) for a task that returned, (None, failed section) for one that raised."""
        r = results[key]
        return (r.value, None) if r.error is None else (None, failed_section(title, r.error))
