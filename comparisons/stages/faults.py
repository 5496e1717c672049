"""The fault-injection stage and the localization of failing term comparisons."""

from __future__ import annotations

from ..judgments.faults import run_fault_suite
from ..judgments.tolerances import Tolerances
from .results import Section
from .stage import Assembled, Plan, Stage

TERM_QUANTITIES = ("mass_matrix", "inverse_dynamics", "gravity", "generalized_forces",
                   "constraint_jacobian", "constraint_bias", "forward_acceleration", "torques",
                   "multipliers")


def fault_base(engine: str) -> str:
    """The correct model the faults are injected into: the thesis bicycle, on its disc-contact
    variant for an engine that models only the disc."""
    from engines.facts import engine_facts
    return "thesis" if "thesis" in engine_facts(engine).contacts else "thesis-disc"


def fault_entries(tolerances: Tolerances, engine: str, model: str | None = None,
                  options: tuple = ()) -> list[dict]:
    """The fault suite against one engine, judged by ``tolerances`` (a stage: worker processes
    call it). Every fault the engine's declared terms can show must be detected and localized
    on it; a fault confined to terms it does not provide (e.g. the contact switch, which moves
    only D and dD dq, on an engine that gives M and the forces alone) is not observable there
    and is listed as such, not counted as missed. ``options``: the engine's (key, value) pairs."""
    from engines import UnsupportedModel
    from reference_model import load_model

    from .runs import label_of
    label = label_of(engine)   # the report's name of the engine (a spec's class name)
    entries = []
    base = fault_base(engine) if model is None else model
    name = load_model(base).name
    try:
        results = run_fault_suite(engines=(engine,), base=base, tolerances=tolerances,
                                  options={engine: dict(options)})
    except UnsupportedModel as exc:   # the engine cannot represent this bicycle: declared
        return [{"fault": "-", "engine": label, "model": name, "detected": None,
                 "localized_to": "-", "expected": "-", "correct": None, "observable": False,
                 "evidence": f"not run on this model: {exc}", "verdict": "not run"}]
    for r in results:
        d = r.to_dict()
        d["engine"] = label
        d["model"] = name
        d["verdict"] = ("localized" if r.correct else "not observable" if not r.observable
                        else "detected, mislocalized" if r.detected else "missed")
        entries.append(d)
    return entries


def fault_section(entries: list[dict]) -> Section:
    sec = Section("Fault injection: does the harness catch a broken model?")
    sec.text("Broken copies of the reference model are run against engines built from the "
             "correct parameters (16 deterministic states). Each fault must be detected (a term "
             "fails its tolerance) and localized: the differing terms, and the parameter or "
             "structural cause, with its body, that explains at least 99 % of the difference "
             "(least squares over the sensitivities of all 30 parameters and the structural "
             "causes; `comparisons/judgments/diagnose.py`). The same machinery is "
             "`bicycle-xval diagnose FILE` for your own parameter file. 'not observable': the "
             "engine does not provide the terms the fault changes (it is not counted as missed).")
    sec.table(("fault", "engine", "detected", "localized to", "expected", "verdict", "evidence"),
              [(e["fault"], e["engine"] + (f" ({e['model']})" if e.get("model", "thesis") != "thesis"
                                             else ""),
                "-" if e["detected"] is None else "yes" if e["detected"] else "no",
                e["localized_to"],
                e["expected"], e["verdict"], e["evidence"]) for e in entries])
    return sec


class FaultsStage(Stage):
    """The fault suite against every selected engine that declares a term: on the thesis
    bicycle, or on each ``--model`` whose front contact it models."""

    name, section = "faults", "faults"

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        out = []
        for f in plan.engines(lambda f: f.has_terms):
            opts = tuple(plan.options_for(f.spec).items())
            if not plan.opts.models:
                out.append(Task((f.spec, None), fault_entries, (plan.tolerances, f.spec, None, opts),
                                f.costs.faults, f"fault injection on {f.label}", f.spec))
            for m in plan.opts.models:
                if m.contact in f.contacts:
                    out.append(Task((f.spec, m.spec), fault_entries,
                                    (plan.tolerances, f.spec, m.spec, opts), f.costs.faults,
                                    f"{m.name}: fault injection on {f.label}", f.spec))
        return out

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        for key in results:
            v, failed = self.value(results, key, f"fault injection on {plan.facts[key[0]].label}")
            if failed is None:
                out.faults += v
            else:
                out.sections.append(failed)
        if out.faults:
            out.sections.append(fault_section(out.faults))
        return out


def localization_lines(tolerances: Tolerances, comparisons, setups: dict,
                       specs: dict | None = None) -> list[tuple[str, str]]:
    """For every (model, engine) whose terms or inverse dynamics failed a tolerance: a heading
    and the localization (`diagnose.localize`): which terms, which entries, and the parameter
    or structural cause (with its body) that best explains the difference. Empty when
    everything agrees. ``specs``: a model's name -> its spec (a user's file) where the name
    alone does not load it."""
    from engines import UnsupportedModel
    from engines.guard import describe
    from reference_model import load_model
    from ..judgments.diagnose import localize
    from ..judgments.terms import random_states
    pairs = sorted({(c.get("model", "thesis"), c["engines"][1]) for c in comparisons
                    if c["passed"] is False and c["quantity"] in TERM_QUANTITIES
                    and len(c["engines"]) == 2})
    out = []
    for model_name, engine in pairs:
        if engine not in setups:
            continue
        try:
            model = load_model((specs or {}).get(model_name, model_name))
            built = setups[engine].build(model)
        except (UnsupportedModel, ValueError, OSError):   # nothing to localize against
            continue
        try:
            loc = localize(model, random_states(16, seed=11), [built], tolerances=tolerances)
        except Exception as exc:   # noqa: BLE001 - the engine failed: say so, keep the rest
            out.append((f"{model_name}: reference vs {engine}", f"not localized: {describe(exc)}"))
            continue
        out.append((f"{model_name}: reference vs {engine}", loc.describe()))
    return out
