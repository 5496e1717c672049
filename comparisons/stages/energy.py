"""The energy drift of a torque- and drag-free roll (IFToMM: 100 (Emax - Emin) / E0): the
reference and every selected engine that simulates and declares no model difference of its runs
(a soft contact dissipates by design), each variant of a fixed-step integrator at its step.
Judged against ``tolerances.toml`` [energy_drift].
"""

from __future__ import annotations

import numpy as np

from engines import load_engine
from reference_model import load_model

from ..judgments.energy import describe_drift, energy_drifts, free_roll_model
from ..judgments.tolerances import Tolerances
from ..judgments.rows import Comparison
from .results import Section
from .stage import Assembled, Plan, Stage

__all__ = ["EnergyStage", "energy_section", "free_roll_on"]


def free_roll_on(spec: str, free) -> tuple:
    """The energy check's free roll on ``spec`` and how it starts, in words. On thesis-disc
    the stability study's leaned and steered state (pi/16) at psi_dot = 10 rad/s; on a user's
    bicycle a gentler start, lean and steer pi/32 at the middle of its self-stable speed range
    (1.2 x its weave speed when it has no capsize speed below 10 m/s, psi_dot = 10 rad/s when
    it has no weave speed either), so that the bicycle does not fall within the second:
    measured on BicycleParameters' Browserins, the thesis's start falls at 0.99 s and even at
    a self-stable speed it reaches 1.3 rad of lean, where a second-order integrator's drift at
    h = 1e-3 s is 0.3 %, against 1.4e-4 % from pi/32."""
    from ..judgments.energy import free_roll_scenario
    if spec == "thesis-disc":
        return None, "the stability study's leaned and steered state at psi_dot = 10 rad/s"
    from .stability import critical
    crit = critical(spec) if free.contact == "disc" else {}
    if "weave" in crit:
        v = (0.5 * (crit["weave"] + crit["capsize"]) if "capsize" in crit
             else 1.2 * crit["weave"])
        psi_dot = v / free.params.R_rear
    else:
        psi_dot = 10.0
    sc = free_roll_scenario(psi_dot=psi_dot, model=free.name, lean=np.pi / 32)
    return sc, (f"lean and steer pi/32 at psi_dot = {psi_dot:.4g} rad/s "
                f"(v = {psi_dot * free.params.R_rear:.3f} m/s"
                + (", the middle of its self-stable range)" if "capsize" in crit else ")"))


def _runs_of(spec: str, options: dict) -> list[tuple[str, dict]]:
    """(label, options) of the engine's energy runs: every variant of a fixed-step integrator
    at its step, else its first run setup (or the command line's options)."""
    from engines.facts import engine_facts

    from .runs import engine_setups
    f = engine_facts(spec)
    if f.fixed_step is not None and not options:
        return f.fixed_step.runs(f.name, sep=" ")
    s = engine_setups(spec, options)[0]
    return [(s.label, dict(s.options))]


def energy_rows(spec: str | None, options: dict, model: str = "thesis-disc") -> list[dict]:
    """The energy drift rows of one engine (``spec``; None: the reference) on ``model``'s free
    roll (a stage: one per engine, so they run in parallel). An engine that cannot represent
    the model gives one 'not run' row with the reason."""
    from engines import UnsupportedModel
    free = free_roll_model(load_model(model))
    scenario, _ = free_roll_on(model, free)
    if spec is None:
        return energy_drifts(free, scenario)
    import dataclasses

    from engines import EngineError
    from ..judgments.energy import free_roll_scenario
    sc = scenario or free_roll_scenario(model=free.name)
    rows = []
    for label, opts in _runs_of(spec, options):
        try:
            eng = load_engine(spec, free, **opts)
        except UnsupportedModel as exc:
            rows.append({"engine": label, "not_run": f"not run on this model: {exc}"})
            continue
        try:
            rows += energy_drifts(free, sc, [(label, eng)])[1:]
        except EngineError as first:   # an engine that refuses projection: its Baumgarte run
            try:
                baum = dataclasses.replace(sc, constraints="baumgarte")
                row = energy_drifts(free, baum, [(label, eng)])[1]
                row["settings"] += f"; Baumgarte a1 = a2 = {baum.baumgarte[0]:g} (it refused " \
                                   f"projection: {' '.join(str(first).split())[:120]})"
                rows.append(row)
            except Exception as exc:   # noqa: BLE001 - the engine's failure: a FAIL row
                rows.append({"engine": label, "failed": f"{type(exc).__name__}: "
                                                        f"{' '.join(str(exc).split())[:300]}"})
        except Exception as exc:   # noqa: BLE001 - the engine's failure: a FAIL row, counted
            rows.append({"engine": label, "failed": f"{type(exc).__name__}: "
                                                    f"{' '.join(str(exc).split())[:300]}"})
    return rows


def energy_section(tolerances: Tolerances, engines: tuple[tuple[str, dict], ...],
                   model: str = "thesis-disc", rows: list[dict] | None = None) -> Section:
    """The energy drift of a torque- and drag-free roll of ``model`` (default thesis-disc; a
    user's bicycle with ``--model``) on the reference and each of ``engines`` ((spec,
    options) pairs), or from their ``rows`` (`energy_rows`, the reference's first) when
    given."""
    sec = Section("Energy drift, torque-free and drag-free (IFToMM: 100 (Emax - Emin) / E0)"
                  + ("" if model == "thesis-disc" else f" on {load_model(model).name}"))
    free = free_roll_model(load_model(model))
    _, start = free_roll_on(model, free)
    if rows is None:
        rows = energy_rows(None, {}, model) + [r for spec, o in engines
                                                for r in energy_rows(spec, o, model)]
    tol = tolerances["energy_drift"]
    sec.text(f"Free roll from {start} for 1 s, cv = 0, no torques; potential energy zero at "
             "the ground.",
             f"Tolerance {tol.tolerance:g} % (`tolerances.toml` [energy_drift]: {tol.reason})")
    table = []
    for r in rows:
        if "not_run" in r:
            table.append((r["engine"], "-", "-", "-", "not run", r["not_run"]))
            continue
        if "failed" in r:   # asked for and not made: the engine's failure, counted
            table.append((r["engine"], "-", "-", "-", "FAIL", r["failed"]))
            sec.comparisons.append(Comparison.of({"quantity": "energy drift percent", "scenario": "free-roll",
                                    "model": f"{free.name} (cv = 0)", "engines": [r["engine"]],
                                    "max_error": None, "tolerance": tol.tolerance,
                                    "passed": False, "localized_to": r["failed"]}))
            continue
        ok = r["status"] != "failed" and r["drift_percent"] <= tol.tolerance
        table.append((r["engine"], r["settings"], f"{r['E0']:.3f}", f"{r['drift_percent']:.2e}",
                      "pass" if ok else "FAIL", f"{r['status']} at {r['t_end']:.2f} s"))
        sec.comparisons.append(Comparison.of({"quantity": "energy drift percent", "scenario": "free-roll",
                                "model": f"{free.name} (cv = 0)", "engines": [r["engine"]],
                                "max_error": r["drift_percent"], "tolerance": tol.tolerance,
                                "passed": bool(ok), "localized_to": r["settings"],
                                "note": describe_drift(r)}))
    sec.table(("engine", "settings", "E0 [J]", "drift [% of E0]", "verdict", "status"), table)
    return sec


class EnergyStage(Stage):
    """The energy drift on thesis-disc, or on each ``--model``: one task per engine."""

    name, section = "energy", "energy"

    def _engines(self, plan: Plan) -> list:
        return plan.engines(lambda f: "simulate" in f.capabilities and f.run_difference is None)

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        engines = self._engines(plan)
        if not engines:
            return []
        models = [(m.spec, m.name) for m in plan.opts.models] or [("thesis-disc", None)]
        out = []
        for spec, name in models:
            where = f"{name}: " if name else ""
            out.append(Task((None, spec), energy_rows, (None, {}, spec), 0.5,
                            f"{where}energy drift of the reference"))
            out += [Task((f.spec, spec), energy_rows, (f.spec, plan.options_for(f.spec), spec),
                         f.costs.run_per_second * (1 + (f.fixed_step is not None)),
                         f"{where}energy drift on {f.label}", f.spec) for f in engines]
        return out

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        for model in dict.fromkeys(k[1] for k in results):
            rows, failed = [], []
            for key in (k for k in results if k[1] == model):
                v, f = self.value(results, key, "Energy drift"
                                  + (f" on {plan.facts[key[0]].label}" if key[0] else ""))
                (rows.extend(v) if f is None else failed.append(f))
            if rows and "not_run" not in rows[0] and rows[0]["engine"].startswith("reference"):
                out.sections.append(energy_section(plan.tolerances, (), model, rows))
            out.sections += failed
        return out
