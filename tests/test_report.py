"""The report of `bicycle-xval run`: the summary.json contract, the engine runs, the thesis's
claims per engine, the self-contained HTML, exit codes and determinism."""

import json
import re
from pathlib import Path

import pytest

from comparisons.cli import main
from comparisons.judgments.summary import summary_table
from engines.facts import engine_facts


VERDICTS = {"reproduced", "not reproduced", "partly", "not assessed"}


@pytest.fixture(scope="module")
def report(quick_report):
    """The session's quick report (tests/conftest.py): (folder, summary)."""
    out, code, summary = quick_report
    assert code == 0
    return out, summary


def test_summary_carries_the_contract_keys(report):
    _, summary = report
    from conftest import QUICK_REPORT_ENGINES
    from engines.facts import engine_facts
    # the engines asked for, in their order
    assert summary["engines"] == list(QUICK_REPORT_ENGINES)
    # the engines beside the three setups below: Kane's disc-only equations and the
    # soft-contact simulators, none running the thesis's fork-axis contact
    disc_only = [e for e in summary["engines"] if e not in ("reference", "pinocchio", "exudyn")]
    soft = [e for e in disc_only if engine_facts(e).run_difference]
    assert {"comparisons", "claims", "faults", "environment"} <= set(summary)
    assert summary["comparisons"], "no engine comparison in the summary"
    for c in summary["comparisons"]:
        assert {"quantity", "scenario", "engines", "max_error", "tolerance", "passed"} <= set(c)
    for c in summary["claims"]:
        assert {"claim", "claim_id", "engine", "verdict", "evidence"} <= set(c)
        assert c["verdict"] in VERDICTS and c["evidence"]
    # --quick selects check, zigzag, check-forward, stability-psid10: exactly the claims that
    # need one of those scenarios, once per engine setup
    setups = ("reference", "pinocchio", "exudyn-tree")
    claims = {(c["claim_id"], c["engine"]): c for c in summary["claims"]}
    assert len(claims) == len(summary["claims"])
    ids = ("check-pedal-torque", "replay-identical", "stability-psid10")
    others = tuple(summary["engines"][3:])      # kane, mujoco and any engine registered since
    assert set(claims) == {(cid, e) for e in setups + others for cid in ids}
    # Kane's equations model the disc contact only: on the thesis bicycle's runs nothing of
    # its own to judge (so for every disc-only engine)
    disc_only = [e for e in others if engine_facts(e).contacts == ("disc",)]
    assert "kane" in disc_only
    assert all(claims[(cid, e)]["verdict"] == "not assessed" for cid in ids for e in disc_only)
    runs = {(r["engine"], r["scenario"]): r for r in summary["engine_runs"]}
    # MuJoCo and Drake have no thesis (fork-axis) front contact: their runs of the thesis's
    # scenarios are 'not run', a declared model difference, and (without the contact section,
    # which judges the stability claims on their thesis-disc runs) their claims not assessed,
    # not failed
    assert {"mujoco"} <= set(soft)
    for e in soft:
        for sc in ("check-forward", "stability-psid10"):
            assert runs[(e, sc)]["status"] == "not run"
            assert "declared model difference" in runs[(e, sc)]["message"]
        assert {claims[(cid, e)]["verdict"] for cid in
                ("check-pedal-torque", "replay-identical", "stability-psid10")} == {"not assessed"}
    for e in setups:
        # the replay is not in the quick subset: its claim is listed, and not assessed
        c = claims[("replay-identical", e)]
        assert c["verdict"] == "not assessed" and "replay not run" in c["evidence"], c
        # straight rolling under the drag-balancing torque is an exact steady state
        # (tests/test_solvers.py): every engine that runs it must reproduce it
        assert claims[("check-pedal-torque", e)]["verdict"] == "reproduced", claims
        # psid10: the verdict must agree with the run it judges, as reported in the same file
        run, c = runs[(e, "stability-psid10")], claims[("stability-psid10", e)]
        if run["status"] == "fell":
            assert c["verdict"] in ("partly", "not reproduced"), c
            assert f"fell at {run['t_end']:.3f} s" in c["evidence"], (c, run)
        else:
            assert run["status"] == "completed", run
            assert c["verdict"] in ("reproduced", "partly"), c
    for f in summary["faults"]:
        assert {"fault", "detected", "localized_to"} <= set(f)
    env = summary["environment"]
    assert {"packages", "machine", "solvers", "steps"} <= set(env)
    # each engine's declared library, with its version (not 'not installed': it ran)
    assert env["packages"]["pinocchio"] != "not installed" and env["packages"]["exudyn"] != "not installed"


def test_pinocchio_terms_all_pass_and_name_their_worst_entry(report):
    _, summary = report
    terms = [c for c in summary["comparisons"] if c["engines"] == ["reference", "pinocchio"]
             and c["scenario"].startswith("random-states")]
    by_model = {}
    for c in terms:
        by_model.setdefault(c["model"], []).append(c)
    # 7 quantities on each: the thesis with both contact models, and the benchmark bicycle
    assert {m: len(cs) for m, cs in by_model.items()} == {"thesis": 7, "thesis-disc": 7, "benchmark": 7}
    assert all(c["passed"] and c["max_error"] <= c["tolerance"] for c in terms)
    assert all(c["localized_to"] for c in terms)


def test_every_engine_runs_every_scenario_it_can(report):
    """Inverse scenarios on the reference and Pinocchio, forward ones on all three; Exudyn's
    inverse runs are recorded as not run (it has no inverse dynamics), not dropped."""
    _, summary = report
    runs = {(r["engine"], r["scenario"]): r["status"] for r in summary["engine_runs"]}
    for sc in ("check", "zigzag"):
        assert runs[("reference", sc)] == runs[("pinocchio", sc)] == "completed"
        assert runs[("exudyn-tree", sc)] == "not run"
    assert all(runs[(e, "stability-psid10")] in ("fell", "completed")
               for e in ("reference", "pinocchio", "exudyn-tree"))
    # Kane's equations: no inverse dynamics, and the thesis's contact is not Moore's geometry:
    # every run here is 'not run', with the engine's own reason, and costs nothing
    kane = {r["scenario"]: r for r in summary["engine_runs"] if r["engine"] == "kane"}
    assert {r["status"] for r in kane.values()} == {"not run"}
    assert kane["check"]["message"].startswith("kane has no constrained inverse dynamics")
    assert kane["stability-psid10"]["message"].startswith("CapabilityError: engine 'kane' "
                                                          "cannot use the front contact 'thesis'")


def test_inverse_dynamics_torques_and_multipliers_compared_per_engine(report):
    _, summary = report
    got = {(c["quantity"], c["scenario"]) for c in summary["comparisons"]
           if c["engines"] == ["reference", "pinocchio"]}
    assert {("torques", "zigzag"), ("multipliers", "zigzag"), ("torques", "check"),
            ("multipliers", "check"), ("mass_matrix", "zigzag")} <= got


def test_check_claim_holds_on_the_engines_with_inverse_dynamics(report):
    """The analytic result Mped = cv (R psi_dot)^2 R (thesis 5.3) is exact: every engine with
    inverse dynamics must reproduce it."""
    _, summary = report
    verdict = {c["engine"]: c["verdict"] for c in summary["claims"]
               if c["claim_id"] == "check-pedal-torque"}
    assert verdict["reference"] == verdict["pinocchio"] == "reproduced"


def test_faults_are_detected_and_localized(report):
    _, summary = report
    ids = {f["fault"] for f in summary["faults"]}
    assert {"I3xz-sign", "I2xx-I2yy-swapped", "com-offset-1mm", "z3-0.39647",
            "gyroscopic-dropped", "contact-switched"} <= ids
    pin = [f for f in summary["faults"] if f["engine"] == "pinocchio"]
    assert len(pin) == 6 and all(f["detected"] and f["correct"] for f in pin)
    # Exudyn's tree gives M and the generalized forces only: the contact switch changes just
    # D and dD dq, so it is caught in the tree's forward run instead (12 of 12)
    exu = {f["fault"]: f for f in summary["faults"] if f["engine"] == "exudyn"}
    assert exu["contact-switched"]["localized_to"].startswith("trajectory via front contact")
    assert all(f["verdict"] == "localized" for f in exu.values())
    # Kane's equations on the disc-contact thesis bicycle give M, the generalized forces, D and
    # dD dq: all six faults show in its terms, the contact switch in D and dD dq
    kane = {f["fault"]: f for f in summary["faults"] if f["engine"] == "kane"}
    assert len(kane) == 6 and all(f["verdict"] == "localized" and f["model"] == "thesis-disc"
                                  for f in kane.values())
    assert kane["contact-switched"]["localized_to"].startswith("D, dD dq via front contact")


def test_kane_terms_pass_on_the_disc_model_and_are_not_run_on_the_thesis_contact(report):
    out, summary = report
    terms = [c for c in summary["comparisons"] if c["engines"] == ["reference", "kane"]
             and c["model"] != "benchmark"]   # the benchmark section's terms: disc contact too
    assert {c["quantity"] for c in terms} == {"mass_matrix", "generalized_forces",
                                              "constraint_jacobian", "constraint_bias",
                                              "forward_acceleration"}
    assert all(c["model"] == "thesis-disc" and c["passed"] for c in terms)
    text = (out / "report.md").read_text()
    assert "## Reference vs Kane, term by term" in text   # its declared label
    assert "| thesis | - | - | - | not run | not run on this model: engine 'kane'" in text
    assert "supports the front-contact models disc" in text


def test_quick_runs_exudyn_on_one_benchmark_manoeuvre_and_says_so(report):
    """--quick judges all three IFToMM manoeuvres on the reference, runs Exudyn on
    benchmark-v4.6 only, and names the other two where a reader looks for them. Planted: the
    benchmark stage passing the quick runs to every manoeuvre again fails the first
    assertion."""
    out, summary = report
    exudyn = {c["scenario"] for c in summary["comparisons"]
              if c["quantity"] == "trajectory (benchmark)"}
    assert exudyn == {"benchmark-v4.6"}
    physics = {c["scenario"] for c in summary["comparisons"]
               if c["quantity"].startswith("outcome:") and c["engines"] == ["reference"]}
    assert physics == {"benchmark-v4", "benchmark-v4.6", "benchmark-v8"}
    text = (out / "report.md").read_text()
    assert ("Run on the reference only (`--quick`: the engines run benchmark-v4.6): "
            "benchmark-v4, benchmark-v8.") in text


def test_figure_policy_names_what_it_does_not_draw():
    """--figures failing keeps a failing section's figures and replaces a passing section's by
    one line naming every one of them; none replaces them all. Planted: testing ``passed is
    not True`` (a reported row counts as failing) keeps the passing section's figures."""
    from comparisons.stages.pipeline import apply_figure_policy
    from comparisons.stages.results import Figure, Section

    def section(passed):
        sec = Section("s")
        sec.text("before")
        sec.figure("a.png", "convergence")
        sec.figure("b.png", "convergence")
        sec.text("after")
        sec.comparisons += [{"passed": passed}, {"passed": None}]
        return sec

    assert apply_figure_policy(section(False), "failing").figures != []
    assert len(apply_figure_policy(section(True), "all").figures) == 2
    for policy in ("failing", "none"):
        out = apply_figure_policy(section(True), policy)
        assert out.figures == [] and len(out.blocks) == 3
        assert "`a.png`, `b.png`" in out.blocks[1].text and "--figures all" in out.blocks[1].text
    assert apply_figure_policy(section(False), "none").figures == []
    assert not isinstance(apply_figure_policy(section(True), "failing").blocks[1], Figure)
    with pytest.raises(ValueError, match="figure policy 'some': choose one of all, failing, none"):
        apply_figure_policy(section(True), "some")


def test_report_starts_with_the_verdict_then_claims_then_summary(report):
    """First screen: the verdict, then (no failures here) the claims, then the summary table;
    every figure drawn is linked."""
    out, _ = report
    text = (out / "report.md").read_text()
    headings = re.findall(r"^## (.*)$", text, flags=re.M)
    assert text.splitlines()[2].startswith("**All judged comparisons are within tolerance")
    assert headings[0].startswith("The thesis's claims") and headings[1].startswith("Summary")
    assert "Where the engines disagree" not in text   # nothing to localize when all agree
    for png in (out / "figures").glob("*.png"):
        assert f"figures/{png.name}" in text
    assert "Initial state" in text and "beta corrected by" in text


def test_html_is_self_contained(report):
    out, _ = report
    html = (out / "report.html").read_text()
    srcs = re.findall(r'src="([^"]+)"', html)
    assert srcs and all(s.startswith("data:image/png;base64,") for s in srcs)
    assert len(srcs) == len(list((out / "figures").glob("*.png")))
    assert "<table>" in html and "<link" not in html




def _short_forward(folder: Path) -> Path:
    """stability-psid10 cut to its first 0.5 s, as a scenario file (same format as the
    built-ins): every engine still runs it forward, in a third of the time."""
    from reference_model.scenario_files import BUILTIN_DIR
    text = (BUILTIN_DIR / "stability-psid10.toml").read_text(encoding="utf-8")
    text = re.sub(r'(?m)^name = "stability-psid10"$', 'name = "psid10-short"', text)
    text = re.sub(r"(?m)^samples = 629$", "samples = 51", text)
    text = re.sub(r"(?m)^claim = .*$", "", text)   # the claim is about the whole run
    assert "psid10-short" in text and "samples = 51" in text
    path = folder / "psid10-short.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.slow
def test_same_inputs_give_the_same_report(tmp_path):
    """Determinism: two runs of a small subset (every engine, an inverse and a forward
    scenario, in worker processes finishing in any order) write byte-identical summary.json,
    report.md and figures; run times live only in timings.json."""
    a, b = tmp_path / "a", tmp_path / "b"
    small = ["run", "--quick", "--scenarios", "check", "--scenario-file",
             str(_short_forward(tmp_path)), "--sections", "none", "--figures", "all"]
    assert main([*small, "--jobs", "2", "--out", str(a)]) == 0
    assert main([*small, "--jobs", "1", "--out", str(b)]) == 0
    assert len(list((a / "figures").iterdir())) >= 3
    for name in ["summary.json", "report.md"] + [f"figures/{p.name}" for p in (a / "figures").iterdir()]:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    assert "seconds" not in (a / "summary.json").read_text()


@pytest.mark.slow
def test_a_tolerance_too_tight_fails_the_run_with_exit_1(tmp_path):
    """A tolerance is a claim: tighten the mass matrix's below round-off and the run must fail."""
    from comparisons.judgments.tolerances import TOLERANCES_FILE
    tight = tmp_path / "tight.toml"
    tight.write_text(TOLERANCES_FILE.read_text().replace(
        "[mass_matrix]\ntolerance = 1e-12", "[mass_matrix]\ntolerance = 1e-19"))
    out = tmp_path / "r"
    assert main(["run", "--quick", "--scenarios", "zigzag", "--engines", "reference,pinocchio",
                 "--sections", "none", "--tolerances", str(tight), "--out", str(out)]) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["passed"] is False
    assert any(c["quantity"] == "mass_matrix" and c["passed"] is False for c in summary["comparisons"])
    text = (out / "report.md").read_text()
    assert "## Where the engines disagree" in text
    # --quick draws the figures of the sections where something failed: here, the scenarios'
    assert summary["figures"] == "failing"
    assert (out / "figures" / "zigzag_torques.png").is_file() and "Not drawn" not in text


@pytest.mark.slow
def test_the_workers_judge_by_the_given_tolerances(tmp_path, failing_tolerances):
    """--tolerances reaches the stages in worker processes as a value in their arguments: with
    every tolerance at 1e-300 (any round-off difference fails it) every judged comparison of
    Pinocchio's term-by-term stage (a worker's) and of the scenarios (the main process's)
    fails. Two workers, one inverse scenario, 50 states: ~4 s."""
    failing = failing_tolerances
    out = tmp_path / "r"
    assert main(["run", "--quick", "--scenarios", "check", "--engines", "reference,pinocchio",
                 "--sections", "terms", "--jobs", "2", "--figures", "none", "--no-html",
                 "--no-data", "--tolerances", str(failing), "--out", str(out)]) == 1
    comps = json.loads((out / "summary.json").read_text())["comparisons"]
    terms = [c for c in comps if c["scenario"].startswith("random-states")]
    assert len(terms) >= 7 and all(c["passed"] is False for c in terms), terms
    judged = [c for c in comps if c.get("tolerance") is not None]
    assert all(c["tolerance"] == 1e-300 for c in judged)
    assert all(c["passed"] is False for c in judged if c["max_error"]), \
        [c for c in judged if c["passed"] is not False]


def test_every_stage_is_given_the_runs_tolerances():
    """Every stage function with a ``tolerances`` parameter gets ``Options.tolerances`` itself
    as its first argument, in the thesis's full run and in a --model run (planted: one stage
    built without it fails this)."""
    import dataclasses
    import inspect

    from comparisons.judgments.tolerances import Tolerances, load_tolerances
    from comparisons.stages.cases import build_cases, model_spec
    from comparisons.stages.pipeline import Options, _stage_tasks, select
    from comparisons.stages.runs import setups_for
    from comparisons.stages.stage import Plan
    from engines.facts import engine_facts
    mine = Tolerances(tuple(dataclasses.replace(t, tolerance=t.tolerance / 2)
                            for t in load_tolerances().values()), "mine")
    base = select(None, False, None)
    runs = [Options(base.scenarios, base.engines, tolerances=mine),
            Options(base.scenarios, base.engines, True, models=(model_spec("benchmark"),),
                    tolerances=mine)]
    given = set()
    for opts in runs:
        cases, _ = build_cases(opts.scenarios, opts.models, ())
        plan = Plan(opts, tuple(setups_for(opts.engines)),
                    {e: engine_facts(e) for e in opts.engines}, tuple(cases), {})
        for t in _stage_tasks(plan):
            if "tolerances" in inspect.signature(t.func).parameters:
                assert t.args[0] is mine, t.label
                given.add(t.func.__name__)
    assert {"engine_terms", "fault_entries", "benchmark_terms", "linear_check"} <= given


@pytest.mark.parametrize("args, needle", [
    (["--engines", "reference,bullet"], "unknown engine 'bullet'"),
    (["--scenarios", "zigzag,nope"], "unknown scenario 'nope'"),
    (["--jobs", "0"], "--jobs must be between 1 and 8"),
    (["--jobs", "64"], "--jobs must be between 1 and 8"),
    (["--tolerances", "/nonexistent.toml"], "--tolerances: no file"),
])
def test_usage_errors_exit_2_with_one_line(tmp_path, capsys, args, needle):
    assert main(["run", *args, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0]


def test_summary_table_groups_by_quantity_and_pair():
    comps = [
        {"quantity": "M", "scenario": "a", "engines": ["r", "p"], "max_error": 1e-15, "tolerance": 1e-12, "passed": True},
        {"quantity": "M", "scenario": "b", "engines": ["r", "p"], "max_error": 2e-12, "tolerance": 1e-12, "passed": False},
        {"quantity": "M", "scenario": "a", "engines": ["r", "e"], "max_error": 3e-3, "tolerance": None, "passed": None},
    ]
    rows = {(r["quantity"], r["engines"]): r for r in summary_table(comps)}
    assert rows[("M", "r vs p")]["max_error"] == 2e-12 and rows[("M", "r vs p")]["verdict"] == "FAIL (1 of 2)"
    assert rows[("M", "r vs e")]["verdict"] == "reported"
