"""A model's linearization against the benchmark's closed form (``bicycle-xval run --model``).

    section = linear_check(tolerances, spec)   # a stage: spec as load_model takes it

The judgment is `judgments.linear_check.linear_benchmark_check` (the project's exact
linearization against Meijaard et al. 2007, Appendix A, from the model's own Table 1 values),
over the stability section's speed range; the tolerances are `[linear_closed_form]` and
`[linear_closed_form_speeds]`. A model without a benchmark counterpart (the thesis's front
contact, wheels with Izz != Ixx) gets a section saying why and one *reported* row, never a
failure. Cheap: one linearization and a few thousand 4x4 eigenvalue problems, batched (~0.1 s
with loading the model, measured on the ten BicycleParameters sets).
"""

from __future__ import annotations

from reference_model import load_model

from ..judgments.linear_check import LinearCheck, SpeedCheck, linear_benchmark_check
from ..judgments.tolerances import Tolerances
from .results import Section, num
from .stability import SPEED_RANGE
from .stage import Assembled, Plan, Stage

__all__ = ["ENGINES", "linear_check", "linear_check_section"]

#: the two sides of every comparison row
ENGINES = ["linearize", "closed form (Meijaard 2007)"]


def linear_check(tolerances: Tolerances, spec: str) -> Section:
    """The section of the model ``spec`` judged by ``tolerances`` (a stage; module docstring)."""
    model = load_model(spec)
    return linear_check_section(linear_benchmark_check(model, tolerances, SPEED_RANGE))


def _speed(v: float | None) -> str:
    return "none" if v is None else f"{v:.12f}"


def _where(s: SpeedCheck, lo: float, hi: float) -> str:
    if s.closed_form is None and s.linearization is None:
        return f"none in {lo:g}-{hi:g} m/s on both"
    return f"closed form {_speed(s.closed_form)} m/s, linearization {_speed(s.linearization)} m/s"


def linear_check_section(check: LinearCheck) -> Section:
    """The section and its comparison rows for one judged model."""
    sec = Section(f"Linearization of {check.model} against the benchmark's closed form")
    scenario = f"{check.model}, upright straight running"
    if not check.applicable:
        sec.text(f"Not applicable: {check.reason}.")
        sec.comparisons.append({
            "quantity": "linearization vs closed form", "scenario": scenario,
            "model": check.model, "engines": ENGINES, "max_error": None, "tolerance": None,
            "passed": None, "localized_to": "-", "note": f"not applicable: {check.reason}"})
        return sec
    lo, hi = check.speeds_range
    sec.text(
        "The project's linearization about upright straight running (complex-step derivatives "
        "of the model's own reduced equations) against Meijaard et al. (2007), Appendix A, "
        "evaluated from the model's Table 1 values: independent formulas, so a disagreement is "
        "an error in one of them. Matrices in benchmark signs over [phi, delta], difference "
        "relative to the closed form's largest entry; weave and capsize speeds in "
        f"{lo:g}-{hi:g} m/s, the closed form's by its own root finding on its eigenvalues"
        + (f". {check.note}." if check.note else "."))
    rows = []
    for c in check.matrices:
        rows.append((c.name, f"{c.error:.1e}", f"{c.tolerance:.0e}",
                     "pass" if c.passed else "FAIL", c.worst))
        sec.comparisons.append({
            "quantity": f"linearization vs closed form: {c.name}", "scenario": scenario,
            "model": check.model, "engines": ENGINES, "max_error": c.error,
            "tolerance": c.tolerance, "passed": c.passed, "localized_to": c.worst,
            "note": "max |difference| / max |closed form| over the matrix"})
    sec.table(("matrix", "max relative difference", "tolerance", "verdict", "worst entry"), rows)
    rows = []
    for s in check.speeds:
        rows.append((f"{s.mode} speed", _speed(s.closed_form), _speed(s.linearization),
                     num(s.difference), f"{s.tolerance:.0e}", "pass" if s.passed else "FAIL"))
        sec.comparisons.append({
            "quantity": f"linearization vs closed form: {s.mode} speed", "scenario": scenario,
            "model": check.model, "engines": ENGINES, "max_error": s.difference,
            "tolerance": s.tolerance, "passed": s.passed, "closed_form": s.closed_form,
            "linearization": s.linearization, "localized_to": _where(s, lo, hi),
            "note": f"in {lo:g}-{hi:g} m/s; none on both counts as agreement"})
    sec.table(("critical speed", "closed form [m/s]", "linearization [m/s]", "difference [m/s]",
               "tolerance", "verdict"), rows)
    return sec


class LinearCheckStage(Stage):
    """Each ``--model``'s linearization against the benchmark's closed form."""

    name, section = "linear-check", None

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        return [Task(m.spec, linear_check, (plan.tolerances, m.spec), 0.1,
                     f"{m.name}: linearization vs the closed form") for m in plan.opts.models]

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        names = {m.spec: m.name for m in plan.opts.models}
        for key in results:
            v, failed = self.value(results, key,
                                   f"{names[key]}: linearization against the closed form")
            out.sections.append(failed or v)
        return out
