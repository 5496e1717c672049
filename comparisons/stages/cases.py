"""What `bicycle-xval run --model ... --scenario-file ...` runs: scenarios on models, as *cases*.

A case is a scenario bound to a model (a named model or a parameter-file path: a picklable
string, loaded again in each worker). Without --model and --scenario-file the cases are the
built-in scenarios under their own names on their own models: today's run, unchanged.

With ``--model M`` (repeatable): every built-in thesis scenario that makes sense for any
bicycle runs on M under the name ``<scenario>-on-<M's name>``, and the scenarios that cannot
apply are listed as not run, with the reason (`not_applicable`). The initial states written
for the thesis geometry are re-made consistent for M's (forward: `consistent_state` at run
start; inverse: beta(0) from [rD]_z = 0), and the correction is reported. What makes sense:

* **check, zigzag** (prescribed motions): any bicycle can follow them; the torques are M's.
* **replay, check-forward**: their torques are named functions, the inverse dynamics of zigzag
  and check *computed on the model the run uses* (`reference_model.scenarios.torque_input`),
  so on M they are M's own zig-zag torques fed forward from M's consistent initial state: the
  same test of inverse against forward dynamics as on the thesis bicycle. (The thesis's
  torque history itself, identified for its bicycle, would mean nothing on another one.)
* **stability-psidN**: the thesis's leaned start and pedal torque; on M it shows M's
  behaviour. The thesis's claims about them are about its bicycle: judged on thesis models only.
* **benchmark-v***: not run on M: written for the benchmark bicycle's critical speeds (4.29
  and 6.02 m/s); M's own runs below and above its own critical speeds are in its stability
  section (`stages/stability.py`).

The expected differences written for the thesis (its contact against the disc) are dropped on
M. A scenario on the named model it was written for keeps its built-in name (``--model
thesis``: the thesis's scenarios, so its claims are judged; ``--model benchmark``: the IFToMM
manoeuvres too, when selected with --scenarios).

``--scenario-file F`` (repeatable): F's scenario runs on the model it names, and on every
--model as well (as ``<name>-on-<model>``).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path

from reference_model.scenarios import Scenario


@dataclass(frozen=True)
class ModelSpec:
    """A model the run uses: ``spec`` (name or path, as load_model takes it), its name, the file
    it was read from, its contact model and its warnings (what summary.json's ``models`` says)."""

    spec: str
    name: str
    source: str
    contact: str
    cv: float
    warnings: tuple[str, ...] = ()

    def as_dict(self) -> dict:
        return {"name": self.name, "source": self.source, "contact": self.contact,
                "warnings": list(self.warnings)}


@dataclass(frozen=True)
class Case:
    """A scenario (renamed as the report shows it) on a model spec."""

    name: str
    scenario: Scenario
    model: str               # the spec
    origin: str = "built-in"


@dataclass(frozen=True)
class NotRun:
    scenario: str
    model: str
    reason: str


def model_spec(spec: str) -> ModelSpec:
    """Load ``spec`` once (a bad file is a ParameterError here, before any run) and describe it."""
    from reference_model import NAMED_MODELS, load_model
    m = load_model(spec)
    if spec in NAMED_MODELS:
        source = str(NAMED_MODELS[spec][0])
    else:
        source = spec
        spec = str(Path(spec).resolve())      # workers may run elsewhere: an absolute path
    return ModelSpec(spec, m.name, source, m.contact, float(m.params.cv), tuple(m.warnings))


def slug(text: str) -> str:
    """A file-name-safe form of a model's name (report figure names derive from case names)."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", text).strip("-") or "model"


def not_applicable(sc: Scenario) -> str | None:
    """Why a built-in scenario is not run on a user's model, or None (module docstring)."""
    if "benchmark" in sc.tags:
        return ("written for the benchmark bicycle's critical speeds (weave 4.29, capsize 6.02 "
                "m/s); this bicycle's runs below and above its own critical speeds are in its "
                "stability section")
    return None


def on_model(sc: Scenario, m: ModelSpec, keep_name: bool = False) -> Scenario:
    """``sc`` bound to the model ``m``: renamed ``<name>-on-<model>``, its model the spec, and
    the expected differences written for another model dropped."""
    if keep_name:
        return dataclasses.replace(sc, model=m.spec)
    return dataclasses.replace(sc, name=f"{sc.name}-on-{slug(m.name)}", model=m.spec,
                               expected_differences=())


def build_cases(names, models: tuple[ModelSpec, ...], files: tuple[str, ...]
                ) -> tuple[list[Case], list[NotRun]]:
    """The cases of the run and the scenarios not run, with reasons (module docstring)."""
    from reference_model.scenario_files import load_scenario
    from reference_model.scenarios import get_scenario

    cases: list[Case] = []
    skipped: list[NotRun] = []
    if not models:
        cases = [Case(n, get_scenario(n), get_scenario(n).model) for n in names]
    for m in models:
        for n in names:
            sc = get_scenario(n)
            if sc.model == m.spec:            # the scenario's own model: as built in
                cases.append(Case(n, sc, m.spec))
                continue
            why = not_applicable(sc)
            if why is not None:
                skipped.append(NotRun(n, m.name, why))
                continue
            bound = on_model(sc, m)
            cases.append(Case(bound.name, bound, m.spec))
    for f in files:
        sc = load_scenario(f)
        own = model_spec(sc.model)
        targets = [own] + [m for m in models if m.spec != own.spec]
        for m in targets:
            bound = on_model(sc, m, keep_name=m is own)
            cases.append(Case(bound.name, bound, m.spec, origin=str(f)))
    seen: dict[str, Case] = {}
    for c in cases:
        if c.name in seen:
            raise ValueError(f"two scenarios named {c.name!r} ({seen[c.name].origin}, "
                             f"{c.origin}); rename one (scenario.name in its file)")
        seen[c.name] = c
    return cases, skipped
