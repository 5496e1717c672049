"""The option studies: an engine option whose values other than the reference's build another
bicycle (`engines.facts.OptionStudy`, e.g. a tyre's crown radius), quantified in the roll/steer
eigenvalues against speed and the weave and capsize speeds against the option.

    value = option_value(spec, options, study, value, model_spec)   # a stage: one value
    section, summary = option_study_section(facts, study, model, values, tolerances)

For every engine declaring an option study and the ``eigenvalues`` capability, each declared
value is one task: the engine built with the run's options and that value, its eigenvalues on
the comparison grid (`engine_eigenvalues.GRID`) and on a 0.1 m/s grid for the figure, and its
critical speeds. Judged: at the study's ``reference_value`` the engine's bicycle is the
reference's, so it is held to the reference's exact linearization exactly as in the engines'
linearization section (``[engine_eigenvalues]``, ``[engine_critical_speeds]``): that is the
study's independent check. At every other value the bicycle differs by the declared model
difference: its rows are *reported* (passed None, the difference named) with their numbers
(the eigenvalues' distance from the reference's, each critical speed and its shift), never a
failure.

Which models: each ``--model`` the engine models, else ``benchmark`` (self-stable between its
weave and capsize speeds, so both shifts are visible; thesis-disc has neither in 0-10 m/s).
Cost: ~0.3 s per value (building the engine on cached code, 21 + 101 speeds, the root
finding); the declared ``quick_values`` only in ``--quick`` (none: not run).
"""

from __future__ import annotations

import numpy as np

from ..judgments.engine_eigenvalues import check_rows, judge_eigenvalues
from ..judgments.rows import Comparison
from .engine_eigenvalues import (GRID, SPEED_RANGE, linearization_model, linearized,
                                 reference_linearization)
from .results import Section
from .stage import Assembled, Plan, Stage

__all__ = ["CURVE", "DEFAULT_MODEL", "OptionStudyStage", "option_study_section", "option_value"]

#: the figure's speed grid (m/s)
CURVE = tuple(float(v) for v in np.round(np.arange(0.0, 10.0 + 1e-9, 0.1), 10))
DEFAULT_MODEL = "benchmark"


def option_value(spec: str, options: dict, option: str, value: float, model_spec: str) -> dict:
    """One option value's linearization (a stage): the engine built with ``options`` and
    ``option = value``. A dict: value, model, note, speeds, lam, curve, critical, ref_lam,
    ref_curve, ref_critical, seconds; or ``not_run`` (the reason)."""
    from engines import UnsupportedModel, load_engine
    from engines.base import CapabilityError
    model, note = linearization_model(model_spec)
    out = {"value": float(value), "model": model.name, "note": note, "speeds": GRID}
    try:
        eng = load_engine(spec, model, **{**options, option: value})
    except (UnsupportedModel, CapabilityError) as exc:
        return {**out, "not_run": f"not run on this model: {exc}"}
    mine = linearized(eng, GRID, CURVE)
    ref_lam, ref_crit = reference_linearization(model, GRID)
    return {**out, "lam": mine["lam"], "curve": mine["curve"], "critical": mine["critical"],
            "seconds": mine["seconds"], "ref_lam": ref_lam, "ref_curve": model.eigenvalues(
                np.asarray(CURVE)), "ref_critical": ref_crit}


def _speed(x) -> str:
    return "none" if x is None else f"{x:.6f}"


def _shift(x, ref) -> str:
    """The shift of a critical speed (m/s): 6 decimals, or the round-off's size when smaller."""
    if x is None or ref is None:
        return "-"
    d = x - ref
    return f"{d:+.6f}" if abs(d) >= 5e-7 else f"{d:+.0e}"


def option_study_section(facts, study, model: str, values: list[dict],
                         tolerances) -> tuple[Section, dict]:
    """The section of one engine's study on one model (``values``: `option_value`'s, in the
    study's order), and its summary.json entry."""
    from .cases import slug
    sec = Section(f"Option study: {facts.label}'s {study.quantity} on {model}")
    sec.text(
        f"`{study.option}` = {study.reference_value:g} {study.unit} is the reference's bicycle; "
        f"any other value is a declared model difference: {study.difference}. Values "
        f"{', '.join(f'{v:g}' for v in study.values)} {study.unit}"
        + (f" ({study.why})" if study.why else "") + ". "
        f"At {study.reference_value:g} {study.unit} the engine's eigenvalues and critical "
        "speeds are judged against the reference's exact linearization (the study's "
        "independent check, tolerances [engine_eigenvalues] and [engine_critical_speeds]); at "
        "the others they are reported: their distance from the reference's eigenvalues "
        "(matched, relative to max(1, max |eigenvalue|), largest over the grid) and the shift "
        "of each critical speed quantify the difference."
        + (f" {values[0]['note']}." if values and values[0].get("note") else ""))
    rows, entries, done = [], [], []
    for v in values:
        x = v["value"]
        at_ref = x == study.reference_value
        if "not_run" in v:
            rows.append((f"{x:g}", "-", "-", "-", "-", "-", "not run"))
            entries.append({"value": x, "not_run": v["not_run"]})
            sec.comparisons.append(Comparison.of({
                "quantity": f"option study {study.option}: roll/steer eigenvalues",
                "scenario": f"{study.option} = {x:g} {study.unit}", "model": model,
                "engines": ["reference", facts.name], "max_error": None, "tolerance": None,
                "passed": None, "localized_to": v["not_run"], "note": v["not_run"]}))
            continue
        difference = "" if at_ref else f"{study.option} = {x:g} {study.unit}: {study.difference}"
        c = judge_eigenvalues(facts.name, model, v["speeds"], v["lam"], v["ref_lam"],
                              v["critical"], v["ref_critical"], SPEED_RANGE, tolerances,
                              difference)
        w, k = c.critical
        word = ("pass" if c.passed else "FAIL") if at_ref else "reported: model difference"
        rows.append((f"{x:g}", f"{c.error:.2e}", _speed(w.engine), _shift(w.engine, w.reference),
                     _speed(k.engine), _shift(k.engine, k.reference), word))
        sec.comparisons.extend(r.replace(option=study.option, value=x) for r in check_rows(
            c, f"option study {study.option}", f"{study.option} = {x:g} {study.unit}"))
        entries.append({"value": x, "eigenvalue_distance": c.error,
                        "weave_speed": w.engine, "capsize_speed": k.engine,
                        "passed": c.passed, "declared_difference": difference or None})
        done.append(v)
    sec.table((f"{study.quantity} [{study.unit}]", "eigenvalues vs reference (relative)",
               "weave speed [m/s]", "shift [m/s]", "capsize speed [m/s]", "shift [m/s]",
               "verdict"), rows,
              note="shift: the engine's critical speed minus the reference's (the reference's "
                   "own bicycle); none: no such speed in "
                   f"{SPEED_RANGE[0]:g}-{SPEED_RANGE[1]:g} m/s")
    if done:
        sec.figure(f"option_study_{slug(facts.name)}_{slug(study.option)}_{slug(model)}.png",
                   "option_study", caption=(
                       f"Left: the real parts of the four roll/steer eigenvalues against speed at "
                       f"each {study.quantity} (the reference's exact ones in black; the castor "
                       f"mode leaves the axes below -10 /s). Right: the weave and capsize speeds "
                       f"against the {study.quantity}, the reference's circled."),
                   engine=facts.name, label=facts.label,
                   quantity=study.quantity, unit=study.unit,
                   values=[v["value"] for v in done], reference_value=study.reference_value,
                   v=np.asarray(CURVE), re=np.array([np.asarray(v["curve"]).real for v in done]),
                   ref_re=np.asarray(done[0]["ref_curve"]).real,
                   critical=[tuple(v["critical"]) for v in done],
                   ref_critical=tuple(done[0]["ref_critical"]), model=model)
    ref_w, ref_k = done[0]["ref_critical"] if done else (None, None)
    summary = {"engine": facts.name, "option": study.option, "unit": study.unit,
               "model": model, "reference_value": study.reference_value,
               "reference_weave_speed": ref_w, "reference_capsize_speed": ref_k,
               "values": entries}
    return sec, summary


class OptionStudyStage(Stage):
    """Every declared option study (`engines.facts.OptionStudy`) of the engines with the
    ``eigenvalues`` capability, on each ``--model`` (default: benchmark)."""

    name, section = "option-study", "option-study"

    @staticmethod
    def _studies(plan: Plan) -> list:
        return [(f, s) for f in plan.engines(lambda f: "eigenvalues" in f.capabilities)
                for s in f.option_studies if not plan.quick or s.quick_values]

    def prepare(self, plan: Plan) -> None:
        """Each study's declared shared work (e.g. the generated code of the option's variant:
        cold, a minute, which one task's time limit would not allow), once before the workers
        fork."""
        for f, s in self._studies(plan):
            if s.prepare is not None:
                s.prepare()

    @staticmethod
    def _models(plan: Plan, facts) -> tuple[list[str], list]:
        """(the model specs the study runs on, the ``--model`` s whose front contact the
        engine does not model)."""
        if not plan.opts.models:
            return [DEFAULT_MODEL], []
        return ([m.spec for m in plan.opts.models if m.contact in facts.contacts],
                [m for m in plan.opts.models if m.contact not in facts.contacts])

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        out = []
        for f, s in self._studies(plan):
            values = s.quick_values if plan.quick else s.values
            for spec in self._models(plan, f)[0]:
                out += [Task((f.spec, s.option, spec, x), option_value,
                             (f.spec, plan.options_for(f.spec), s.option, x, spec), 0.4,
                             f"{spec}: {f.label} at {s.option} = {x:g} {s.unit}", f.spec)
                        for x in values]
        return out

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        summary = []
        for f, s in self._studies(plan):
            keys = [k for k in results if k[0] == f.spec and k[1] == s.option]
            for spec in dict.fromkeys(k[2] for k in keys):
                values, failed = [], []
                for key in (k for k in keys if k[2] == spec):
                    v, bad = self.value(results, key, f"Option study: {f.label} at "
                                        f"{s.option} = {key[3]:g} {s.unit}")
                    (values.append(v) if bad is None else failed.append(bad))
                if values:
                    sec, entry = option_study_section(f, s, values[0]["model"], values,
                                                      plan.tolerances)
                    out.sections.append(sec)
                    summary.append(entry)
                out.sections += failed
            for m in self._models(plan, f)[1]:     # a declared limitation: said, not failed
                why = (f"not run on this model: {f.label} models the front contact(s) "
                       f"{', '.join(f.contacts)}, not {m.contact!r}")
                sec = Section(f"Option study: {f.label}'s {s.quantity} on {m.name}")
                sec.text(f"{why}.")
                sec.comparisons.append(Comparison.of({
                    "quantity": f"option study {s.option}: roll/steer eigenvalues",
                    "scenario": "-", "model": m.name, "engines": ["reference", f.name],
                    "max_error": None, "tolerance": None, "passed": None, "localized_to": why,
                    "note": why}))
                out.sections.append(sec)
        if summary:
            out.summary["option_studies"] = summary
        return out
