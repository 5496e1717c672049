"""The soft-contact study is every soft-contact engine's, not one engine's (issue 25): the same
study, a row of its own in the side-by-side ranking (report and summary.json's
``soft_contact_ranking``) and its own thesis-disc claims, for a second engine the harness has
never heard of (tests/soft_twin.py: the built-in soft contact five times softer, loaded by a
file spec), beside the built-in one.

Expected values come from outside the code under test: slip RMS recomputed from each study's
own per-sample diagnostics (the figure's arrays), the ranking order from the rows' errors, and
the twin's place from MuJoCo's documented constraint model (slip and error proportional to the
contact's time constant: five times the time constant, about five times both).

Cost: the twin's quick study (~0.5 s, made once per session: `twin_quick_study`; the
built-in's is `mujoco_quick_study`, which tests/test_contact.py shares), two 5 s reference runs
at the benchmark's weave speeds (~0.3 s), and ms for the rest. The whole run on both engines is
`slow`.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from comparisons.judgments.contact_ranking import ContactRow, contact_row, rank, shared_horizon
from comparisons.stages.pool import TaskResult
from comparisons.stages.results import Figure, Table
from comparisons.stages.soft_contact import MODEL, SoftContactStage
from comparisons.stages.soft_contact_claims import DiscClaims
from comparisons.stages.stage import Plan
from engines.facts import engine_facts
from reference_model.solvers import Trajectory
from soft_twin import NAME, SPEC, TC

BUILT_IN = "mujoco"
BUILT_IN_TC = 2e-4       # s: its declared default solref time constant (engines/mujoco/options)


# -- the ranking as a judgment: synthetic rows and runs -------------------------------------------

def _row(engine, error, slip=1e-3, reached=True, horizon=0.43, model=MODEL):
    return ContactRow(engine=engine, label=engine.upper(), model=model,
                      scenario="stability-psid10", horizon=horizon, reached=reached,
                      error_at_horizon=error if reached else None, error_max=error or 1.0,
                      slip_rms=slip, slip_max=2 * slip, penetration_max=1e-7,
                      penetration_rms=1e-8, lift_off_s=None, simulated_s=0.6, run_seconds=0.3)


def test_the_ranking_puts_the_smallest_error_at_the_horizon_first():
    """Order from the rows themselves: errors 3e-4, 1e-4, 2e-4 rank b, c, a; a tie in the error
    goes to the smaller slip; a run that ends before the horizon is last whatever its numbers."""
    rows = [_row("a", 3e-4), _row("b", 1e-4), _row("c", 2e-4, slip=5e-3),
            _row("d", 2e-4, slip=1e-3), _row("e", None, slip=0.0, reached=False)]
    ranked = rank(rows)
    assert [(r.rank, r.row.engine) for r in ranked] == [(1, "b"), (2, "d"), (3, "c"), (4, "a"),
                                                          (5, "e")]
    errors = [r.row.error_at_horizon for r in ranked if r.row.reached]
    assert errors == sorted(errors)


def test_rows_not_side_by_side_are_refused():
    with pytest.raises(ValueError, match="not on one model, scenario and horizon: "
                       r"a: thesis-disc, stability-psid10, 0\.43 s; "
                       r"b: thesis-disc, stability-psid10, 0\.3 s$"):
        rank([_row("a", 1e-4), _row("b", 1e-4, horizon=0.3)])
    with pytest.raises(ValueError, match="twice"):
        rank([_row("a", 1e-4), _row("a", 2e-4)])


def test_the_shared_horizon_is_the_last_sample_before_the_ground_must_pull():
    t = np.round(np.arange(61) * 0.01, 12)
    assert shared_horizon(t, 0.44, 0.6, 0.6) == pytest.approx(0.43)
    assert shared_horizon(t, None, 0.6, 0.5) == pytest.approx(0.5)       # the window
    assert shared_horizon(t, 0.44, 0.25, 0.6) == pytest.approx(0.25)     # the reproducible part
    assert shared_horizon(t, 0.445, 0.6, 0.6) == pytest.approx(0.44)     # off the grid


def test_the_shared_horizon_treats_a_billionth_of_a_step_as_round_off():
    """The grid's own step sets the round-off: a time within 1e-9 of a step of a sample is that
    sample, one 1.5e-9 of a step away is another instant. On a grid far from 0 (t0 = 100 s,
    dt = 0.01 s), so a step taken from the wrong samples (t1 + t0, t2 - t0, 1 s, 0) moves the
    band; and the one- and two-sample grids, whose step is 1 s by definition or t1 - t0."""
    t = 100.0 + np.arange(61) * 0.01
    dt = float(t[1] - t[0])
    t43, t44 = float(t[43]), float(t[44])
    # the ground must pull at t44 itself (up to round-off): the last sample before is t43
    assert shared_horizon(t, t44 + 0.5e-9 * dt, 200.0, 200.0) == t43
    # it must pull 1.5e-9 dt after t44: t44 is before it
    assert shared_horizon(t, t44 + 1.5e-9 * dt, 200.0, 200.0) == t44
    # the meaningful horizon a round-off short of t44 is t44; 1.5e-9 dt short of it is not
    assert shared_horizon(t, None, t44 - 0.5e-9 * dt, 200.0) == t44
    assert shared_horizon(t, None, t44 - 1.5e-9 * dt, 200.0) == t43
    assert shared_horizon(np.array([2.0]), None, 5.0, 5.0) == 2.0
    two = np.array([100.0, 100.01])
    assert shared_horizon(two, 100.01 + 1.5e-9 * 0.01, 200.0, 200.0) == 100.01


def _traj(t, q, diag):
    z = np.zeros_like(q)
    return Trajectory(t=t, q=q, dq=z, ddq=z, C=np.zeros((t.size, 5)), T=np.zeros((t.size, 3)),
                      status="completed", message="", t_end=float(t[-1]), diagnostics=diag)


def test_a_row_measures_its_own_run_up_to_the_horizon():
    """A run drifting in yc at 2e-3 m/s with slip 1e-3 m/s on the rear wheel and 3e-3 on the
    front up to the horizon (and 1 m/s after it, which must not count): error 2e-3 x 0.4 at the
    horizon, slip RMS sqrt((1e-6 + 9e-6) / 2), run time 0.3 s / 0.6 s."""
    t = np.round(np.arange(61) * 0.01, 12)
    q = np.zeros((t.size, 8))
    q[:, 1] = 2e-3 * t
    after = t > 0.4 + 1e-9
    diag = {"slip_speed_rear": np.where(after, 1.0, 1e-3),
            "slip_speed_front": np.where(after, 1.0, 3e-3),
            "penetration_rear": np.full(t.size, 1e-6), "penetration_front": np.zeros(t.size)}
    ref = _traj(t, np.zeros_like(q), {})
    row = contact_row("x", "X", ref, _traj(t, q, diag), horizon=0.4, seconds=0.3)
    assert row.reached and row.error_at_horizon == pytest.approx(8e-4, rel=1e-12)
    assert row.slip_rms == pytest.approx(np.sqrt((1e-6 + 9e-6) / 2), rel=1e-12)
    assert row.slip_max == pytest.approx(3e-3) and row.penetration_max == pytest.approx(1e-6)
    assert row.run_time_per_simulated_second == pytest.approx(0.5)
    # the error grows linearly, so its max up to the horizon is the one at it; the rear wheel
    # sinks 1e-6 m, the front none: RMS over both wheels' samples 1e-6 / sqrt(2)
    assert row.error_max == pytest.approx(8e-4, rel=1e-12)
    assert row.penetration_rms == pytest.approx(1e-6 / np.sqrt(2), rel=1e-12)
    assert (row.label, row.model, row.scenario, row.settings, row.lift_off_s) == \
        ("X", "", "", "", None)
    named = contact_row("x", "X", ref, _traj(t, q, diag), horizon=0.4, seconds=0.3,
                        model="thesis-disc", scenario="stability-psid10", settings="h = 0.002",
                        lift_off_s=0.45)
    assert (named.model, named.scenario, named.settings, named.lift_off_s) == \
        ("thesis-disc", "stability-psid10", "h = 0.002", 0.45)
    short = _traj(t[:31], q[:31], {k: v[:31] for k, v in diag.items()})
    cut = contact_row("y", "Y", ref, short, horizon=0.4, seconds=0.1)
    assert not cut.reached and cut.error_at_horizon is None
    assert cut.error_max == pytest.approx(2e-3 * 0.3, rel=1e-12)    # measured to its own end
    assert [r.row.engine for r in rank([cut, row])] == ["x", "y"]
    # a run that ends on the horizon reaches it; so does one whose only sample is a horizon
    # at the start (no drift yet: error 0)
    ends = contact_row("z", "Z", ref, _traj(t[:41], q[:41], {k: v[:41] for k, v in diag.items()}),
                       horizon=0.4, seconds=0.1)
    assert ends.reached and ends.error_at_horizon == pytest.approx(8e-4, rel=1e-12)
    first = contact_row("w", "W", ref, _traj(t[:1], q[:1], {k: v[:1] for k, v in diag.items()}),
                        horizon=0.0, seconds=0.1)
    assert first.reached and first.error_at_horizon == 0.0
    # a reference that ends before the horizon: no common sample there, so not reached
    early = contact_row("v", "V", _traj(t[:31], np.zeros_like(q[:31]), {}), _traj(t, q, diag),
                        horizon=0.4, seconds=0.3)
    assert not early.reached and early.error_at_horizon is None


# -- two soft-contact engines through the stage ------------------------------------------------

@pytest.fixture(scope="module")
def twin_study(twin_quick_study):
    return twin_quick_study


@pytest.fixture(scope="module")
def assembled(mujoco_quick_study, twin_study):
    """The stage's assembly of both engines' studies and of thesis-disc claims made by hand
    (the claims' runs are the slow test's)."""
    facts = {"reference": engine_facts("reference"), BUILT_IN: engine_facts(BUILT_IN),
             SPEC: engine_facts(SPEC)}
    plan = Plan(opts=None, setups=(), facts=facts)
    claim = "stability (Fig. 6-7): at psi_dot(0) = 10 rad/s ..."

    def disc(engine, label, verdict):
        return DiscClaims(engine, label, ({"claim": claim, "claim_id": "stability-psid10",
                                           "engine": engine, "verdict": verdict,
                                           "evidence": f"{engine}'s run"},))
    results = {("study", BUILT_IN, MODEL): TaskResult(None, mujoco_quick_study, 1.0),
               ("study", SPEC, MODEL): TaskResult(None, twin_study, 1.0),
               ("claims-reference", "reference", MODEL):
                   TaskResult(None, disc("reference", "reference", "partly"), 1.0),
               ("claims", BUILT_IN, MODEL): TaskResult(None, disc(BUILT_IN, "MuJoCo", "partly"), 1.0),
               ("claims", SPEC, MODEL): TaskResult(None, disc(NAME, "Soft twin", "not reproduced"), 1.0)}
    stage = SoftContactStage()
    part = stage.assemble(plan, results)
    base = [{"claim": claim, "claim_id": "stability-psid10", "engine": e,
             "verdict": "not assessed", "evidence": "no thesis contact"}
            for e in ("reference", BUILT_IN, NAME)]
    return part, stage.revise_claims(plan, results, base)


def _fig(study, kind):
    return next(b for b in study.section.blocks if isinstance(b, Figure) and b.kind == kind)


def _slip_rms(study, horizon):
    """From the study's own per-sample diagnostics (the figure's arrays), not from the row."""
    d = _fig(study, "contact_run").data
    keep = np.asarray(d["t"]) <= horizon + 1e-9
    both = np.concatenate([np.asarray(d["slip"][w])[keep] for w in ("rear", "front")])
    return float(np.sqrt(np.mean(both ** 2)))


def test_each_engine_gets_the_same_study_under_its_own_name(mujoco_quick_study, twin_study):
    for study, label in ((mujoco_quick_study, "MuJoCo"), (twin_study, "Soft twin")):
        assert study.section.title.startswith(f"{label} contact study")
        kinds = [b.kind for b in study.section.blocks if isinstance(b, Figure)]
        assert kinds == ["contact_run", "refinement"]
        qty = [c["quantity"].split(" (")[0] for c in study.section.comparisons]
        assert qty[0] == "contact fidelity" and "contact refinement" in qty
    names = [b.name for s in (mujoco_quick_study, twin_study) for b in s.section.figures]
    assert len(set(names)) == len(names), names      # no engine draws over another's figure
    table = {b.header[0]: b for b in twin_study.section.blocks if isinstance(b, Table)}
    assert dict(table["setting"].rows)["solref (time constant s, damping ratio)"] == f"{TC:g}, 1"


def test_the_twins_refinement_has_its_own_series_and_order(twin_study):
    """Its declared series (the time constant over 8x, step at half of it) at order 1 +- 0.2
    (the built-in's measured law, slip and error proportional to the time constant)."""
    (row,) = [c for c in twin_study.section.comparisons if c["quantity"].startswith("contact refinement")]
    assert row["values"] == [4e-3, 2e-3, 1e-3, 5e-4]
    assert 0.8 <= row["order"] <= 1.2 and row["verdict"] == "approaches ideal rolling", row
    assert len(row["run_time_per_simulated_second"]) == 4
    assert all(c > 0 for c in row["run_time_per_simulated_second"])


def test_the_ranking_has_each_engines_own_numbers(assembled, mujoco_quick_study, twin_study):
    """One row per engine in summary.json's new key and in the report's table; each row's slip
    RMS is the RMS of that engine's own diagnostics up to the shared horizon (recomputed here),
    and the label beside it is that engine's."""
    part, _ = assembled
    (entry,) = part.summary["soft_contact_ranking"]
    horizon = entry["horizon_s"]
    assert entry["model"] == MODEL and 0.3 <= horizon <= 0.6
    rows = {r["engine"]: r for r in entry["rows"]}
    assert set(rows) == {BUILT_IN, NAME}
    for engine, study in ((BUILT_IN, mujoco_quick_study), (NAME, twin_study)):
        assert rows[engine]["slip_rms"] == pytest.approx(_slip_rms(study, horizon), rel=1e-12)
        assert rows[engine]["run_time_per_simulated_second"] > 0
    section = part.sections[0]
    assert section.title.startswith("Soft-contact engines side by side")
    table = next(b for b in section.blocks if isinstance(b, Table))
    by_label = {r[1]: r for r in table.rows}
    assert set(by_label) == {"MuJoCo", "Soft twin"}
    for engine, label in ((BUILT_IN, "MuJoCo"), (NAME, "Soft twin")):
        assert by_label[label][0] == str(rows[engine]["rank"])
        assert by_label[label][4] == f"{rows[engine]['slip_rms']:.2e}"
    json.dumps(part.summary)      # plain data, as the writer needs


def test_the_softer_contact_ranks_second_by_about_five_times(assembled):
    """Five times the time constant: about five times the slip (0.8x-1.25x of 5: the slip's
    pattern shifts a little with the contact) and an error three to eight times larger (first
    order in the time constant, with the integrator's own share at each step)."""
    part, _ = assembled
    rows = part.summary["soft_contact_ranking"][0]["rows"]
    assert [r["engine"] for r in rows] == [BUILT_IN, NAME] and [r["rank"] for r in rows] == [1, 2]
    a, b = rows
    ratio = TC / BUILT_IN_TC
    assert 0.8 * ratio <= b["slip_rms"] / a["slip_rms"] <= 1.25 * ratio, (a, b)
    assert 3.0 <= b["error_at_horizon"] / a["error_at_horizon"] <= 8.0, (a, b)


def test_a_soft_contact_is_a_declared_difference_never_a_failure(assembled):
    part, _ = assembled
    rows = [c for s in part.sections for c in s.comparisons]
    assert len(rows) >= 4 and all(c["passed"] is None for c in rows), \
        [c["quantity"] for c in rows if c["passed"] is not None]
    assert all("declared model difference" in c["note"] for c in rows)


def test_the_claims_are_side_by_side_and_each_engine_keeps_its_own(assembled):
    part, claims = assembled
    section = next(s for s in part.sections if "stability claims" in s.title)
    table = next(b for b in section.blocks if isinstance(b, Table))
    assert table.header == ("claim", "reference thesis-disc", f"{BUILT_IN} thesis-disc",
                            f"{NAME} thesis-disc")
    assert [c.split(":")[0] for c in table.rows[0][1:]] == ["partly", "partly", "not reproduced"]
    by = {c["engine"]: c for c in claims}
    assert by["reference"]["verdict"] == "not assessed"       # its thesis-contact claim stays
    assert by[BUILT_IN]["verdict"] == "partly" and by[NAME]["verdict"] == "not reproduced"
    assert by[NAME]["evidence"].startswith("on thesis-disc (Soft twin has")
    assert by[NAME]["evidence"].endswith(f"{NAME}'s run")


# -- the whole run on both engines -------------------------------------------------------------

@pytest.mark.slow
def test_a_run_with_two_soft_contact_engines(tmp_path):
    """run --sections contact on the built-in and the twin (full size: the claims too): a
    ranking row and thesis-disc claims for each, the run passes (a soft contact fails
    nothing). Measured 11 s, and 18 s at a load of 9, on the 2-core machine."""
    from comparisons.cli import main
    out = tmp_path / "r"
    assert main(["run", "--scenarios", "stability-psid0,stability-psid10", "--engines",
                 f"reference,{BUILT_IN},{SPEC}", "--sections", "contact", "--figures", "none",
                 "--no-html", "--no-data", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    (entry,) = summary["soft_contact_ranking"]
    assert [r["engine"] for r in entry["rows"]] == [BUILT_IN, NAME]
    disc = [c for c in summary["claims"] if c["engine"] in (BUILT_IN, NAME)
            and c["claim_id"] == "stability-psid10"]
    assert len(disc) == 2 and all(c["evidence"].startswith("on thesis-disc") for c in disc)
    assert all(c["verdict"] != "not assessed" for c in disc)
    text = (out / "report.md").read_text()
    assert "Soft-contact engines side by side" in text
    assert "Soft twin contact study" in text and "MuJoCo contact study" in text


# -- the stability picture's nonlinear runs against the linear prediction -------------------------

WEAVE = 4.29238          # m/s: the benchmark's published weave speed (Meijaard et al. 2007)


@pytest.fixture(scope="module")
def weave_runs():
    """The reference's two runs at 0.9 and 1.1 x the weave speed (~0.3 s)."""
    from comparisons.stages.stability import FACTORS, scenario, stability_model
    from engines import load_engine
    model, _ = stability_model("benchmark")
    eng = load_engine("reference", model)
    return {f * WEAVE: eng.simulate(scenario("benchmark", f * WEAVE)) for f in FACTORS}


def test_a_soft_contact_engines_stability_runs_are_reported_not_judged(weave_runs):
    """The same runs under a judged label and under a soft-contact one: the judged rows pass
    (the weave grows below its speed and decays above it, the speed's definition), the soft
    rows carry the same measurement, passed None, the declared difference and whether the sign
    agrees; a bicycle the engine cannot represent is 'not run', not a failure; an engine that
    crashes still fails."""
    from comparisons.stages.cases import model_spec
    from comparisons.stages.stability import stability_section
    runs = {}
    for speed, traj in weave_runs.items():
        runs[("weave", speed, "reference")] = traj
        runs[("weave", speed, NAME)] = traj
    slow = max(weave_runs)
    runs[("weave", slow, "other")] = "not run on this model: it breaks A + B >= C"
    errors = {("weave", slow, "broken"): "EngineError: diverged"}
    sec = stability_section(model_spec("benchmark"), {"weave": WEAVE}, None, runs, errors,
                            ("reference", NAME, "other", "broken"),
                            {NAME: "soft contact", "other": "soft contact"})
    rows = {(c["engines"][0], c["scenario"].split(" at ")[1][:6]): c for c in sec.comparisons}
    judged = [c for (e, _), c in rows.items() if e == "reference"]
    soft = [c for (e, _), c in rows.items() if e == NAME]
    assert len(judged) == 2 and all(c["passed"] is True for c in judged)
    assert len(soft) == 2 and all(c["passed"] is None and c["agrees"] is True
                                  and c["declared_difference"] == "soft contact" for c in soft)
    assert sorted(c["measured"] for c in soft) == sorted(c["measured"] for c in judged)
    (other,) = [c for (e, _), c in rows.items() if e == "other"]
    assert other["passed"] is None and other["note"].startswith("not run on this model")
    (broken,) = [c for (e, _), c in rows.items() if e == "broken"]
    assert broken["passed"] is False


def test_the_stability_stage_runs_soft_contact_engines_in_full_runs_only():
    from types import SimpleNamespace

    from comparisons.stages.cases import model_spec
    from comparisons.stages.runs import setups_for
    from comparisons.stages.stability import StabilityStage
    setups = tuple(setups_for(("reference", BUILT_IN, SPEC), {}))
    m = model_spec("benchmark")
    labels = {}
    for quick in (False, True):
        plan = Plan(opts=SimpleNamespace(models=(m,), quick=quick), setups=setups,
                    facts={s.engine: engine_facts(s.engine) for s in setups},
                    critical={m.spec: {"weave": WEAVE}})
        labels[quick] = sorted({t.key[-1] for t in StabilityStage().tasks(plan)
                                if t.key[0] == "run"})
    assert labels[False] == sorted(["reference", BUILT_IN, NAME])
    assert labels[True] == ["reference"]


def test_a_rows_summary_entry_is_its_fields_under_summary_jsons_keys():
    """summary.json's soft_contact_ranking entry (docs/report.md): each field under its key,
    the run time per simulated second the wall time over the simulated time (2 s / 0.5 s)."""
    from comparisons.judgments.contact_ranking import ContactRow
    row = ContactRow(engine="mujoco", label="MuJoCo", model="thesis-disc", scenario="s",
                     horizon=0.43, reached=True, error_at_horizon=1e-3, error_max=2e-3,
                     slip_rms=3e-3, slip_max=4e-3, penetration_max=5e-4, penetration_rms=6e-4,
                     lift_off_s=0.44, simulated_s=0.5, run_seconds=2.0, settings="h = 0.002")
    assert row.as_dict() == {
        "engine": "mujoco", "label": "MuJoCo", "reached_horizon": True,
        "error_at_horizon": 1e-3, "error_max": 2e-3, "slip_rms": 3e-3, "slip_max": 4e-3,
        "penetration_max": 5e-4, "penetration_rms": 6e-4, "lift_off_s": 0.44,
        "run_time_per_simulated_second": 4.0, "settings": "h = 0.002"}
    import dataclasses
    assert math.isnan(dataclasses.replace(row, simulated_s=0.0).run_time_per_simulated_second)
