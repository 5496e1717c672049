"""One bicycle of a sweep: a pure function of (spec, index) returning one plain row (a dict).

    row = bicycle_row(spec, k)          # what every chunk of `stages.sweep` maps over

Columns (`columns` lists them in order; every row has all of them, NaN / "" where a check was
not asked for or could not run):

* ``bicycle`` (index in the sweep), ``seed`` (the states' seed), ``status`` ("agree": every
  check held; "disagree": a term beyond tolerance or a run contradicting the linear
  prediction; "failed": an engine or the model raised; "invalid": the sampled parameters are
  not a bicycle), ``failures`` (``engine: message`` joined by " | ");
* ``vary.<name>`` for every varied name (the grid's value, or the sampled value), then
  ``trail``, ``head_angle``, ``wheelbase`` (derived, NaN without a benchmark counterpart) and
  ``p.<name>`` for the model's 30 parameters;
* terms (``--checks terms``), per engine E (its name, or the class name of a ``file.py:Class`` spec) and quantity Q
  both provide: ``err.E.Q`` (max error
  normalised as its tolerance in `judgments/tolerances.toml`), ``entry.E.Q`` (worst entry and
  state, e.g. "M[theta, gamma] @ state 3"); ``max_error`` over all, ``terms_passed``;
  ``localization`` (for a bicycle that disagrees: the failing entries and `judgments.diagnose`'s
  best explanation by one parameter or structural cause);
* eigen: ``weave_speed``, ``capsize_speed`` (m/s, in `stability.SPEED_RANGE`; NaN where none);
* runs: ``run.<mode>.<factor>.<engine>`` = "confirmed" / "contradicted" / "failed: ..." for
  forward runs (on the reference and each engine `run_options` finds: those that declare a
  forward run on the contact and no model difference) at 0.9 and 1.1 x each critical speed
  (`stages.stability`'s scenario and judgment), ``runs_confirmed``;
* ``task_seconds``: the wall time of this bicycle on its worker (the only column that differs
  between two runs of the same spec).

The reference model of a contact variant is loaded once per worker process
(`reference_model.model._library` is cached per process; `_template` keeps one model per
variant), so a task only swaps the parameter vector.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .sweep_spec import DERIVED, SweepSpec, bicycle_parameters, derived_values, grid_point

_TEMPLATES: dict[str, object] = {}     # contact -> a Model: the per-process generated-code cache


def _template(contact: str):
    """One model per contact variant per process (loads and verifies the generated code once)."""
    if contact not in _TEMPLATES:
        from reference_model import load_model
        _TEMPLATES[contact] = load_model("benchmark" if contact == "disc" else "thesis")
    return _TEMPLATES[contact]


def quantities(spec: SweepSpec) -> dict[str, tuple[str, ...]]:
    """engine -> the quantities compared with the reference (what both declare)."""
    from engines.registry import resolve
    from ..judgments.terms import QUANTITIES
    ref = set(resolve("reference")[0].capabilities)
    out = {}
    for e in spec.engines:
        caps = set(resolve(e)[0].capabilities)
        out[e] = tuple(q for q in QUANTITIES if q in caps and q in ref)
    return out


def columns(spec: SweepSpec) -> list[str]:
    """Every column of a row, in order (module docstring)."""
    from reference_model.params import PARAMETER_NAMES
    cols = ["bicycle", "seed", "status", "failures"]
    cols += [f"vary.{n}" for n in spec.varied] + list(DERIVED)
    cols += [f"p.{n}" for n in PARAMETER_NAMES]
    if "terms" in spec.checks:
        for e, qs in quantities(spec).items():
            for q in qs:
                cols += [f"err.{label_of(e)}.{q}", f"entry.{label_of(e)}.{q}"]
        cols += ["max_error", "terms_passed", "localization"]
    if "eigen" in spec.checks:
        cols += ["weave_speed", "capsize_speed"]
    if "runs" in spec.checks:
        cols += [f"run.{mode}.{f:g}.{e}" for mode in ("weave", "capsize")
                 for f in _factors() for e in run_options(spec)]
        cols.append("runs_confirmed")
    cols.append("task_seconds")
    return cols


def label_of(spec: str) -> str:
    """An engine's name in the columns: its registered name or the class of a spec."""
    from .runs import label_of as label
    return label(spec)


def _factors():
    from .stability import FACTORS
    return FACTORS


def run_options(spec: SweepSpec) -> dict:
    """label -> `runs.EngineSetup` of the forward runs: the reference's, then, for every engine
    of the spec that models the spec's front contact, its first setup that goes into the
    stability picture (`stability.simulating`: it runs forward scenarios and declares no model
    difference; a soft contact's runs are not judged against ideal rolling's prediction)."""
    from engines.defaults import REFERENCE
    from engines.facts import engine_facts
    from .runs import engine_setups
    from .stability import simulating
    out = {}
    for e in (REFERENCE, *(e for e in spec.engines if e != REFERENCE)):
        if spec.contact not in engine_facts(e).contacts:
            continue
        setup = next((s for s in engine_setups(e) if simulating(s)), None)
        if setup is not None:
            out[label_of(e)] = setup
    return out


def empty_row(spec: SweepSpec, k: int) -> dict:
    """A row with every column at its 'not computed' value."""
    row: dict = {}
    for c in columns(spec):
        if c.startswith(("entry.", "run.")) or c in ("status", "failures", "localization"):
            row[c] = ""
        elif c in ("terms_passed", "runs_confirmed"):
            row[c] = None
        else:
            row[c] = math.nan
    row.update(bicycle=k, seed=_states_seed(spec, k))
    return row


def _states_seed(spec: SweepSpec, k: int) -> int:
    return int(np.random.SeedSequence([spec.seed, k, 1]).generate_state(1)[0])


def failed_row(spec: SweepSpec, k: int, message: str) -> dict:
    """The row of a bicycle whose task never returned (e.g. its worker died)."""
    row = empty_row(spec, k)
    row.update(status="failed", failures=message, task_seconds=math.nan)
    if spec.grids:
        row.update({f"vary.{n}": v for n, v in grid_point(spec, k)})
    return row


def bicycle_row(spec: SweepSpec, k: int) -> dict:
    """Every asked check on bicycle ``k`` (module docstring); never raises for a bicycle that
    breaks an engine: the failure is in the row."""
    from reference_model import ParameterError
    from reference_model.params import PARAMETER_NAMES
    t0 = time.perf_counter()
    row = empty_row(spec, k)
    failures: list[str] = []
    try:
        params = bicycle_parameters(spec, k)
    except ParameterError as exc:
        row.update(status="invalid", failures=f"parameters: {exc}",
                   task_seconds=time.perf_counter() - t0)
        if spec.grids:
            row.update({f"vary.{n}": v for n, v in grid_point(spec, k)})
        return row
    derived = derived_values(params)
    row.update(derived)
    row.update({f"p.{n}": float(getattr(params, n)) for n in PARAMETER_NAMES})
    if spec.grids:
        row.update({f"vary.{n}": v for n, v in grid_point(spec, k)})
    else:
        row.update({f"vary.{n}": float(getattr(params, n)) for n in spec.varied})
    model = _template(spec.contact).with_params(params)
    disagree = False
    if "terms" in spec.checks:
        disagree |= not _terms(spec, model, row, failures)
    crit: dict[str, float] = {}
    if "eigen" in spec.checks:
        try:
            from ..judgments.eigenvalues import critical_speeds
            from .stability import SPEED_RANGE
            weave, capsize = critical_speeds(model, np.array(SPEED_RANGE))
            crit = {m: v for m, v in (("weave", weave), ("capsize", capsize)) if v is not None}
            row.update(weave_speed=math.nan if weave is None else weave,
                       capsize_speed=math.nan if capsize is None else capsize)
        except Exception as exc:      # noqa: BLE001 -- a bicycle the linearization breaks is a row
            failures.append(f"eigen: {_one_line(exc)}")
    if "runs" in spec.checks:
        disagree |= not _runs(spec, model, crit, row, failures)
    row["failures"] = " | ".join(failures)
    row["status"] = "failed" if failures else ("disagree" if disagree else "agree")
    row["task_seconds"] = time.perf_counter() - t0
    return row


def _one_line(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"[:500]


def _terms(spec: SweepSpec, model, row: dict, failures: list[str]) -> bool:
    """Fill the terms columns; True when every compared quantity is within tolerance."""
    from engines import load_engine
    from ..judgments.terms import compare_term, random_states
    states = random_states(spec.n_states, seed=row["seed"])
    tols = spec.tolerances          # travelled with the task: no file, no environment
    ref = load_engine("reference", model)
    passed, worst, bad_engines, bad, broke = True, 0.0, [], [], len(failures)
    for e, qs in quantities(spec).items():
        try:
            engine = load_engine(e, model)
        except Exception as exc:      # noqa: BLE001 -- an engine a bicycle breaks is a row
            failures.append(f"{label_of(e)}: {_one_line(exc)}")
            continue
        ok_engine, e = True, label_of(e)
        for q in (q for q in qs if engine.supports(q)):
            try:
                c = compare_term(q, ref, engine, states, tols[q])
            except Exception as exc:  # noqa: BLE001
                failures.append(f"{e} {q}: {_one_line(exc)}")
                continue
            row[f"err.{e}.{q}"] = c.max_error
            row[f"entry.{e}.{q}"] = f"{c.worst_entry} @ state {c.worst_state}"
            worst = max(worst, c.max_error)
            if not c.passed:
                passed = ok_engine = False
                bad.append(f"{e} {q} {c.max_error:.1e} at {c.worst_entry}")
        if not ok_engine:
            bad_engines.append(engine)
    row["max_error"] = worst
    row["terms_passed"] = passed and len(failures) == broke
    if bad:
        row["localization"] = "; ".join(bad) + _explanation(model, states, bad_engines, tols)
    return passed


def _explanation(model, states, engines, tolerances) -> str:
    """`judgments.diagnose`'s best single cause for the disagreement, if it finds one."""
    try:
        from ..judgments.diagnose import localize
        loc = localize(model, states, engines, tolerances=tolerances)
    except Exception as exc:          # noqa: BLE001 -- the localization is a help, not a check
        return f"; localization failed: {_one_line(exc)}"
    if loc.explanation is None:
        return ""
    return f"; best explanation: {loc.explanation.describe()}"


def _runs(spec: SweepSpec, model, crit: dict[str, float], row: dict, failures: list[str]) -> bool:
    """Forward runs below and above each critical speed on the engines of `run_options` (the
    scenario and judgment of `stages.stability`); True when none contradicts the prediction."""
    from .stability import judge_run, run_speeds
    ok, engines = True, run_options(spec)
    for mode, factor, speed in run_speeds(crit):
        scenario = _scenario(model, speed)
        for e, setup in engines.items():
            col = f"run.{mode}.{factor:g}.{e}"
            try:
                engine = setup.build(model)
                traj = engine.simulate(scenario)
                j = judge_run(model, mode, speed, traj)
            except Exception as exc:  # noqa: BLE001
                row[col] = f"failed: {_one_line(exc)}"
                failures.append(f"{e} run {mode} {factor:g}x: {_one_line(exc)}")
                continue
            row[col] = "confirmed" if j["passed"] else "contradicted"
            ok &= j["passed"]
    row["runs_confirmed"] = ok if crit else None
    return ok


def _scenario(model, speed: float):
    """`stages.stability.scenario` for an in-memory model (same initial state and settings)."""
    from reference_model.scenarios import Scenario
    from .stability import GRID, ROLL_RATE
    return Scenario(
        name=f"stability-v{speed:.4f}", kind="forward", model=model.name, grid=GRID,
        description=f"upright at {speed:.4f} m/s, roll rate {ROLL_RATE:g} rad/s, no torques, 5 s",
        q0=(0, 0, 0, 0, 0, 0, 0, 0), dq_ind0=(ROLL_RATE, speed / model.params.R_rear, 0.0),
        torques=(0.0, 0.0, 0.0), constraints="projection", tags=("model-stability",))


def chunk_rows(spec: SweepSpec, indices: tuple[int, ...]) -> list[dict]:
    """The rows of a chunk of bicycles (a Dask task: top-level, picklable arguments)."""
    return [bicycle_row(spec, k) for k in indices]
