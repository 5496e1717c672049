"""The fault-injection stage and the localization of failing term comparisons."""

from __future__ import annotations

from ..judgments.faults import run_fault_suite
from ..judgments.tolerances import Tolerances
from .results import Section

TERM_QUANTITIES = ("mass_matrix", "inverse_dynamics", "gravity", "generalized_forces",
                   "constraint_jacobian", "constraint_bias", "forward_acceleration", "torques",
                   "multipliers")
FAULT_ENGINES = ("pinocchio", "exudyn", "mujoco", "kane")
FAULT_LABELS = {"pinocchio": "Pinocchio", "exudyn": "Exudyn's tree", "mujoco": "MuJoCo",
                "kane": "Kane's engine"}
FAULT_COST = {"pinocchio": 4.0, "exudyn": 3.0, "mujoco": 1.0, "kane": 2.0}   # s, the pool's order


def fault_base(engine: str) -> str:
    """The correct model the faults are injected into: the thesis bicycle, on its disc-contact
    variant for an engine that models only the disc (Kane's)."""
    from engines.registry import resolve
    return "thesis" if "thesis" in getattr(resolve(engine)[0], "contacts", ()) else "thesis-disc"


def fault_entries(tolerances: Tolerances, engine: str, model: str | None = None) -> list[dict]:
    """The fault suite against one engine, judged by ``tolerances`` (a stage: worker processes
    call it). Pinocchio
    computes every term, so every fault must be detected and localized on it; the Exudyn tree
    gives only M and the generalized forces, and MuJoCo M, the inverse dynamics and gravity, so
    a fault confined to D and dD dq (the contact switch) is not observable there (MuJoCo has no
    forward run on the thesis contact to see it in) and is listed as such, not counted as
    missed. Kane's engine gives M, the generalized forces, D and dD dq of the disc-contact
    thesis bicycle: every fault is observable in its terms (the contact switch turns the broken
    reference's contact into the thesis's)."""
    from engines import UnsupportedModel
    from reference_model import load_model
    entries = []
    base = fault_base(engine) if model is None else model
    name = load_model(base).name
    try:
        results = run_fault_suite(engines=(engine,), base=base, tolerances=tolerances)
    except UnsupportedModel as exc:   # the engine cannot represent this bicycle: declared
        return [{"fault": "-", "engine": engine, "model": name, "detected": None,
                 "localized_to": "-", "expected": "-", "correct": None, "observable": False,
                 "evidence": f"not run on this model: {exc}", "verdict": "not run"}]
    for r in results:
        d = r.to_dict()
        d["engine"] = engine
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
