"""Every engine term by term against the reference: the quantities it declares, at
deterministic random states (large lean, steer near ±π/2, rates up to 20 rad/s), on the thesis
bicycle with both front contacts, or on each ``--model``.

Each quantity is judged against its tolerance in `tolerances.toml`. A model the engine cannot
represent (a declared limitation, `engines.UnsupportedModel`) is a 'not run' row with the
reason; an engine that raises otherwise is a FAIL row, counted in the verdict. An engine that
provides M gets the figure of its worst relative error per entry.
"""

from __future__ import annotations

import numpy as np

from engines import load_engine
from reference_model import COORDINATES, load_model

from ..judgments.terms import compare_terms, random_states
from ..judgments.tolerances import Tolerances
from ..judgments.rows import Comparison
from .results import Section
from .stage import Assembled, Plan, Stage

__all__ = ["THESIS_MODELS", "TERM_HEADER", "TermsStage", "engine_terms", "plugin_terms",
           "term_rows"]

TERM_HEADER = ("model", "quantity", "max error", "tolerance", "verdict", "worst entry")
THESIS_MODELS = ("thesis", "thesis-disc")
N_STATES, QUICK_N_STATES = 200, 50


def term_rows(sec: Section, results, model_name: str, engines: list[str], scenario: str,
              prefix: tuple = ()) -> list[tuple]:
    """Table rows of `compare_terms` results, each also a comparison of ``sec``."""
    rows = []
    for r in results:
        rows.append(prefix + (r.quantity, f"{r.max_error:.1e}", f"{r.tolerance:.0e}",
                              "pass" if r.passed else "FAIL", r.worst_entry))
        sec.comparisons.append(Comparison.of({
            "quantity": r.quantity, "scenario": scenario, "model": model_name,
            "engines": engines, "max_error": r.max_error, "tolerance": r.tolerance,
            "passed": r.passed, "localized_to": r.worst_entry}))
    return rows


def _terms_on_models(tolerances: Tolerances, sec: Section, spec: str, label: str, options: dict,
                     states, n_states: int, models=THESIS_MODELS) -> tuple[list[tuple], dict]:
    """``spec``'s declared terms against the reference on each of ``models`` (rows, comparisons
    into ``sec``); returns the rows and the engines built, by model."""
    from engines import UnsupportedModel
    rows, built = [], {}
    for name in models:
        model = load_model(name)
        try:
            eng = load_engine(spec, model, **options)
        except UnsupportedModel as exc:   # declared: not run, and why
            rows.append((model.name, "-", "-", "-", "not run", f"not run on this model: {exc}"))
            continue
        except Exception as exc:   # noqa: BLE001 - the engine failed: a result, counted
            why = f"{type(exc).__name__}: {' '.join(str(exc).split())[:300]}"
            rows.append((model.name, "-", "-", "-", "FAIL", why))
            sec.comparisons.append(Comparison.of({"quantity": "engine build", "scenario": "-",
                                    "model": model.name, "engines": [label], "max_error": None,
                                    "tolerance": None, "passed": False, "localized_to": why}))
            continue
        built[name] = ref, eng = load_engine("reference", model), eng
        rows += term_rows(sec, compare_terms(ref, eng, states, tolerances), model.name,
                          ["reference", label], f"random-states-{n_states}", (model.name,))
    return rows, built


def engine_terms(tolerances: Tolerances, spec: str, options: dict, n_states: int,
                 models=THESIS_MODELS) -> Section:
    """An engine term by term on each of ``models`` (default: the thesis bicycle on both
    contact models; a user's bicycle with ``--model``) where it can represent them: the
    quantities it declares (a stage: worker processes call it)."""
    from engines.facts import engine_facts

    from .runs import label_of
    label, shown = label_of(spec), engine_facts(spec).label
    on = "" if tuple(models) == THESIS_MODELS else f" on {', '.join(load_model(m).name for m in models)}"
    sec = Section(f"Reference vs {shown}{on}, term by term")
    sec.text(f"`{spec}`{' with ' + str(options) if options else ''} at {n_states} deterministic "
             "states (large lean, steer near ±π/2, rates up to 20 rad/s), the quantities it "
             "declares; errors relative to the scale each tolerance names "
             "(`comparisons/judgments/tolerances.toml`).")
    states = random_states(n_states, seed=7)
    rows, built = _terms_on_models(tolerances, sec, spec, label, options, states, n_states, models)
    sec.table(TERM_HEADER, rows)
    first = next(iter(built.values()), None)
    if first is not None and first[1].supports("mass_matrix"):
        ref, eng = first
        try:
            M_ref = ref.mass_matrix(states.q)
            diff = np.abs(M_ref - eng.mass_matrix(states.q)).max(axis=0) / np.abs(M_ref).max()
        except Exception:   # noqa: BLE001 - its failure is already a FAIL row above
            return sec
        name = next(k for k, v in built.items() if v is first)
        sec.figure(f"mass_matrix_error_{_slug(label)}{'' if name == 'thesis' else '_' + _slug(load_model(name).name)}.png",
                   "matrix_error", relative=diff, labels=list(COORDINATES),
                   tolerance=tolerances["mass_matrix"].tolerance,
                   title=f"mass matrix: reference vs {shown} on {load_model(name).name}, max "
                         "over the states",
                   colorbar="log10 max |M_ref - M_engine| / max|M|")
    return sec


#: the name earlier releases gave `engine_terms` (a plugin's terms; now every engine's)
plugin_terms = engine_terms


def _slug(name: str) -> str:
    from .cases import slug
    return slug(name)


class TermsStage(Stage):
    """Every selected engine that declares a term, term by term: on the thesis bicycle, or on
    each ``--model``."""

    name, section = "terms", "terms"

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        n = QUICK_N_STATES if plan.quick else N_STATES
        out = []
        models = [(m.spec, m.name) for m in plan.opts.models] or [(None, None)]
        for f in plan.engines(lambda f: f.has_terms):
            for spec, name in models:
                args = (plan.tolerances, f.spec, plan.options_for(f.spec), n)
                out.append(Task((f.spec, spec), engine_terms, args if spec is None else args + ((spec,),),
                                f.costs.terms,
                                f"{f.label} term by term" + (f" on {name}" if name else ""),
                                f.spec))
        return out

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        for key in results:
            spec, model = key
            who = plan.facts[spec].label
            title = (f"Reference vs {who}, term by term" if model is None else
                     f"{_model_name(plan, model)}: reference vs {who}, term by term")
            v, failed = self.value(results, key, title)
            out.sections.append(failed or v)
        return out


def _model_name(plan: Plan, spec: str) -> str:
    return next((m.name for m in plan.opts.models if m.spec == spec), spec)
