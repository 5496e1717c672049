"""A bicycle's own stability picture (``bicycle-xval run --model``): its linearized roll/steer
eigenvalues against speed with its weave and capsize speeds, and forward runs just below and
above each critical speed on every engine that can simulate, showing the predicted growth or
decay.

    curves = stability_curves(spec)                    # a stage: the eigenvalue figure's data
    traj = stability_run(spec, setup, 4.6)             # a stage: one forward run
    section = stability_section(model, critical, curves, runs, errors, labels)

Which models: front contact "disc" (the benchmark's knife-edge wheel, for which the
linearization about upright straight running is Meijaard et al.'s). A model with drag (cv > 0)
has no steady upright motion: it is linearized, and run, with cv = 0, and the section says so.

The runs: upright, straight steer, beta from [rD]_z = 0, forward speed v = R_rear psi_dot(0) at
``FACTORS`` (0.9 and 1.1) times each critical speed found in ``SPEED_RANGE``, an initial roll
rate of ``ROLL_RATE`` (the IFToMM kick), no torques, projection, 5 s on a 0.01 s grid (the
IFToMM manoeuvres' settings). At those speeds the linearization predicts the sign of one
mode's real part, and each run is judged on it:

* near the **weave** speed: the weave's real part (grows below, decays above), measured as the
  envelope rate of the peaks of |d theta/dt| from 1 s on (`judgments.benchmark.
  roll_rate_envelope`, as the IFToMM outcome check);
* near the **capsize** speed: the capsize eigenvalue (real; decays below, grows above),
  identified from the run by the matrix pencil (`judgments.benchmark.identify_eigenvalues`,
  four modes on theta and gamma) and taken as the real exponent closest to the linear one.

Passed when the run completed and the measured sign is the predicted sign. Both numbers are
reported beside the linear value (the nonlinear run at this amplitude deviates from the linear
value by O(a^2) relative; only the sign is judged: 10 % from the critical speed the predicted
real parts are 0.06 to 0.7 /s in magnitude for the benchmark and BicycleParameters-like sets,
far from zero against that deviation).

An engine whose forward runs declare a model difference (a soft contact: `soft_differing`)
runs the same scenarios in a full run (not ``--quick``) and is measured the same way, each row
*reported* (passed None, the difference declared), never a failure: a soft contact's runs are
not a test of the rigid rolling model's linearization. A bicycle the engine cannot represent
is `not run on this model`, with the reason.
"""

from __future__ import annotations

import numpy as np

from reference_model import Model, load_model
from reference_model.scenarios import Scenario

from ..judgments.benchmark import _cx, _pick, identify_eigenvalues, roll_rate_envelope
from ..judgments.rows import Comparison
from .results import Section
from .stage import Assembled, Plan, Stage

SPEED_RANGE = (0.0, 10.0)      # m/s: where critical speeds are looked for
SPEED_STEP = 0.01              # m/s: the figure's grid
FACTORS = (0.9, 1.1)           # runs below and above each critical speed
ROLL_RATE = 0.05               # rad/s: the IFToMM kick
GRID = (0.0, 0.01, 501)        # 0:0.01:5 s


def simulating(setup) -> bool:
    """Whether a setup's runs go into the stability picture: it runs forward scenarios and
    declares no model difference of its runs (a soft contact's runs are that difference's
    study, not a prediction's test)."""
    from engines.facts import engine_facts
    return "forward" in setup.kinds and engine_facts(setup.engine).run_difference is None


def soft_differing(setup) -> str | None:
    """The model difference a setup's forward runs declare (a soft contact), when they are
    measured in the stability picture as reported rows; else None."""
    from engines.facts import engine_facts
    facts = engine_facts(setup.engine)
    return (facts.run_difference if "forward" in setup.kinds and facts.soft_contact is not None
            else None)


def stability_model(spec: str) -> tuple[Model, str]:
    """The model as linearized and run (cv = 0), and a note when the drag was removed."""
    m = load_model(spec)
    if m.params.cv != 0.0:
        return (m.with_params(m.params.replace(cv=0.0)),
                f"{m.name} has drag (cv = {m.params.cv:g} kg/m), so no steady upright motion: "
                "linearized and run with cv = 0")
    return m, ""


def applies(contact: str) -> str | None:
    """Why the stability picture is not made for a model, or None."""
    if contact != "disc":
        return ("its front contact is the thesis's (rim point along the fork's -z axis), not the "
                "benchmark's knife-edge disc that the linearization and the critical speeds are "
                "defined for; load it with contact 'disc' (e.g. the named model thesis-disc)")
    return None


def critical(spec: str) -> dict[str, float]:
    """The weave and capsize speeds of the model in ``SPEED_RANGE`` (m/s), by name."""
    from ..judgments.eigenvalues import critical_speeds
    model, _ = stability_model(spec)
    weave, capsize = critical_speeds(model, np.array(SPEED_RANGE))
    return {k: v for k, v in (("weave", weave), ("capsize", capsize)) if v is not None}


def run_speeds(crit: dict[str, float]) -> list[tuple[str, float, float]]:
    """(mode, factor, speed) of every run."""
    return [(mode, f, f * v) for mode, v in crit.items() for f in FACTORS]


def scenario(spec: str, speed: float) -> Scenario:
    """Upright at ``speed`` with the roll-rate kick (module docstring)."""
    model, _ = stability_model(spec)
    return Scenario(
        name=f"stability-v{speed:.4f}", kind="forward", model=spec, grid=GRID,
        description=f"upright at {speed:.4f} m/s, roll rate {ROLL_RATE:g} rad/s, no torques, 5 s",
        q0=(0, 0, 0, 0, 0, 0, 0, 0), dq_ind0=(ROLL_RATE, speed / model.params.R_rear, 0.0),
        torques=(0.0, 0.0, 0.0), constraints="projection", tags=("model-stability",))


def stability_curves(spec: str) -> dict:
    """The eigenvalues-against-speed figure's data (a stage)."""
    from ..judgments.eigenvalues import eigenvalue_curves
    model, _ = stability_model(spec)
    lo, hi = SPEED_RANGE
    grid = lo + SPEED_STEP * np.arange(int(round((hi - lo) / SPEED_STEP)) + 1)
    return eigenvalue_curves(model, grid)


def stability_run(spec: str, setup, speed: float):
    """One forward run at ``speed`` on the engine setup ``setup`` (a `runs.EngineSetup`; a
    stage): the Trajectory."""
    model, _ = stability_model(spec)
    return setup.build(model).simulate(scenario(spec, speed))


def differing_run(spec: str, setup, speed: float):
    """`stability_run` of a setup declaring a model difference (`soft_differing`; a stage): the
    Trajectory, or the reason (str) when the engine cannot represent the bicycle."""
    from engines import UnsupportedModel
    try:
        return stability_run(spec, setup, speed)
    except UnsupportedModel as exc:   # a declared limitation: said, not failed
        return f"not run on this model: {exc}"


def judge_run(model: Model, mode: str, speed: float, traj) -> dict:
    """Measured and predicted real part of ``mode`` at ``speed`` (module docstring)."""
    from reference_model.linearize import eigenvalues
    lin = eigenvalues(model, speed)
    if mode == "weave":
        predicted = complex(lin[0])
        env = roll_rate_envelope(traj)
        measured = env.rate
        how = (f"{env.peaks.size} peaks of |dtheta/dt| from {env.t_from:g} s, envelope rate "
               f"{measured:+.4f} /s")
    else:
        real = lin[np.abs(lin.imag) <= 1e-12 * np.abs(lin)]
        pool = real if real.size else lin
        predicted = complex(pool[np.argmin(np.abs(pool.real))])   # the slow real mode
        fit = _pick(identify_eigenvalues(traj), "capsize", predicted)
        measured = fit.real
        how = f"capsize eigenvalue from the run (matrix pencil) {_cx(fit)} /s"
    expected = "grows" if predicted.real > 0 else "decays"
    ok = bool(traj.status == "completed" and np.isfinite(measured)
              and (measured > 0) == (predicted.real > 0))
    return {"predicted": predicted.real, "measured": float(measured), "expected": expected,
            "passed": ok, "how": f"{how}; {traj.status} at {traj.t_end:.2f} s"}


def stability_section(m, crit: dict[str, float], curves: dict | None,
                      runs: dict[tuple[str, float, str], object], errors: dict,
                      labels: tuple[str, ...] = (), differences: dict | None = None) -> Section:
    """The section of one model (``m`` a `cases.ModelSpec`): the eigenvalue figure, the critical
    speeds, the runs' table and figure; every run judged (module docstring). ``labels``: the
    setups' order in the tables (default: as the runs come); ``differences``: label -> the
    model difference its runs declare (their rows reported, not judged; a str in ``runs``: the
    reason it was not run)."""
    differences = differences or {}
    labels = tuple(labels) or tuple(dict.fromkeys(k[2] for k in (*runs, *errors)))
    sec = Section(f"Stability of {m.name} ({m.source})")
    model, note = stability_model(m.spec)
    sec.text(
        "Linearized roll/steer dynamics about upright straight running (exact derivatives), "
        f"eigenvalues against speed {SPEED_RANGE[0]:g}-{SPEED_RANGE[1]:g} m/s"
        + (f". {note}." if note else ", contact disc, cv = 0.")
        + " Critical speeds: " + (", ".join(f"{k} {v:.6f} m/s" for k, v in crit.items())
                                   or f"none in {SPEED_RANGE[0]:g}-{SPEED_RANGE[1]:g} m/s") + ".")
    if curves is not None:
        sec.figure(f"eigenvalues_{_slug(m.name)}.png", "eigenvalues", **curves)
    if not crit:
        sec.text("No critical speed in the range: no runs.")
        return sec
    sec.text(
        f"Forward runs at {' and '.join(f'{f:g}' for f in FACTORS)} x each critical speed: "
        f"upright, roll rate {ROLL_RATE:g} rad/s, no torques, projection, 5 s. Judged: the sign "
        "of the mode's real part measured on the run equals the linear prediction (weave: "
        "envelope of |dtheta/dt| from 1 s; capsize: the real exponent identified by the matrix "
        "pencil)."
        + (f" {', '.join(lab for lab in labels if lab in differences)}: a declared model difference (soft contact), "
           "measured the same way and reported, not judged." if differences else ""))
    rows, panels = [], []
    for mode, factor, speed in run_speeds(crit):
        lines = {}
        # in the engines' fixed order, not the order the pool finished them (identical inputs,
        # identical report)
        for label in [lab for lab in labels if (mode, speed, lab) in runs]:
            traj = runs[(mode, speed, label)]
            differs = differences.get(label)
            where = f"{m.name} at {speed:.4f} m/s ({factor:g} x {mode} speed)"
            if isinstance(traj, str):      # the engine cannot represent the bicycle
                rows.append((mode, f"{factor:g} x = {speed:.4f}", label, "-", "-", "-",
                             "not run", traj))
                sec.comparisons.append(Comparison.of({
                    "quantity": f"stability: {mode} run", "scenario": where, "model": m.name,
                    "engines": [label], "max_error": None, "tolerance": None, "passed": None,
                    "localized_to": "-", "note": traj}))
                continue
            lines[label] = (traj.t, traj.q[:, 3])
            j = judge_run(model, mode, speed, traj)
            word = ("pass" if j["passed"] else "FAIL") if differs is None else \
                f"reported: {'agrees' if j['passed'] else 'differs'}"
            rows.append((mode, f"{factor:g} x = {speed:.4f}", label, f"{j['predicted']:+.4f}",
                         f"{j['measured']:+.4f}", f"{mode} {j['expected']}", word, j["how"]))
            extra = {} if differs is None else {
                "declared_difference": differs, "agrees": j["passed"],
                "why": "declared model difference"}
            sec.comparisons.append(Comparison.of({
                "quantity": f"stability: {mode} {j['expected']} (sign of its real part)",
                "scenario": where, "model": m.name, "engines": [label], "max_error": None,
                "tolerance": None, "passed": j["passed"] if differs is None else None,
                "measured": j["measured"], "predicted": j["expected"],
                "linear": j["predicted"], "localized_to": f"measured {j['measured']:+.4f} /s",
                "note": j["how"] if differs is None else
                f"{j['how']}; reported, not judged: a declared model difference ({differs})",
                **extra}))
        for label in [lab for lab in labels if (mode, speed, lab) in errors]:
            err = errors[(mode, speed, label)]
            rows.append((mode, f"{factor:g} x = {speed:.4f}", label, "-", "-", "-", "FAIL", err))
            sec.comparisons.append(Comparison.of({
                "quantity": f"stability: {mode} run", "scenario": f"{m.name} at {speed:.4f} m/s",
                "model": m.name, "engines": [label], "max_error": None, "tolerance": None,
                "passed": False, "localized_to": err}))
        panels.append({"title": f"{m.name}: {factor:g} x {mode} speed = {speed:.4f} m/s",
                       "lines": lines})
    sec.table(("mode", "speed [m/s]", "engine", "linear real part [1/s]", "measured [1/s]",
               "predicted", "verdict", "how"), rows)
    sec.figure(f"stability_runs_{_slug(m.name)}.png", "lean_panels", panels=panels,
               ylabel="theta (lean) [rad]")
    return sec


def _slug(name: str) -> str:
    from .cases import slug
    return slug(name)


class StabilityStage(Stage):
    """Each disc-contact ``--model``'s stability picture: its eigenvalues against speed, and
    runs below and above each critical speed on every setup that simulates (`simulating`)."""

    name, section = "stability", None

    def tasks(self, plan: Plan) -> list:
        from .pool import Task
        out = []
        for m in plan.opts.models:
            if m.spec not in plan.critical:
                continue
            out.append(Task(("curves", m.spec), stability_curves, (m.spec,), 0.5,
                            f"{m.name}: eigenvalues against speed"))
            for mode, factor, speed in run_speeds(plan.critical[m.spec]):
                for s in plan.setups:
                    run = (stability_run if simulating(s) else
                           differing_run if soft_differing(s) and not plan.quick else None)
                    if run is not None:
                        cost = 5.0 * plan.facts[s.engine].costs.run_per_second
                        out.append(Task(("run", m.spec, mode, speed, s.label), run,
                                        (m.spec, s, speed), cost,
                                        f"{m.name}: {factor:g} x {mode} speed on {s.label}",
                                        None if s.engine == "reference" else s.engine))
        return out

    def assemble(self, plan: Plan, results: dict) -> Assembled:
        out = Assembled()
        differences = {s.label: d for s in plan.setups
                       if not plan.quick and (d := soft_differing(s)) is not None}
        labels = tuple(s.label for s in plan.setups if simulating(s) or s.label in differences)
        for m in plan.opts.models:
            why = applies(m.contact)
            if why is not None:
                sec = Section(f"Stability of {m.name} ({m.source})")
                sec.text(f"Not computed: {why}.")
                out.sections.append(sec)
                continue
            curves = results[("curves", m.spec)]
            runs, errors = {}, {}
            for key, r in results.items():
                if key[0] == "run" and key[1] == m.spec:
                    if r.error is None:
                        runs[key[2:]] = r.value
                    else:
                        errors[key[2:]] = r.error
            out.sections.append(stability_section(m, plan.critical[m.spec],
                                                  curves.value if curves.error is None else None,
                                                  runs, errors, labels, differences))
        return out
