"""Every engine's own linearization against the reference's: the roll/steer eigenvalues of
each engine declaring the ``eigenvalues`` capability, over a speed grid, and its weave and
capsize speeds (`judgments.engine_eigenvalues`; tolerances ``[engine_eigenvalues]`` and
``[engine_critical_speeds]``).

    value = engine_linearization(spec, options, model_spec)   # a stage: one engine, one model
    section = engine_eigenvalues_section(values, tolerances)

Which models: each ``--model``, else ``benchmark`` and ``thesis-disc`` (the benchmark's
knife-edge disc and the thesis's bicycle on it); a model with drag is linearized with cv = 0
(no steady upright motion otherwise), as the stability section does. An engine that does not
model the front contact (or cannot represent the bicycle) is *not run* on it, with the
reason, never a failure; an engine without the capability gets no rows.

Cost: one task per engine and model: the grid's 21 speeds (one batch of 168 states), which
also bracket the critical speeds, then about 14 calls of one speed (8 states each) for their
root finding, plus building the engine: measured 0.05 s (Pinocchio) to 0.5 s (DART, ~1 ms per
state) per task on the 2-core machine. Not run by ``--quick``.
"""

from __future__ import annotations

import time

import numpy as np

from ..judgments.engine_eigenvalues import EigenvalueCheck, check_rows, judge_eigenvalues
from ..judgments.rows import Comparison
from .results import Section
from .stage import Assembled, Plan, Stage

__all__ = ["DEFAULT_MODELS", "EngineEigenvaluesStage", "GRID", "SPEED_RANGE", "check_of",
           "engine_eigenvalues_section", "engine_linearization", "linearization_model",
           "linearized", "reference_linearization"]

#: the comparison's speed grid (m/s): 21 speeds; the nearest to a coalescence of two
#: eigenvalues (where the error of any linearization grows like its square root) is 0.5 m/s,
#: 0.18 m/s from the benchmark's (0.684 m/s, the weave pair forming); thesis-disc's (cv = 0)
#: have none in 0-10 m/s (measured on a 1e-4 m/s grid)
GRID = tuple(float(v) for v in np.linspace(0.0, 10.0, 21))
SPEED_RANGE = (0.0, 10.0)      # m/s: where the critical speeds are looked for
DEFAULT_MODELS = ("benchmark", "thesis-disc")


def linearization_model(spec: str):
    """(the model as linearized: cv = 0, a note when drag was removed)."""
    from reference_model import load_model
    m = load_model(spec)
    if m.params.cv != 0.0:
        return (m.with_params(m.params.replace(cv=0.0)),
                f"{m.name} has drag (cv = {m.params.cv:g} kg/m): linearized with cv = 0")
    return m, ""


def reference_linearization(model, speeds) -> tuple[np.ndarray, tuple]:
    """The reference's exact eigenvalues at ``speeds`` and its (weave, capsize) speeds in
    ``SPEED_RANGE``."""
    from ..judgments.eigenvalues import critical_speeds
    return model.eigenvalues(np.asarray(speeds)), critical_speeds(model, np.array(SPEED_RANGE))


def linearized(engine, speeds, fine: tuple[float, ...] = ()) -> dict:
    """A built engine's eigenvalues at ``speeds`` (and at ``fine``, for a figure) and its
    critical speeds in ``SPEED_RANGE``, bracketed on those (the finer if given), with the
    time it took."""
    from engines.linear import critical_speeds
    t0 = time.perf_counter()
    lam = np.asarray(engine.eigenvalues(np.asarray(speeds)))
    curve = np.asarray(engine.eigenvalues(np.asarray(fine))) if fine else None
    known = (np.asarray(fine), curve) if fine else (np.asarray(speeds), lam)
    weave, capsize = critical_speeds(engine.eigenvalues, SPEED_RANGE, known=known)
    return {"lam": lam, "curve": curve, "critical": (weave, capsize),
            "seconds": time.perf_counter() - t0}


def engine_linearization(spec: str, options: dict, model_spec: str, label: str = "") -> dict:
    """One engine's eigenvalues on one model, and the reference's (a stage). A dict: engine,
    model, note, speeds, lam, critical, ref_lam, ref_critical; or ``not_run`` (the reason)."""
    from engines import EngineError, UnsupportedModel, load_engine
    from engines.base import CapabilityError
    model, note = linearization_model(model_spec)
    out = {"engine": label or spec, "model": model.name, "note": note, "speeds": GRID}
    try:
        eng = load_engine(spec, model, **options)
    except (UnsupportedModel, CapabilityError) as exc:   # a declared limitation: said
        return {**out, "not_run": f"not run on this model: {exc}"}
    except EngineError as exc:
        return {**out, "failed": str(exc)}
    if not eng.supports("eigenvalues"):
        return {**out, "not_run": "its options leave it without the eigenvalues capability"}
    mine = linearized(eng, GRID)
    ref_lam, ref_crit = reference_linearization(model, GRID)
    return {**out, "lam": mine["lam"], "critical": mine["critical"],
            "seconds": mine["seconds"], "ref_lam": ref_lam, "ref_critical": ref_crit}


def check_of(value: dict, tolerances, difference: str = "") -> EigenvalueCheck:
    """The judgment of one `engine_linearization` value."""
    return judge_eigenvalues(value["engine"], value["model"], value["speeds"], value["lam"],
                             value["ref_lam"], value["critical"], value["ref_critical"],
                             SPEED_RANGE, tolerances, difference)


def _speed(x) -> str:
    return "none" if x is None else f"{x:.10f}"


def engine_eigenvalues_section(values: list[dict], tolerances) -> tuple[Section, dict]:
    """The section over every engine and model, and summary.json's ``engine_eigenvalues``."""
    sec = Section("Engines' linearizations against the reference's")
    et, st = tolerances["engine_eigenvalues"], tolerances["engine_critical_speeds"]
    notes = sorted({v["note"] for v in values if v.get("note")})
    sec.text(
        "Each engine declaring the `eigenvalues` capability linearizes its own bicycle about "
        "upright straight running (most by central differences of their own constrained "
        "accelerations on their own constraints, `engines.linear`); the reference's are exact "
        "(complex-step derivatives of the thesis's reduced equations). The four roll/steer "
        f"eigenvalues at {len(GRID)} speeds {GRID[0]:g}-{GRID[-1]:g} m/s are matched pairwise "
        "(a sort order that flips where a pair forms is not an error); the error is the "
        "largest |difference| over max(1, max |eigenvalue|), tolerance "
        f"{et.tolerance:.0e}; the weave and capsize speeds in {SPEED_RANGE[0]:g}-"
        f"{SPEED_RANGE[1]:g} m/s, found on each side's own eigenvalues, within "
        f"{st.tolerance:.0e} m/s." + (" " + "; ".join(notes) + "." if notes else ""))
    rows, summary = [], {}
    for v in values:
        entry = summary.setdefault(v["engine"], {})
        if "not_run" in v or "failed" in v:
            why = v.get("not_run") or v["failed"]
            rows.append((v["engine"], v["model"], "-", "-", "-", "-",
                         "not run" if "not_run" in v else "FAIL", why))
            entry[v["model"]] = {"not_run" if "not_run" in v else "failed": why}
            sec.comparisons.append(Comparison.of({
                "quantity": "eigenvalues: roll/steer eigenvalues", "scenario":
                "upright straight running", "model": v["model"],
                "engines": ["reference", v["engine"]], "max_error": None,
                "tolerance": et.tolerance, "passed": None if "not_run" in v else False,
                "localized_to": why, "note": why}))
            continue
        c = check_of(v, tolerances)
        w, k = c.critical
        word = "pass" if c.passed else "FAIL"
        rows.append((v["engine"], v["model"], f"{c.error:.1e} at {c.worst_speed:g} m/s",
                     f"{_speed(w.engine)} ({'-' if w.difference is None else f'{w.difference:.0e}'})",
                     f"{_speed(k.engine)} ({'-' if k.difference is None else f'{k.difference:.0e}'})",
                     f"{v['seconds']:.2f}", word, ""))
        entry[v["model"]] = {"max_error": c.error, "worst_speed": c.worst_speed,
                             "weave_speed": w.engine, "capsize_speed": k.engine,
                             "reference_weave_speed": w.reference,
                             "reference_capsize_speed": k.reference,
                             "passed": c.passed, "seconds": v["seconds"]}
        sec.comparisons.extend(check_rows(c))
    sec.table(("engine", "model", "eigenvalue error (relative)",
               "weave speed [m/s] (|difference|)", "capsize speed [m/s] (|difference|)",
               "time [s]", "verdict", "why"), rows,
              note="none: no such speed in the range (agreement when the reference has none "
                   "either)")
    return sec, summary


class EngineEigenvaluesStage(Stage):
    """Each engine with the ``eigenvalues`` capability against the reference's linearization,
    on each ``--model`` (default: benchmark, thesis-disc). Not in ``--quick``."""

    name, section = "engine-eigenvalues", "eigenvalues"

    @staticmethod
    def _engines(plan: Plan) -> list:
        return plan.engines(lambda f: "eigenvalues" in f.capabilities)

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        if plan.quick:
            return []
        models = [m.spec for m in plan.opts.models] or list(DEFAULT_MODELS)
        return [Task((f.spec, spec), engine_linearization,
                     (f.spec, plan.options_for(f.spec), spec, f.name), 0.5,
                     f"{spec}: eigenvalues of {f.label}", f.spec)
                for spec in models for f in self._engines(plan)]

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        if not results:
            return out
        values, failed = [], []
        for key in results:
            v, f = self.value(results, key, f"Eigenvalues of {plan.facts[key[0]].label}")
            (values.append(v) if f is None else failed.append(f))
        if values:
            sec, summary = engine_eigenvalues_section(values, plan.tolerances)
            out.sections.append(sec)
            out.summary["engine_eigenvalues"] = summary
        out.sections += failed
        return out
