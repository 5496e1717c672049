"""`run_comparison` (comparisons/stages/pipeline.py): what it hands to the parts it calls, what
it writes into summary.json and timings.json, its progress line, and the text of *Models of
this run*; a complement to tests/test_pipeline_parts.py, with its stand-in stages and plugins.

The contract: the module's docstrings (every stage gets the run's Plan; the thesis's claims are
judged on the thesis's scenarios only; the meaningful horizon of each forward scenario; run
times kept apart), `stage.Stage` (assemble and revise_claims get the plan and the stage's own
results), docs/report.md ("Your own bicycle": what *Models of this run* says; `--stage-timeout`;
the exit-status table: one stage's failed assembly fails alone) and `engines.runs.Run`'s
fields. One recorded run, check and benchmark-v4 (a forward scenario whose trajectory is
compared: it has a meaningful horizon) on ``--model benchmark`` and ``--model thesis``, the
reference only, with the worker pool's times and the process clock replaced by known values,
so every rounding is checked against a hand-computed number. Each test names the bugs planted
by hand (in a copy of the module, one at a time) it was seen failing on.
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import pytest

from comparisons.stages import faults as faults_module
from comparisons.stages import pipeline, pool
from comparisons.stages import runs as runs_module
from comparisons.stages import scenarios as scenarios_module
from comparisons.stages import soft_contact
from comparisons.stages.cases import NotRun, model_spec
from comparisons.stages.pipeline import Options, run_comparison, select
from comparisons.stages.pool import Task
from comparisons.stages.results import Section, Table
from comparisons.stages.stage import Assembled, Plan, Stage
from engines.runs import Run
from test_pipeline_parts import _row, _run_with, _spec, cheap_pool  # noqa: F401 - a fixture

#: the process clock run_comparison reads, in order: its start, the judging's start and end,
#: the end (s)
CLOCK = (100.0, 102.0, 102.1234567, 103.9876543)
#: the seconds the pool reports for the i-th task (and its Run, when it is one)
SECONDS = 0.1234567


class _Spy(Stage):
    """A stage recording the plan (and results) each call gets; ``make`` builds its part."""

    def __init__(self, name, section=None, tasks=(), make=None):
        self.name, self.section, self._tasks, self.make = name, section, list(tasks), make
        self.calls = []

    def tasks(self, plan):
        self.calls.append(("tasks", plan))
        return list(self._tasks)

    def assemble(self, plan, results):
        self.calls.append(("assemble", plan, dict(results)))
        return self.make(plan, results) if self.make else Assembled()

    def revise_claims(self, plan, results, claims):
        self.calls.append(("revise", plan, dict(results)))
        return claims


def _section(title, faults):
    def make(plan, results):
        sec = Section(title)
        sec.comparisons.append(_row("check", True))
        return Assembled([sec], faults)
    return make


def _raising(plan, results):
    raise RuntimeError("assembly broke")


@pytest.fixture(scope="module")
def recorded():
    """check and benchmark-v4 on --model benchmark and --model thesis, the reference only,
    --stage-timeout 7.5, --jobs not given; stages: spy (one task, faults localized), broken
    (its assembly raises), last (faults not observable)."""
    mp = pytest.MonkeyPatch()
    seen = SimpleNamespace(isolated=[], compare=[], localize=[], claims=[])
    spy = _Spy("spy", tasks=[Task("one", divmod, (7, 2), 0.1, "spy one")],
               make=_section("Spy", [{"engine": "reference", "verdict": "localized"}]))
    broken = _Spy("broken", make=_raising)
    last = _Spy("last", make=_section("Last", [{"engine": "reference",
                                                "verdict": "not observable"}]))

    def run(tasks, workers=None, progress=lambda s: None, limits=None):
        done = pool.run_tasks(tasks, 1, progress, warm=(), limits=limits)
        for i, t in enumerate(tasks):
            r = done[t.key]
            r.seconds = SECONDS + i
            if isinstance(r.value, Run):
                r.value = dataclasses.replace(r.value, seconds=SECONDS + 10 + i)
        return done

    def isolated(setup, *args):
        seen.isolated.append((setup.label, args))
        return setup

    def compare(*args):
        seen.compare.append(args)
        return real_compare(*args)

    def localize(*args):
        seen.localize.append(args)
        return real_localize(*args)

    def claims(*args):
        seen.claims.append(args)
        return real_claims(*args)

    real_compare = scenarios_module.compare_scenarios
    real_localize = faults_module.localization_lines
    real_claims = pipeline.judge_claims
    clock = iter(CLOCK)
    mp.setattr(pipeline, "STAGES", (spy, broken, last))
    mp.setattr(pipeline, "run_tasks", run)
    mp.setattr(pipeline, "isolated", isolated)
    mp.setattr(pipeline, "judge_claims", claims)
    mp.setattr(pipeline, "time", SimpleNamespace(perf_counter=lambda: next(clock)))
    mp.setattr(scenarios_module, "compare_scenarios", compare)
    mp.setattr(faults_module, "localization_lines", localize)
    try:
        opts = dataclasses.replace(select("check,benchmark-v4", False, "reference"),
                                   stage_timeout=7.5,
                                   models=(model_spec("benchmark"), model_spec("thesis")))
        said = []
        result = run_comparison(opts, said.append)
    finally:
        mp.undo()
    return SimpleNamespace(result=result, said=said, seen=seen, opts=opts, spy=spy,
                           broken=broken, last=last)


def test_every_stage_gets_the_run_s_plan(recorded):
    """stage.Plan's docstring: what every stage reads is the run's options, its engine setups,
    the facts of each engine, the cases and each --model's critical speeds (the benchmark's
    weave and capsize speeds, 4.2924 and 6.0243 m/s, Meijaard et al. 2007); the same plan
    goes to tasks, assemble and revise_claims. Planted: the stage's tasks asked with no plan;
    the plan built without its setups, without its cases, without the critical speeds, or
    with the critical speeds in place of the cases; assemble or revise_claims given no
    plan."""
    calls = recorded.spy.calls
    assert [c[0] for c in calls] == ["tasks", "assemble", "revise"]
    plan = calls[0][1]
    assert isinstance(plan, Plan)
    assert all(c[1] is plan for c in calls)
    assert plan.opts is recorded.opts
    assert [s.label for s in plan.setups] == ["reference"] and isinstance(plan.setups, tuple)
    assert [(c.name, c.model) for c in plan.cases] == [
        ("check-on-benchmark", "benchmark"), ("benchmark-v4", "benchmark"),
        ("check", "thesis")]
    (spec,) = plan.critical
    assert plan.critical[spec]["weave"] == pytest.approx(4.2924, abs=1e-4)
    assert plan.critical[spec]["capsize"] == pytest.approx(6.0243, abs=1e-4)


def test_assemble_and_revise_claims_get_the_stage_s_own_results(recorded):
    """stage.Stage: assemble and revise_claims get the stage's results keyed as it gave them.
    Planted: revise_claims given no results."""
    _, (_, _, assembled), (_, _, revised) = recorded.spy.calls
    assert set(assembled) == {"one"} and assembled["one"].value == (3, 1)
    assert set(revised) == {"one"} and revised["one"].value == (3, 1)


def test_a_failed_assembly_fails_alone_and_every_stage_s_faults_are_kept(recorded):
    """docs/report.md's exit-status table: a stage that raises fails alone, every other
    engine's (and stage's) results are kept: the stage after it is still assembled, and the
    fault rows of every stage are listed. Planted: the stages after a failed assembly
    skipped (break for continue); each stage's fault rows replacing the previous ones."""
    r = recorded.result
    assert [c[0] for c in recorded.last.calls] == ["tasks", "assemble", "revise"]
    titles = [s.title for s in r.sections]
    assert titles[-3:] == ["Spy", "broken: assembling its section", "Last"]
    assert [f["verdict"] for f in r.summary["faults"]] == ["localized", "not observable"]


def test_forward_scenarios_are_judged_up_to_their_meaningful_horizon(recorded):
    """Module docstring: the meaningful horizon of each forward scenario (two reference runs
    1e-9 rad/s apart) is computed and given to the scenarios' comparisons: benchmark-v4 is
    forward and its trajectory is compared, check is inverse (no horizon). A horizon is a
    time within the scenario's grid (0 to 5 s). Planted: the horizons not given (None); the
    task's key misspelt where it is looked up; only the horizons whose task failed kept."""
    (args,) = recorded.seen.compare
    horizons = args[4]
    assert set(horizons) == {"benchmark-v4"}
    t0, dt, n = scenarios_module.get_scenario("benchmark-v4").grid
    assert t0 < horizons["benchmark-v4"].t <= t0 + (n - 1) * dt


def test_the_scenarios_are_judged_by_the_run_s_tolerances_and_setups(recorded):
    """Options: --tolerances is read once and given as a value to every judgment; an engine's
    calls in the main process run in a worker with --stage-timeout's limit (docs/report.md:
    "`--stage-timeout S` gives every stage the same limit"). Planted: the scenarios judged
    with no tolerances; each setup isolated without the stage limit."""
    (args,) = recorded.seen.compare
    assert args[0] is recorded.opts.tolerances
    assert list(args[1]) == ["check-on-benchmark", "benchmark-v4", "check"]
    assert recorded.seen.isolated == [("reference", (7.5,))]


def test_localization_gets_the_tolerances_setups_and_the_models_specs(recorded):
    """faults.localization_lines(tolerances, comparisons, setups, specs): the run's
    tolerances, the isolated setups by label, and each --model's spec by its name (a user's
    file is found by its path). Planted: no tolerances; no setups; the specs dropped or given
    in place of the setups."""
    (args,) = recorded.seen.localize
    assert len(args) == 4
    tolerances, _, setups, specs = args
    assert tolerances is recorded.opts.tolerances
    assert list(setups) == ["reference"]
    assert specs == {m.name: m.spec for m in recorded.opts.models}
    assert set(specs) == {"benchmark", "thesis"}


def test_the_claims_are_judged_on_the_thesis_s_scenarios_only(recorded, monkeypatch,
                                                               cheap_pool):
    """Module docstring and docs/report.md: with --model, the thesis's claims are judged only
    on the thesis's scenarios, i.e. those asked for by name that run on model thesis (here
    check, not benchmark-v4 on the benchmark); without --model every scenario asked for is
    given to the claims (benchmark-v4 included, on the benchmark bicycle). Planted: a scenario kept when asked for OR on the thesis model;
    the thesis-only selection used without --model too."""
    ((_, labels, _, selected),) = recorded.seen.claims
    assert labels == ["reference"] and list(selected) == ["check"]
    seen = []
    real = pipeline.judge_claims
    monkeypatch.setattr(pipeline, "judge_claims", lambda *a: seen.append(a) or real(*a))
    r = _run_with(monkeypatch, scenarios="check,benchmark-v4", models=())
    assert [list(a[3]) for a in seen] == [["check", "benchmark-v4"]]
    assert r.summary["claims"]


def test_the_models_section_lists_what_was_not_run(recorded):
    """docs/report.md, "Your own bicycle": *Models of this run* lists the scenarios not run on
    a model, each with its reason (the IFToMM manoeuvres are written for the benchmark
    bicycle's critical speeds). Planted: the not-run list not given to the section."""
    sec = recorded.result.sections[0]
    assert sec.title == "Models of this run"
    table = sec.blocks[2]
    assert table.header == ("scenario", "model", "not run because")
    assert [row[:2] for row in table.rows] == [("benchmark-v4", "thesis")]
    assert "benchmark bicycle's critical speeds" in table.rows[0][2]


def test_summary_environment_is_of_the_run_s_plan(monkeypatch, cheap_pool):
    """summary.json's environment is the run's: a --quick run's soft-contact window is
    --quick's (here set apart from the full run's to tell them apart). Planted: the
    environment written without the plan (a full run's window)."""
    monkeypatch.setattr(soft_contact, "QUICK_WINDOW", 0.25)
    r = _run_with(monkeypatch, quick=True)
    assert r.summary["environment"]["steps"]["soft_contact_study"]["window_s"] == 0.25


def test_environment_window_follows_the_plan_s_quick_flag(monkeypatch):
    """environment(): the soft-contact study's window of a quick run with a quick plan, of a
    full run without a plan (soft_contact.window). Planted: the window asked with no flag;
    a missing plan taken as quick."""
    monkeypatch.setattr(soft_contact, "QUICK_WINDOW", 0.25)
    monkeypatch.setattr(soft_contact, "WINDOW", 0.75)
    monkeypatch.setattr(pipeline, "_cpu", lambda: "a CPU")
    monkeypatch.setattr(pipeline, "_versions", lambda modules=(): {})
    study = lambda env: env["steps"]["soft_contact_study"]["window_s"]   # noqa: E731
    assert study(pipeline.environment([])) == 0.75
    assert study(pipeline.environment([], Plan(SimpleNamespace(quick=True), (), {}))) == 0.25
    assert study(pipeline.environment([], Plan(SimpleNamespace(quick=False), (), {}))) == 0.75


def test_environment_names_the_platform_tersely_and_where_the_times_are(monkeypatch):
    """environment(): the platform in its terse form (system and release: what the numbers
    depend on, not the C library's build), and run_times says the times are in timings.json,
    kept apart (docs/report.md: timings.json is kept out of the report so that two
    identical runs give byte-identical reports). Planted: the platform's long form."""
    monkeypatch.setattr(pipeline, "_cpu", lambda: "a CPU")
    monkeypatch.setattr(pipeline, "_versions", lambda modules=(): {})
    monkeypatch.setattr(pipeline.platform, "platform",
                        lambda aliased=False, terse=False: "terse" if terse is True else "long")
    env = pipeline.environment([])
    assert env["machine"]["platform"] == "terse"
    assert env["run_times"] == "timings.json (kept apart: they vary from run to run)"


def test_timings_are_seconds_to_the_millisecond(recorded):
    """timings.json: each stage, the judging, each engine run and the total in seconds,
    rounded to the millisecond (here from known pool times, 0.1234567 s plus the task's
    index, and clock readings: the judging 102.1234567 - 102.0, the total 103.9876543 - 100.0). Planted: the rounding to 4 digits
    or to a whole second anywhere; the total the sum of the clock readings."""
    t = recorded.result.timings
    # the pool's i-th task took SECONDS + i s; the three runs (tasks 0-2) SECONDS + 10 + i
    assert sorted(t["stages"].values()) == [0.123, 1.123, 2.123, 3.123, 4.123]
    assert all(isinstance(v, float) for v in t["stages"].values())
    assert t["judging in the main process"] == 0.123
    assert t["total_seconds"] == 3.988
    runs = t["engine_run_seconds"]
    assert runs == {"check-on-benchmark on reference": 10.123,
                    "benchmark-v4 on reference": 11.123, "check on reference": 12.123}
    assert all(isinstance(v, float) for v in runs.values())


def test_the_progress_line_says_all_workers_when_jobs_is_not_given(recorded):
    """Without --jobs the pool uses every core: the line says 'all'. Planted: the word
    changed."""
    # three runs, benchmark-v4's horizon and the spy's task
    assert recorded.said[0] == ("5 stages on all worker(s): 3 scenario(s) on reference, the "
                                "stability of 1 model(s) ...")


def test_a_failed_run_is_a_run_of_unknown_model_and_kind_and_no_time(monkeypatch, cheap_pool):
    """A run whose task raised is a Run (engines.runs) with its engine and scenario, model and
    kind '-' (not known: the run never started), status 'failed', the error as its message
    and no run time; summary.json's engine_runs gives its message. Planted: the kind None or
    another word; the run time 1 s."""
    def broken_run(setup, scenario, model=None):
        raise RuntimeError("the solver gave up")
    monkeypatch.setattr(runs_module, "run_one", broken_run)
    r = _run_with(monkeypatch, scenarios="zigzag")
    run = r.runs[("reference", "zigzag")]
    assert (run.model, run.kind, run.status, run.seconds) == ("-", "-", "failed", 0.0)
    assert r.timings["engine_run_seconds"] == {"zigzag on reference": 0.0}
    (row,) = r.summary["engine_runs"]
    assert set(row) == {"engine", "scenario", "model", "status", "t_end", "message"}
    assert row["message"] == run.message and "the solver gave up" in row["message"]


def test_engine_runs_t_end_to_the_microsecond(monkeypatch, cheap_pool):
    """summary.json's engine_runs: t_end (the run's last time) rounded to 1e-6 s (here check's
    grid, 629 times 0.01 s apart, moved by 4.4e-7 s: 6.28). Planted: 7 digits."""
    real = runs_module.run_one

    def shifted(*args):
        run = real(*args)
        return dataclasses.replace(run, t=run.t + 4.4e-7)
    monkeypatch.setattr(runs_module, "run_one", shifted)
    r = _run_with(monkeypatch, scenarios="check")
    t0, dt, n = scenarios_module.get_scenario("check").grid
    assert r.summary["engine_runs"][0]["t_end"] == round(t0 + (n - 1) * dt, 6) == 6.28


#: docs/report.md, "Your own bicycle", sentence by sentence as the section says it
MODELS_TEXT = (
    # "The thesis's scenarios run on a model as `<scenario>-on-<model>`; their initial states
    # are re-made for its geometry (the corrections are listed with the reference's runs"
    "Every built-in scenario that makes sense for a bicycle runs on each model as "
    "`<scenario>-on-<model>`; initial states written for the thesis geometry are made "
    "consistent for the model's (the corrections are listed with the reference's runs). "
    # "the replay's and check-forward's torques are the model's own inverse dynamics of zigzag
    # and check"
    "The replay and check-forward torques are the model's own inverse dynamics of zigzag and "
    "check, fed forward. "
    # "The thesis's claims are judged only on the thesis's scenarios."
    "The thesis's claims are about the thesis bicycle: they are judged only on the thesis's "
    "scenarios (model `thesis`). "
    # "Every engine section then runs on each model": term by term at random states, the fault
    # injection, convergence, energy drift, contact study, stability runs at its critical
    # speeds, the linearization against the benchmark's closed form
    "Every engine section runs on each model: every engine term by term at random states, "
    "fault injection on that bicycle, the fixed-step engines' convergence order, the energy "
    "drift, the soft-contact engines' study, the eigenvalues with runs at its own critical "
    "speeds and the linearization against the benchmark's closed form (disc contact). "
    # docs/report.md's statuses: 'not run' with the reason, a declared limitation
    "An engine that cannot represent a model says so ('not run on this model', with the "
    "reason): a declared limitation, not a failure.")


def test_the_models_section_says_what_a_model_run_covers():
    """docs/report.md, "Your own bicycle": *Models of this run*'s text after the models'
    table, each sentence one of the documented facts (MODELS_TEXT), each sentence starting
    with a capital. Planted: any sentence's words changed in case or framed by stray
    characters."""
    opts = Options(("check",), ("reference",), models=(_spec("mine"),))
    sec = pipeline._models_section(opts, [NotRun("benchmark-v4", "mine", "why")])
    assert isinstance(sec.blocks[0], Table) and isinstance(sec.blocks[2], Table)
    assert sec.blocks[1].text == MODELS_TEXT
