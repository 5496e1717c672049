"""The benchmark bicycle (Meijaard et al. 2007) in the engines and in nonlinear runs: the report
section's stages.

    from comparisons.stages.benchmark import benchmark_manoeuvre, benchmark_section

Three parts, all on ``load_model("benchmark")`` (true disc front contact, cv = 0):

(a) **Terms.** Every selected engine that declares a term against the reference at
    deterministic random states (`comparisons.terms`, tolerances from `tolerances.toml`) and M at
    the upright configuration (theta = gamma = 0, beta = -pi/10 solved from the contact).

(b) **The IFToMM "uncontrolled bicycle" manoeuvres** (scenarios ``benchmark-v4``,
    ``benchmark-v4.6``, ``benchmark-v8``: 4, 4.6 and 8 m/s with roll rates 0.05, 0.5 and 0.05
    rad/s, no torques; 5 s with output every 0.01 s as in Exudyn's implementation of the IFToMM
    problem, ``Examples/bicycleIftommBenchmark.py``: tEnd = 5, sensors every 0.01 s, outputs roll
    angle and rate, forward speed, potential, kinetic and mechanical energy, steer angle and
    rate; an older revision of that file ran 20 s). Each on the reference (DOP853, rtol 1e-11,
    projection) and on every variant of each selected fixed-step engine
    (`engines.facts.FixedStep`) at its step:

    * the error against time up to the meaningful horizon (`convergence.reference_horizon`),
      reported; on ``benchmark-v4.6`` (full run only) the engine's convergence order judges it;
    * the constraint residual of every run (tolerance ``constraint_residual``);
    * the IFToMM energy drift 100 (Emax - Emin) / |E0| % over the 0.01 s output samples
      (`comparisons.energy`), judged against IFToMM's acceptance of 1e-3 % (the criterion
      printed by Exudyn's implementation, "must be < 1e-3");
    * the physics, judged against the published critical speeds (weave 4.29238 m/s, capsize
      6.02426 m/s): below the weave speed the weave grows, between the two it decays, above
      the capsize speed the bicycle capsizes slowly. How each is measured:
      - *weave grows / decays*: the peaks of |d theta/dt| from t = 1 s on (the castor mode,
        -12 /s and faster, is gone by then) and the slope of log(peak) against t by least squares:
        the envelope rate, > 0 grows, < 0 decays;
      - *slow capsize*: from t = 3 s on (the weave, decaying at -2.69 /s, is down by e^-8)
        theta keeps one sign and |theta| grows monotonically (theta * d theta/dt > 0 at every
        sample), at a rate sigma (slope of log|theta|) that is positive and slow,
        sigma * 5 s < 1 (less than a factor e over the whole run), and the run does not fall.

(c) **Nonlinear against linear.** The four non-trivial eigenvalues are identified from the
    nonlinear runs by the matrix-pencil method (theta and gamma on a 0.04 s grid, model order
    4: the linearized roll/steer system has exactly four modes) and compared with
    `reference_model.linearize.eigenvalues` at the run's speed: the weave at every speed, the
    capsize at 8 m/s (where it dominates; at 4 and 4.6 m/s it decays under a larger weave and is
    poorly determined). The runs are the IFToMM manoeuvres and the same manoeuvres with roll
    rates of 1e-3 and 1e-2 rad/s. Tolerance: relative deviation <= 2 a^2 + 1e-8 with a the
    largest |theta| or |gamma| of the run (rad). Why: the nonlinear terms left out by the
    linearization are the cubic remainders of the sines and cosines of roll and steer and
    products of three small quantities, so relative to the linear terms they are of order a^2
    with an O(1) coefficient (sin a = a (1 - a^2/6), a pendulum's frequency shifts by a^2/16);
    2 bounds the sum of several (measured: 0.75 to 1.1); 1e-8 is the floor of the fit (reference
    rtol 1e-11, amplified by the pencil's conditioning, its 4th singular value 1e-3 to 1e-2 of
    the 1st). And the deviation must *be* the nonlinearity: between the 1e-3 and 1e-2 rad/s
    runs it must scale as a^order with order in [1.8, 2.2] (a model difference would not vanish
    with the amplitude). The engines' fits on the IFToMM runs are compared with the reference's
    fits on the same runs (the nonlinearity cancels): tolerance 1e-4 relative, the relative error
    of a second-order scheme in a mode's frequency and damping, O((omega h)^2) = (8.5e-3)^2 = 7e-5
    for the weave at 8 m/s and h = 1e-3.

Plus the eigenvalues-against-speed figure (`comparisons.eigenvalues.eigenvalue_figure`).
Every comparison is a dict (quantity, scenario, model, engines, max_error, tolerance, passed,
localized_to, note) as in `engine_report`; outcome checks carry ``measured`` and ``expected``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from engines import UnsupportedModel, load_engine
from reference_model import COORDINATES, Model, load_model
from reference_model.scenarios import SCENARIOS, Scenario
from reference_model.solvers import THETA, Trajectory

from ..judgments.benchmark import (CAPSIZE_FROM, ENVELOPE_FROM, FIT_FLOOR, NONLINEAR_COEFFICIENT,
                                   PUBLISHED_CAPSIZE_SPEED, PUBLISHED_WEAVE_SPEED, ModeFit,
                                   _cx, expected_outcome, judge_outcome, mode_fits, speed_of,
                                   upright_state, with_roll_rate)
from ..judgments.convergence import (DEFAULT_STEPS, ConvergenceStudy, Horizon, convergence_study,
                                     error_vs_time, reference_horizon, reference_run)
from ..judgments.energy import energy_drift
from ..judgments.terms import States, compare_terms, random_states
from ..judgments.tolerances import Tolerances
from ..judgments.rows import Comparison
from .results import Section
from .stage import Assembled, Plan, Stage

MODEL = "benchmark"
MANOEUVRES = ("benchmark-v4", "benchmark-v4.6", "benchmark-v8")
#: --quick runs the engines on this manoeuvre only (the decaying weave between the critical
#: speeds), with their quick variants; the other two are run and judged on the reference
QUICK_ENGINE_MANOEUVRES = ("benchmark-v4.6",)
SMALL_ROLL_RATES = (1e-3, 1e-2)    # rad/s: small-amplitude twins of every manoeuvre
ORDER_BAND = (1.8, 2.2)            # the deviation's order in the amplitude
CONVERGENCE_SCENARIO = "benchmark-v4.6"
CONVERGENCE_HORIZON = 2.0          # s: keeps the four-step study near 1 s of wall time
EIGENVALUE_SPEEDS = (0.0, 10.0, 0.01)   # m/s: start, stop, step of the figure
DIVERGED = 1e-6                    # rad or m: 'first past' threshold


# -- the runs (stages: worker processes call these) --------------------------------------------

@dataclass(frozen=True)
class BenchmarkRun:
    """One engine run of the manoeuvres: its report label, the engine's spec and options."""

    label: str
    spec: str
    options: tuple[tuple[str, object], ...] = ()


def fixed_step_runs(facts, quick: bool = False) -> tuple[BenchmarkRun, ...]:
    """The manoeuvre runs of one fixed-step engine: each variant (``quick``: its quick ones)
    at its step with its declared benchmark options."""
    fx = facts.fixed_step
    variants = fx.quick_variants or fx.variant_names[:1] if quick else fx.variant_names
    return tuple(BenchmarkRun(label, facts.spec, tuple(sorted(opts.items())))
                 for label, opts in fx.runs(facts.name, variants, **dict(fx.benchmark_options)))


@dataclass
class ManoeuvreRuns:
    """One manoeuvre on the reference and on the engines' runs, with its small-amplitude twins'
    mode fits (reference only)."""

    scenario: Scenario
    speed: float
    reference: Trajectory
    horizon: Horizon
    engines: dict[str, Trajectory] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    small_fits: list[ModeFit] = field(default_factory=list)


def benchmark_manoeuvre(name: str, engines: Sequence[BenchmarkRun] = (),
                        twins: bool = True) -> ManoeuvreRuns:
    """The manoeuvre on the reference (DOP853 rtol 1e-11, projection) with its horizon (one twin
    run), on each of ``engines``, and (``twins``) its small-amplitude twins on the reference,
    whose mode fits the nonlinear-against-linear part of the section needs."""
    model = load_model(MODEL)
    sc = SCENARIOS[name]
    t0 = time.perf_counter()
    ref = reference_run(model, sc)
    hor = reference_horizon(model, sc, reference=ref)
    runs = ManoeuvreRuns(sc, speed_of(model, sc), ref, hor,
                         seconds={"reference + twin": time.perf_counter() - t0})
    for run in engines:
        t0 = time.perf_counter()
        runs.engines[run.label] = load_engine(run.spec, model, **dict(run.options)).simulate(sc)
        runs.seconds[run.label] = time.perf_counter() - t0
    for rate in SMALL_ROLL_RATES if twins else ():
        twin = with_roll_rate(sc, rate)
        runs.small_fits += mode_fits(model, twin, reference_run(model, twin))
    return runs


def run_manoeuvres(names: Sequence[str] = MANOEUVRES, engines: Sequence[BenchmarkRun] = (),
                   twins: bool = True) -> list[ManoeuvreRuns]:
    """Every manoeuvre in this process (the pipeline runs them as parallel stages instead)."""
    return [benchmark_manoeuvre(n, engines, twins) for n in names]


def benchmark_terms(tolerances: Tolerances, quick: bool,
                    engines: Sequence[tuple[str, dict]] = ()) -> Section:
    """Each of ``engines`` ((spec, options) pairs) against the reference at random states and
    M upright. A stage."""
    from .runs import label_of
    sec = Section("benchmark terms")
    model = load_model(MODEL)
    n = 50 if quick else 200
    ref = load_engine("reference", model)
    built, unsupported = {}, []
    for spec, opts in engines:
        try:
            built[label_of(spec)] = load_engine(spec, model, **dict(opts))
        except UnsupportedModel as exc:   # a declared limitation: not run, and why
            unsupported.append(f"{label_of(spec)}: not run on this model: {exc}")
    q_up = upright_state(model)
    upright = States(q_up[None, :], np.zeros((1, 8)), np.zeros((1, 8)), np.zeros((1, 3)))
    sec.heading("Terms")
    sec.text(f"{n} deterministic random states (large lean, steer near ±π/2, rates up to "
             f"20 rad/s) and M at the upright "
             f"configuration (beta = {q_up[5]:+.15f} rad, -π/10 = {-np.pi / 10:+.15f}).")
    for line in unsupported:
        sec.text(line)
    rows = []
    for label, eng in built.items():
        for states, where, quantities in ((random_states(n, seed=7), f"random-states-{n}", None),
                                          (upright, "upright", ("mass_matrix",))):
            for r in compare_terms(ref, eng, states, tolerances, quantities):
                rows.append((label, where, r.quantity, f"{r.max_error:.1e}", f"{r.tolerance:.0e}",
                             "pass" if r.passed else "FAIL", r.worst_entry))
                sec.comparisons.append(Comparison.of({
                    "quantity": r.quantity, "scenario": where, "model": model.name,
                    "engines": ["reference", label], "max_error": r.max_error,
                    "tolerance": r.tolerance, "passed": r.passed, "localized_to": r.worst_entry}))
    sec.table(("engine", "states", "quantity", "max error", "tolerance", "verdict", "worst entry"),
              rows)
    return sec


def benchmark_convergence(run: BenchmarkRun, step_option: str = "step",
                          steps: Sequence[float] = DEFAULT_STEPS) -> ConvergenceStudy:
    """One engine run's convergence on ``CONVERGENCE_SCENARIO`` at four steps (its
    ``step_option``) against the reference. A stage."""
    model = load_model(MODEL)
    opts = {k: v for k, v in run.options if k != step_option}
    return convergence_study(model, lambda h: load_engine(run.spec, model, **opts,
                                                          **{step_option: h}),
                             SCENARIOS[CONVERGENCE_SCENARIO], steps=steps,
                             horizon=CONVERGENCE_HORIZON)


# -- the section (main process: cheap, from the stages' results) ------------------------------

def _first_past(err: dict) -> str:
    over = np.flatnonzero(err["max"] > DIVERGED)
    if not over.size:
        return f"none (all below {DIVERGED:g})"
    i = int(over[0])
    return f"{max(COORDINATES, key=lambda c: err[c][i])} at {err['t'][i]:.2f} s"


def _manoeuvre_part(tols: Tolerances, sec: Section, model: Model, runs: list[ManoeuvreRuns],
                    settings: dict[str, str]) -> None:
    c_tol = tols["constraint_residual"].tolerance
    drift_tol = tols["iftomm_energy_drift"].tolerance
    labels = list(dict.fromkeys(lab for mr in runs for lab in mr.engines))
    sec.heading("IFToMM uncontrolled bicycle: reference against "
                + (", ".join(labels) if labels else "no engine (none selected is fixed-step)"))
    sec.text(
        "5 s, output every 0.01 s (IFToMM). Reference: DOP853 rtol 1e-11, projection. "
        + "; ".join(f"{lab}: {how}" for lab, how in settings.items())
        + (". " if settings else "") + "Errors in all eight "
        "coordinates up to the horizon where two reference runs 1e-9 rad/s apart in "
        "theta_dot(0) separate by 1e-6; reported, not judged (the convergence check below "
        "judges them). Energy drift 100 (Emax - Emin)/|E0| over the 0.01 s output, judged "
        f"against IFToMM's acceptance {drift_tol:g} % (stricter than the generic "
        "`tolerances.toml` [energy_drift], which bounds any second-order run at h = 1e-3); "
        f"constraint residual against [constraint_residual] {c_tol:g}.")
    rows, panels, error_panels = [], [], []
    for mr in runs:
        name, ref = mr.scenario.name, mr.reference
        engines = {"reference": ref, **mr.engines}
        panel = {"title": f"{name}: v = {mr.speed:g} m/s, roll rate {mr.scenario.dq_ind0[0]:g} "
                          f"rad/s ({expected_outcome(mr.speed)})",
                 "lines": {lab: (tr.t, tr.q[:, THETA]) for lab, tr in engines.items()}}
        panels.append(panel)
        curves = {}
        for label, tr in engines.items():
            drift = energy_drift(model, tr)
            Cmax = float(np.abs(tr.C).max())
            if label == "reference":
                worst, first = "- (the reference)", "-"
            else:
                err = error_vs_time(ref, tr, coords=COORDINATES, horizon=mr.horizon.t)
                worst, first = f"{err['max'].max():.2e}", _first_past(err)
                sec.comparisons.append(Comparison.of({
                    "quantity": "trajectory (benchmark)", "scenario": name, "model": model.name,
                    "engines": ["reference", label], "max_error": float(err["max"].max()),
                    "tolerance": None, "passed": None, "horizon": mr.horizon.t,
                    "horizon_reason": mr.horizon.reason, "localized_to": first,
                    "note": "reported, not judged: integrator error at h = 1e-3 (see the "
                            "convergence check)"}))
                curves[label] = {"t": err["t"], "theta": err["theta"], "max": err["max"]}
            rows.append((name, f"{mr.speed:g}", label, tr.status, f"{mr.horizon.t:.2f}", worst,
                         first, f"{Cmax:.1e}", f"{drift['drift_percent']:.2e}"))
            sec.comparisons.append(Comparison.of({
                "quantity": "constraint_residual", "scenario": name, "model": model.name,
                "engines": [label], "max_error": Cmax, "tolerance": c_tol,
                "passed": bool(Cmax <= c_tol), "localized_to": "max |C| over the run"}))
            sec.comparisons.append(Comparison.of({
                "quantity": "energy drift percent (IFToMM)", "scenario": name,
                "model": model.name, "engines": [label], "max_error": drift["drift_percent"],
                "tolerance": drift_tol, "passed": bool(drift["drift_percent"] <= drift_tol),
                "localized_to": f"Emax at {drift['t_Emax']:.2f} s, Emin at {drift['t_Emin']:.2f} s",
                "note": (f"100 (Emax - Emin)/|E0| over the 0.01 s output, E0 = {drift['E0']:.3f} J "
                         f"(ground as zero of V), E_end - E0 = {drift['E_end_minus_E0']:+.2e} J")}))
        if len(engines) == 1:
            continue
        error_panels.append({"title": f"{name}: {', '.join(mr.engines)} against the "
                                      f"reference up to the horizon ({mr.horizon.t:.2f} s)",
                             "curves": curves})
    sec.table(("scenario", "v [m/s]", "engine", "status", "horizon [s]",
               "max error to the horizon [rad, m]", f"first past {DIVERGED:g}", "max abs C [m, m/s]",
               "drift [% of E0]"), rows)
    sec.figure("benchmark_roll.png", "lean_panels", panels=panels, ylabel="theta (lean) [rad]")
    if error_panels:   # none when no manoeuvre ran on an engine
        sec.figure("benchmark_error.png", "error_panels", panels=error_panels, threshold=DIVERGED,
                   engine_label=", ".join(labels))
    alone = [mr.scenario.name for mr in runs if not mr.engines]
    if alone and labels:
        sec.text(f"Run on the reference only (`--quick`: the engines run "
                 f"{', '.join(mr.scenario.name for mr in runs if mr.engines) or 'none of them'}): "
                 f"{', '.join(alone)}.")
    sec.text("Initial states (projected once, used by every engine): " + "; ".join(
        f"{mr.scenario.name}: {mr.reference.settings['initial_correction']}" for mr in runs) + ".")


def _outcome_part(sec: Section, model: Model, runs: list[ManoeuvreRuns]) -> None:
    from reference_model.linearize import eigenvalues
    sec.heading("Physics: weave and capsize")
    sec.text(
        f"Expected from the published critical speeds (weave {PUBLISHED_WEAVE_SPEED} m/s, capsize "
        f"{PUBLISHED_CAPSIZE_SPEED} m/s). Weave: slope of log of the peaks of |dtheta/dt| from "
        f"{ENVELOPE_FROM:g} s on (> 0 grows, < 0 decays). Capsize: from {CAPSIZE_FROM:g} s on "
        "theta keeps one sign and |theta| grows monotonically, at a rate sigma with sigma * 5 s < 1 "
        "(slow), no fall. The linear weave real part / capsize eigenvalue is given beside.")
    rows = []
    for mr in runs:
        lin = eigenvalues(model, mr.speed)
        for label, tr in {"reference": mr.reference,
                          **mr.engines}.items():
            o = judge_outcome(mr.scenario.name, mr.speed, tr, label)
            linear = lin[2].real if o.expected == "slow capsize" else lin[0].real
            rows.append((o.scenario, label, o.expected, f"{o.measured:+.4f}", f"{linear:+.4f}",
                         "pass" if o.passed else "FAIL", o.evidence))
            sec.comparisons.append(Comparison.of({
                "quantity": f"outcome: {o.expected}", "scenario": o.scenario, "model": model.name,
                "engines": [label], "max_error": None, "tolerance": None, "passed": o.passed,
                "measured": o.measured, "expected": o.expected, "linear": float(linear),
                "localized_to": f"measured rate {o.measured:+.4f} /s", "note": o.evidence}))
    sec.table(("scenario", "engine", "expected", "measured rate [1/s]", "linear [1/s]", "verdict",
               "how"), rows)


def _nonlinear_part(tols: Tolerances, sec: Section, model: Model, runs: list[ManoeuvreRuns]) -> None:
    sec.heading("Nonlinear against linear")
    sec.text(
        "Eigenvalues identified from the nonlinear runs (matrix pencil on theta and gamma, 0.04 s "
        "grid, order 4) against the linearization at the run's speed. Tolerance on the relative "
        f"deviation: {NONLINEAR_COEFFICIENT:g} a² + {FIT_FLOOR:.0e}, a = max |theta|, |gamma| of "
        "the run (the terms the linearization drops are O(a²) relative; the floor is the fit's "
        "accuracy). Between the two small amplitudes the deviation must scale as a^order with "
        f"order in [{ORDER_BAND[0]}, {ORDER_BAND[1]}]: it is the nonlinearity, not a model "
        "difference.")
    fits: list[ModeFit] = []
    by_speed: dict[str, list[ModeFit]] = {}
    engine_rows = []
    for mr in runs:
        group = list(mr.small_fits) + mode_fits(model, mr.scenario, mr.reference)
        by_speed[mr.scenario.name] = group
        fits += group
        ref_weave = next(f for f in group if f.mode == "weave" and f.scenario == mr.scenario.name)
        for label, tr in mr.engines.items():
            f = mode_fits(model, mr.scenario, tr, engine=label, modes=("weave",))[0]
            engine_rows.append((f, ref_weave, abs(f.fitted - ref_weave.fitted) / abs(ref_weave.fitted)))
    rows = []
    for f in fits:
        ok = f.deviation <= f.tolerance
        sec.comparisons.append(Comparison.of({
            "quantity": f"{f.mode} eigenvalue, nonlinear fit vs linear", "scenario": f.scenario,
            "model": model.name, "engines": ["reference (nonlinear)", "linearize"],
            "max_error": f.deviation, "tolerance": f.tolerance, "passed": bool(ok),
            "localized_to": f"a = {f.amplitude:.2e} rad",
            "note": f"fitted {f.fitted:.10f} /s, linear {f.linear:.10f} /s"}))
        rows.append((f.scenario, f.engine, f.mode, f"{f.amplitude:.2e}", _cx(f.fitted),
                     _cx(f.linear), f"{f.deviation:.2e}", f"{f.tolerance:.1e}",
                     "pass" if ok else "FAIL"))
    sec.table(("scenario", "engine", "mode", "a [rad]", "fitted [1/s]", "linear [1/s]",
               "rel. deviation", "tolerance", "verdict"), rows)
    fit_tol = tols["benchmark_weave_fit"].tolerance
    if not engine_rows:
        return _order_part(sec, model, by_speed)
    sec.text("The engines' weave fits on the IFToMM runs against the reference's fit on the same run "
             f"(the nonlinearity cancels); tolerance {fit_tol:.0e} relative, the O((omega h)^2) "
             "error of the integrator at h = 1e-3:")
    rows = []
    for f, r, dev in engine_rows:
        ok = dev <= fit_tol
        rows.append((f.scenario, f.engine, _cx(f.fitted), _cx(r.fitted), f"{dev:.1e}",
                     "pass" if ok else "FAIL"))
        sec.comparisons.append(Comparison.of({
            "quantity": "weave eigenvalue fit, engine vs reference (same run)",
            "scenario": f.scenario, "model": model.name,
            "engines": ["reference", f.engine], "max_error": dev,
            "tolerance": fit_tol, "passed": bool(ok),
            "localized_to": f"fitted {_cx(f.fitted)} vs {_cx(r.fitted)} /s",
            "note": "same amplitude, so the nonlinearity cancels; (omega h)^2 integrator error"}))
    sec.table(("scenario", "engine", "fitted [1/s]", "reference fit [1/s]", "rel. difference",
               "verdict"), rows)
    _order_part(sec, model, by_speed)


def _order_part(sec: Section, model: Model, by_speed: dict) -> None:
    """The deviation's order in the amplitude, between the two small roll rates."""
    rows, curves = [], []
    for name, group in by_speed.items():
        for mode in ("weave", "capsize"):
            g = [f for f in group if f.mode == mode]
            if not g:
                continue
            small = [f for f in g if f.roll_rate in SMALL_ROLL_RATES]
            a = np.array([f.amplitude for f in small])
            d = np.array([f.deviation for f in small])
            order = float(np.log(d[1] / d[0]) / np.log(a[1] / a[0]))
            ok = ORDER_BAND[0] <= order <= ORDER_BAND[1]
            rows.append((f"{g[0].speed:g} m/s", mode, f"{d[0]:.2e} / {d[1]:.2e}", f"{order:.3f}",
                         "pass" if ok else "FAIL"))
            sec.comparisons.append(Comparison.of({
                "quantity": f"{mode} eigenvalue deviation: order in the amplitude",
                "scenario": name, "model": model.name, "engines": ["reference (nonlinear)", "linearize"],
                "max_error": abs(order - 2.0), "tolerance": ORDER_BAND[1] - 2.0,
                "passed": bool(ok), "order": order, "localized_to": f"order {order:.3f}",
                "note": f"a = {a[0]:.2e}, {a[1]:.2e} rad; deviation {d[0]:.2e}, {d[1]:.2e}"}))
            curves.append({"label": f"{g[0].speed:g} m/s {mode}: order {order:.2f}",
                           "a": [f.amplitude for f in g], "deviation": [f.deviation for f in g]})
    sec.table(("speed", "mode", "deviation at roll rate 1e-3 / 1e-2", "order in a", "verdict"), rows)
    sec.figure("benchmark_nonlinear.png", "nonlinear_fits", curves=curves,
               coefficient=NONLINEAR_COEFFICIENT, floor=FIT_FLOOR)


def _convergence_part(sec: Section, model: Model, label: str, study: ConvergenceStudy) -> None:
    ok = study.verdict == "converges"
    sec.heading(f"{label} convergence on the benchmark")
    sec.text(study.describe())
    sec.comparisons.append(Comparison.of({
        "quantity": "convergence order", "scenario": CONVERGENCE_SCENARIO, "model": model.name,
        "engines": ["reference", label], "max_error": study.difference, "tolerance": None,
        "order": study.order, "steps": list(study.steps), "errors": list(study.errors),
        "verdict": study.verdict, "expected": "converges", "passed": ok,
        "localized_to": f"order {study.order:.2f}, worst coordinate {study.worst[-1]}",
        "reason": study.verdict_reason}))


def _eigenvalue_part(tols: Tolerances, sec: Section, model: Model) -> None:
    """Linear eigenvalues and critical speeds against Meijaard et al. (2007) Table 2, and the
    eigenvalues-against-speed figure."""
    from reference_model.linearize import capsize_speed, eigenvalues, weave_speed
    from ..judgments.eigenvalues import eigenvalue_curves
    from ..judgments.published import (MEIJAARD_CAPSIZE_SPEED, MEIJAARD_TABLE2,
                                       MEIJAARD_WEAVE_SPEED, table2_eigenvalues)
    err, worst = 0.0, "-"
    for v in MEIJAARD_TABLE2:
        e = float(np.abs(eigenvalues(model, float(v)) - table2_eigenvalues(v)).max())
        if e > err:
            err, worst = e, f"v = {v} m/s"
    tol = tols["benchmark_eigenvalues"]
    sec.comparisons.append(Comparison.of({
        "quantity": "eigenvalues vs Meijaard 2007 Table 2", "scenario": "benchmark upright, v = 0..10",
        "model": MODEL, "engines": ["reference", "published"], "max_error": err,
        "tolerance": tol.tolerance, "passed": bool(err <= tol.tolerance), "localized_to": worst,
        "note": "exact linearization (complex step), 4 eigenvalues at 11 speeds"}))
    speeds = {"weave speed": (weave_speed(model), MEIJAARD_WEAVE_SPEED),
              "capsize speed": (capsize_speed(model), MEIJAARD_CAPSIZE_SPEED)}
    tol_s = tols["benchmark_speeds"]
    for name, (ours, theirs) in speeds.items():
        e = abs(ours - theirs)
        sec.comparisons.append(Comparison.of({
            "quantity": f"{name} vs Meijaard 2007", "scenario": "benchmark upright", "model": MODEL,
            "engines": ["reference", "published"], "max_error": e, "tolerance": tol_s.tolerance,
            "passed": bool(e <= tol_s.tolerance), "localized_to": f"{ours:.14f} m/s"}))
    sec.heading("Linear stability against the published Table 2")
    sec.text("Linearized about upright straight running (roll and steer; exact derivatives), "
             "against the published Table 2:")
    sec.table(("quantity", "ours", "published", "error", "tolerance"),
              [("eigenvalues, v = 0..10 m/s", "-", "Table 2", f"{err:.1e} (worst at {worst})",
                f"{tol.tolerance:.0e}")]
              + [(f"{name} [m/s]", f"{ours:.14f}", f"{theirs:.14f}", f"{abs(ours - theirs):.1e}",
                  f"{tol_s.tolerance:.0e}") for name, (ours, theirs) in speeds.items()])
    start, stop, step = EIGENVALUE_SPEEDS
    grid = start + step * np.arange(int(round((stop - start) / step)) + 1)
    sec.figure("benchmark_eigenvalues.png", "eigenvalues", **eigenvalue_curves(model, grid))


def benchmark_section(tolerances: Tolerances, quick: bool, runs: list[ManoeuvreRuns],
                      terms: Section | None, convergence: dict[str, ConvergenceStudy],
                      settings: dict[str, str] | None = None) -> Section:
    """The benchmark bicycle's section of the report (module docstring) from its stages'
    results: terms, the IFToMM manoeuvres on the reference and the fixed-step engines, physics,
    nonlinear against linear, each engine's convergence (full runs only), Table 2 and the
    eigenvalue figure."""
    sec = Section("Benchmark bicycle (Meijaard et al. 2007): engines, IFToMM uncontrolled "
                  "bicycle, nonlinear against linear")
    model = load_model(MODEL)
    if terms is not None:
        sec.blocks += terms.blocks
        sec.comparisons += terms.comparisons
    _manoeuvre_part(tolerances, sec, model, runs, settings or {})
    _outcome_part(sec, model, runs)
    _nonlinear_part(tolerances, sec, model, runs)
    for label, study in convergence.items():
        _convergence_part(sec, model, label, study)
    _eigenvalue_part(tolerances, sec, model)
    return sec


def _settings_line(facts) -> str:
    fx = facts.fixed_step
    extra = ", ".join(f"{k} {v}" for k, v in fx.benchmark_options)
    return (f"{fx.option} = {fx.step:g} s" + (f", {fx.describe}" if fx.describe else "")
            + (f", {extra}" if extra else ""))


class BenchmarkStage(Stage):
    """The benchmark bicycle's section (module docstring): the run without ``--model``."""

    name, section = "benchmark", "benchmark"

    def _runs(self, plan: Plan) -> list:
        return [f for f in plan.engines(lambda f: f.fixed_step is not None
                                        and "simulate" in f.capabilities)]

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        if plan.opts.models:
            return []
        out = []
        with_terms = tuple((f.spec, plan.options_for(f.spec)) for f in plan.engines(
            lambda f: f.has_terms))
        if with_terms:
            out.append(Task("terms", benchmark_terms, (plan.tolerances, plan.quick, with_terms),
                            sum(plan.facts[s].costs.terms for s, _ in with_terms),
                            "benchmark terms"))
        fixed = self._runs(plan)
        for n in MANOEUVRES:
            runs = tuple(r for f in fixed for r in fixed_step_runs(f, plan.quick)) \
                if not plan.quick or n in QUICK_ENGINE_MANOEUVRES else ()
            out.append(Task(("manoeuvre", n), benchmark_manoeuvre, (n, runs),
                            0.5 + 1.5 * len(runs), f"benchmark {n}"))
        if not plan.quick:
            for f in fixed:
                run = fixed_step_runs(f)[0]
                out.append(Task(("convergence", run.label), benchmark_convergence,
                                (run, f.fixed_step.option,
                                 tuple(h * f.fixed_step.step / 1e-3 for h in DEFAULT_STEPS)),
                                6.0, f"benchmark: {f.label} convergence", f.spec))
        return out

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        if not results:   # not run (a --model run)
            return out
        man = [self.value(results, ("manoeuvre", n), f"benchmark {n}") for n in MANOEUVRES]
        terms, failed_terms = (self.value(results, "terms", "benchmark terms")
                               if "terms" in results else (None, None))
        conv = {}
        for key in results:
            if isinstance(key, tuple) and key[0] == "convergence":
                v, failed = self.value(results, key, f"benchmark convergence of {key[1]}")
                if failed is None:
                    conv[key[1]] = v
                else:
                    out.sections.append(failed)
        broken = [f for _, f in man if f is not None] + ([failed_terms] if failed_terms else [])
        if broken:
            out.sections += broken
            return out
        settings = {r.label: _settings_line(f) for f in self._runs(plan)
                    for r in fixed_step_runs(f, plan.quick)}
        out.sections.append(benchmark_section(plan.tolerances, plan.quick, [v for v, _ in man],
                                              terms, conv, settings))
        return out
