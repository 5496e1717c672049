"""The stability judge (`comparisons.stages.stability.judge_run`) at 0.9 and 1.1 x each critical
speed of the benchmark bicycle: the mode it predicts, and the sign it expects, against
Meijaard et al.'s closed form (`comparisons.judgments.meijaard`, written from the paper,
independent of the model's linearization), then judged on the reference engine's own run.

Which eigenvalue is "the weave" or "the capsize" at a speed is decided here by continuity, not
by the judge's rule: at its critical speed a mode is the one on the imaginary axis (the weave
pair's real part, or the capsize root, is zero there), and it is followed in the closed form in
small speed steps to 0.9 or 1.1 x. The signs are the definitions of the speeds: the weave grows
below its speed and decays above it, the capsize decays below its speed and grows above it.

Cost: four 5 s reference runs on the 0.01 s grid, ~0.7 s in all.
"""

import numpy as np
import pytest

from comparisons.judgments.meijaard import (closed_form, closed_form_critical_speeds,
                                            closed_form_eigenvalues)
from comparisons.stages.stability import FACTORS, judge_run, scenario, stability_model
from reference_model.benchmark import to_benchmark

SIGN = {("weave", 0.9): +1, ("weave", 1.1): -1, ("capsize", 0.9): -1, ("capsize", 1.1): +1}


@pytest.fixture(scope="module")
def bench():
    model, _ = stability_model("benchmark")
    cf = closed_form(to_benchmark(model.params))
    weave, capsize = closed_form_critical_speeds(cf)
    return model, cf, {"weave": weave, "capsize": capsize}


def _followed(cf, mode: str, v_crit: float, factor: float, steps: int = 400) -> complex:
    """The closed-form eigenvalue of ``mode`` at factor x v_crit, followed from v_crit (where
    it is the eigenvalue nearest the imaginary axis with positive or zero imaginary part:
    the weave pair's upper member, or the zero capsize root) by nearest-neighbour steps of
    (factor - 1) v_crit / steps (~0.001 m/s: the eigenvalues move by ~0.01 /s per step, the
    gaps between modes are > 0.5 /s)."""
    lam = closed_form_eigenvalues(cf, v_crit)
    if mode == "weave":
        lam = lam[lam.imag > 0]
    else:
        lam = lam[lam.imag == 0]
    z = complex(lam[np.argmin(np.abs(lam.real))])
    assert abs(z.real) < 1e-9, (mode, z)       # the speed is where that mode crosses
    for v in np.linspace(v_crit, factor * v_crit, steps + 1)[1:]:
        lam = closed_form_eigenvalues(cf, v)
        z = complex(lam[np.argmin(np.abs(lam - z))])
    return z


@pytest.fixture(scope="module")
def runs(bench):
    """The reference's run at each (mode, factor), made once for the judge's and the
    section's tests."""
    from engines import load_engine
    model, _, crit = bench
    engine = load_engine("reference", model)
    return {(mode, f): engine.simulate(scenario("benchmark", f * crit[mode]))
            for mode in ("weave", "capsize") for f in FACTORS}


@pytest.mark.parametrize("mode", ["weave", "capsize"])
@pytest.mark.parametrize("factor", FACTORS)
def test_the_judge_predicts_the_closed_form_mode_and_the_run_confirms_it(bench, runs, mode,
                                                                         factor):
    model, cf, crit = bench
    speed = factor * crit[mode]
    expected = _followed(cf, mode, crit[mode], factor)
    assert np.sign(expected.real) == SIGN[(mode, factor)]     # the definitions of the speeds
    run = runs[(mode, factor)]
    j = judge_run(model, mode, speed, run)
    # the model's exact linearization and the paper's closed form agree to ~1e-12 relative
    # (tests/test_linear_closed_form.py); 1e-8 /s leaves room and is far below the 0.07 /s
    # smallest real part here, so another mode (>= 0.4 /s away) cannot pass
    assert j["predicted"] == pytest.approx(expected.real, rel=0, abs=1e-8), j
    assert j["expected"] == ("grows" if SIGN[(mode, factor)] > 0 else "decays")
    # the run, measured, has that sign; the nonlinear run at a 0.05 rad/s kick is within
    # ~10 % of the linear rate (0.558 against 0.612 /s below the weave speed, the worst)
    assert j["passed"] and np.sign(j["measured"]) == SIGN[(mode, factor)], j
    assert j["measured"] == pytest.approx(expected.real, rel=0.15), j
    # how it was measured, and on which run
    how = ("peaks of |dtheta/dt| from 1 s, envelope rate " if mode == "weave"
           else "capsize eigenvalue from the run (matrix pencil) ")
    assert how in j["how"] and j["how"].endswith("; completed at 5.00 s"), j
    # the right sign on a run that did not complete is not a pass
    import dataclasses
    fell = judge_run(model, mode, speed, dataclasses.replace(run, status="fell"))
    assert not fell["passed"] and fell["measured"] == j["measured"]


def test_the_stability_model_drops_only_drag_and_the_scenario_is_the_models():
    """cv = 0 (no steady upright motion with drag), said in a note only when there was drag;
    the run's scenario: the model's spec, upright, the roll-rate kick, the wheel rate for the
    speed (v / R_rear), the model-stability tag."""
    from comparisons.stages.stability import ROLL_RATE
    model, note = stability_model("benchmark")
    assert note == "" and model.params.cv == 0.0
    dragged, note = stability_model("thesis-disc")
    assert dragged.params.cv == 0.0 and dragged.params.R_rear > 0
    assert note.startswith("thesis-disc has drag (cv = ") and note.endswith(
        "linearized and run with cv = 0")
    sc = scenario("thesis-disc", 4.6)
    assert (sc.model, sc.kind, sc.tags) == ("thesis-disc", "forward", ("model-stability",))
    assert sc.dq_ind0 == (ROLL_RATE, 4.6 / dragged.params.R_rear, 0.0)
    assert sc.q0 == (0,) * 8 and sc.torques == (0.0, 0.0, 0.0)    # upright, no torques
    assert sc.constraints == "projection"
    assert sc.name.startswith("stability-v4.6") and "4.6000 m/s" in sc.description
    assert scenario("thesis-disc", 5.0).name != sc.name


def test_the_section_judges_each_run_and_says_what_was_not_run(bench, runs):
    """The section of the benchmark from the four runs above, a soft-contact label whose runs
    are a declared difference (reported, never judged), one that could not represent the
    bicycle (a reason, not run) and one whose runs failed (FAIL): the critical speeds are the
    closed form's (6 decimals), each row is its run's judge_run in the table and in the
    comparisons, in the labels' order; without a critical speed, no runs."""
    import dataclasses
    from comparisons.stages.cases import model_spec
    from comparisons.stages.results import Table, Text
    from comparisons.stages.stability import run_speeds, stability_section
    model, _, crit = bench
    m = model_spec("benchmark")
    speeds = run_speeds(crit)
    assert [(mode, f) for mode, f, _ in speeds] == [(mode, f) for mode in ("weave", "capsize")
                                                    for f in FACTORS]
    got, errors = {}, {}
    for mode, f, v in speeds:
        got[(mode, v, "reference")] = runs[(mode, f)]
        got[(mode, v, "soft")] = dataclasses.replace(runs[(mode, f)], status="fell")
        got[(mode, v, "rigid-less")] = "cannot represent it"
        errors[(mode, v, "broken")] = "boom"
    labels = ("reference", "soft", "rigid-less", "broken")
    sec = stability_section(m, crit, None, got, errors, labels, {"soft": "soft contact"})
    assert sec.title.startswith("Stability of benchmark")
    text = " ".join(b.text for b in sec.blocks if isinstance(b, Text))
    assert (f"Critical speeds: weave {crit['weave']:.6f} m/s, capsize {crit['capsize']:.6f} m/s"
            in text) and "contact disc, cv = 0." in text
    assert "soft: a declared model difference (soft contact)" in text
    (table,) = [b for b in sec.blocks if isinstance(b, Table)]
    assert len(table.rows) == 4 * len(labels)
    for i, (mode, f, v) in enumerate(speeds):
        j = judge_run(model, mode, v, runs[(mode, f)])
        ref, soft, less, broken = table.rows[4 * i: 4 * i + 4]
        assert ref == (mode, f"{f:g} x = {v:.4f}", "reference", f"{j['predicted']:+.4f}",
                       f"{j['measured']:+.4f}", f"{mode} {j['expected']}", "pass", j["how"])
        assert soft[2] == "soft" and soft[6] == "reported: differs"   # it fell: not a pass
        assert less[2:] == ("rigid-less", "-", "-", "-", "not run", "cannot represent it")
        assert broken[2:] == ("broken", "-", "-", "-", "FAIL", "boom")
    assert table.header == ("mode", "speed [m/s]", "engine", "linear real part [1/s]",
                            "measured [1/s]", "predicted", "verdict", "how")
    # summary.json's comparisons (docs/report.md): the common fields and each kind's extras
    rows = {(c["engines"][0], c["scenario"]): c.as_dict() for c in sec.comparisons}
    assert len(rows) == 4 * len(labels)
    for mode, f, v in speeds:
        where = f"benchmark at {v:.4f} m/s ({f:g} x {mode} speed)"
        j = judge_run(model, mode, v, runs[(mode, f)])
        judged = {"quantity": f"stability: {mode} {j['expected']} (sign of its real part)",
                  "scenario": where, "model": "benchmark", "max_error": None, "tolerance": None,
                  "localized_to": f"measured {j['measured']:+.4f} /s",
                  "measured": j["measured"], "predicted": j["expected"], "linear": j["predicted"]}
        assert rows[("reference", where)] == {**judged, "engines": ["reference"], "passed": True,
                                              "note": j["how"]}
        soft = judge_run(model, mode, v, got[(mode, v, "soft")])
        assert rows[("soft", where)] == {
            **judged, "engines": ["soft"], "passed": None,
            "note": f"{soft['how']}; reported, not judged: a declared model difference "
                    "(soft contact)",
            "declared_difference": "soft contact", "agrees": False,
            "why": "declared model difference"}
        unjudged = {"quantity": f"stability: {mode} run", "model": "benchmark",
                    "max_error": None, "tolerance": None}
        assert rows[("rigid-less", where)] == {
            **unjudged, "scenario": where, "engines": ["rigid-less"], "passed": None,
            "localized_to": "-", "note": "cannot represent it"}
        assert rows[("broken", f"benchmark at {v:.4f} m/s")] == {
            **unjudged, "scenario": f"benchmark at {v:.4f} m/s", "engines": ["broken"],
            "passed": False, "localized_to": "boom", "note": ""}
    (panels,) = [b for b in sec.figures if b.kind == "lean_panels"]
    assert panels.name == "stability_runs_benchmark.png"
    assert panels.data["ylabel"] == "theta (lean) [rad]"
    assert [p["title"] for p in panels.data["panels"]] == [
        f"benchmark: {f:g} x {mode} speed = {v:.4f} m/s" for mode, f, v in speeds]
    for (mode, f, v), p in zip(speeds, panels.data["panels"]):
        assert sorted(p["lines"]) == ["reference", "soft"]
        t, theta = p["lines"]["reference"]
        np.testing.assert_array_equal(theta, runs[(mode, f)].q[:, 3])   # theta, the lean
    curves = {"speeds": np.arange(3.0)}
    drawn = stability_section(m, crit, curves, got, errors, labels, {"soft": "soft contact"})
    (eig,) = [b for b in drawn.figures if b.kind == "eigenvalues"]
    assert eig.name == "eigenvalues_benchmark.png" and eig.data == curves
    # the labels default to the runs' own order
    default = stability_section(m, crit, None, got, errors,
                                differences={"soft": "soft contact"})
    assert [b for b in default.blocks if isinstance(b, Table)] == [table]
    # the other verdicts: a judged run that did not complete FAILs, a reported one that
    # agrees says so, and a label that cannot run, first in the order, stops nothing after it
    swapped = {**got, **{(mode, v, "reference"): got[(mode, v, "soft")] for mode, _, v in speeds},
               **{(mode, v, "soft"): got[(mode, v, "reference")] for mode, _, v in speeds}}
    other = stability_section(m, crit, None, swapped, {}, ("rigid-less", "reference", "soft"),
                              {"soft": "soft contact"})
    (t2,) = [b for b in other.blocks if isinstance(b, Table)]
    assert [(r[2], r[6]) for r in t2.rows] == [("rigid-less", "not run"), ("reference", "FAIL"),
                                               ("soft", "reported: agrees")] * 4
    # a bicycle with drag: the note says it was removed; no declared difference, no sentence
    dragged = stability_section(model_spec("thesis-disc"), {"weave": 4.0}, None, {}, {})
    prose = " ".join(b.text for b in dragged.blocks if isinstance(b, Text))
    assert "eigenvalues against speed 0-10 m/s. thesis-disc has drag (cv = " in prose
    assert "declared model difference" not in prose and prose.endswith("matrix pencil).")
    none = stability_section(m, {}, None, {}, {})
    assert "none in 0-10 m/s" in none.blocks[0].text and not none.comparisons
    assert none.blocks[-1].text == "No critical speed in the range: no runs."


def test_the_stage_asks_for_the_curves_and_one_run_per_speed_and_setup(bench):
    """Its tasks for a model with critical speeds (a model without is skipped, and the next is
    still planned): the eigenvalue curves, then each run (stability_run of the model, the setup
    and the speed) named for its model, factor, mode and engine, and tagged with the engine
    whose code it runs (None for the reference's own)."""
    from types import SimpleNamespace

    from comparisons.stages.cases import model_spec
    from comparisons.stages.runs import setups_for
    from comparisons.stages.stability import (StabilityStage, run_speeds, stability_curves,
                                              stability_run)
    from comparisons.stages.stage import Plan
    from engines.facts import engine_facts
    _, _, crit = bench
    setups = tuple(setups_for(("reference", "pinocchio"), {}))
    m = model_spec("benchmark")
    plan = Plan(opts=SimpleNamespace(models=(model_spec("thesis-disc"), m), quick=False),
                setups=setups, facts={s.engine: engine_facts(s.engine) for s in setups},
                critical={m.spec: crit})
    curves, *runs = StabilityStage().tasks(plan)
    assert (curves.key, curves.func, curves.args, curves.label, curves.engine) == \
        (("curves", "benchmark"), stability_curves, ("benchmark",),
         "benchmark: eigenvalues against speed", None)
    want = [(("run", "benchmark", mode, v, s.label), ("benchmark", s, v),
             f"benchmark: {f:g} x {mode} speed on {s.label}",
             None if s.engine == "reference" else s.engine)
            for mode, f, v in run_speeds(crit) for s in setups]
    assert [(t.key, t.args, t.label, t.engine) for t in runs] == want
    assert all(t.func is stability_run for t in runs)
    # a run's expected time (its pool budget: 20 x it, at least 60 s) is 5 s of simulated time
    # at its engine's declared cost per simulated second; the curves' is some positive time
    assert [t.cost for t in runs] == [5.0 * plan.facts[s.engine].costs.run_per_second
                                      for _ in run_speeds(crit) for s in setups]
    assert curves.cost > 0
    assert [t.engine for t in runs[:2]] == [None, "pinocchio"]
