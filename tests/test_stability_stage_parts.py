"""The stability stage's parts (comparisons/stages/stability.py) held to its docstring and to
Meijaard et al. (2007): the critical speeds and the eigenvalues of the benchmark bicycle against
the paper's Table 2 (weave 4.29238253634111 m/s, capsize 6.02426201538837 m/s; at 0 m/s the
roots +-5.53094371765393 and +-3.13164324790656, at 5 m/s the weave -0.77534188219585
+- 4.46486771378823i, the capsize -0.32286642900409 and the castering -14.07838969279820), the
eigenvalue figure on the 0-10 m/s grid of 0.01 m/s, the run's scenario (upright, the IFToMM
kick of 0.05 rad/s, 5 s on a 0.01 s grid), which setups run (forward runs and no declared
difference; a soft contact's runs reported in a full run), the drag removed before building an
engine, an engine that cannot represent the bicycle said, not failed, and the stage's tasks
and assembly (the section each disc model gets, the reason a thesis-contact model gets none).

No engine runs here: the setups are stand-ins that record what they are given, and the
engines' facts are stand-ins (monkeypatched `engines.facts.engine_facts`). Each test names the
planted bugs (mutmut's survivors of the module's first measurement) it fails on.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import comparisons.stages.stability as st
from comparisons.stages.cases import model_spec
from comparisons.stages.pool import TaskResult
from comparisons.stages.results import Text
from comparisons.stages.stage import Plan

#: Meijaard et al. (2007), Table 2 (the benchmark bicycle)
WEAVE = 4.29238253634111        # m/s
CAPSIZE = 6.02426201538837      # m/s
AT_0 = (5.53094371765393, 3.13164324790656, -3.13164324790656, -5.53094371765393)
AT_5 = (complex(-0.77534188219585, 4.46486771378823), complex(-0.77534188219585, -4.46486771378823),
        complex(-0.32286642900409, 0.0), complex(-14.07838969279820, 0.0))


def _facts(**engines):
    """engine_facts stand-in: engine -> (run_difference, soft_contact, run_per_second)."""
    table = {name: SimpleNamespace(run_difference=d, soft_contact=s,
                                   costs=SimpleNamespace(run_per_second=c))
             for name, (d, s, c) in engines.items()}
    return table.__getitem__, table


FACTS, FACTS_TABLE = _facts(reference=(None, None, 0.5), rigid=(None, None, 2.0),
                            soft=("a soft contact", object(), 3.0),
                            lcp=("an LCP contact", None, 4.0))


@pytest.fixture
def facts(monkeypatch):
    monkeypatch.setattr("engines.facts.engine_facts", FACTS)
    return FACTS_TABLE


def _setup(label, engine, kinds=("inverse", "forward")):
    return SimpleNamespace(label=label, engine=engine, kinds=kinds)


# -- the model, its critical speeds and its eigenvalue curves -------------------------------------

def test_the_critical_speeds_are_meijaards_and_only_those_found_are_named(monkeypatch):
    """critical('benchmark'): Table 2's weave and capsize speeds, by name, in that order; over
    a range holding only the weave speed, only it (no None entry). Planted: the dict filter
    inverted; the names swapped."""
    crit = st.critical("benchmark")
    assert list(crit) == ["weave", "capsize"]
    assert crit["weave"] == pytest.approx(WEAVE, rel=0, abs=1e-9)
    assert crit["capsize"] == pytest.approx(CAPSIZE, rel=0, abs=1e-9)
    monkeypatch.setattr(st, "SPEED_RANGE", (0.0, 5.0))
    only = st.critical("benchmark")
    assert list(only) == ["weave"] and only["weave"] == pytest.approx(WEAVE, abs=1e-9)


def test_the_speed_range_and_grid_are_the_documented_ones():
    """The critical speeds are looked for over 0-10 m/s (docs/report.md, docs/engines.md), the
    figure drawn on a 0.01 m/s grid, runs at 0.9 and 1.1 x, the 0.05 rad/s kick, 0:0.01:5 s
    (module docstring)."""
    assert st.SPEED_RANGE == (0.0, 10.0) and st.SPEED_STEP == 0.01
    assert st.FACTORS == (0.9, 1.1) and st.ROLL_RATE == 0.05
    assert st.GRID == (0.0, 0.01, 501)


def test_the_eigenvalue_curves_are_table_2_on_the_0_01_grid(monkeypatch):
    """stability_curves('benchmark'): speeds 0, 0.01, ..., 10 m/s (1001 of them, 10 included),
    the four eigenvalues at 0 and 5 m/s those of Table 2, the critical speeds Table 2's and the
    model's name; over a range 1-5 m/s, 1, 1.01, ..., 5 m/s (401 speeds) holding the weave
    speed only. Planted: the grid one short of 10 m/s or off by a step; the step or the range's
    ends changed; the number of steps counted from hi + lo."""
    c = st.stability_curves("benchmark")
    assert c["v"].shape == (1001,)
    np.testing.assert_allclose(c["v"], np.arange(1001) / 100.0, rtol=0, atol=1e-12)
    assert c["v"][0] == 0.0 and c["v"][-1] == pytest.approx(10.0, abs=1e-12)
    np.testing.assert_allclose(np.sort(c["re"][0]), np.sort(AT_0), rtol=0, atol=1e-8)
    np.testing.assert_allclose(c["im"][0], 0.0, atol=1e-8)
    at5 = c["re"][500] + 1j * c["im"][500]
    assert c["v"][500] == pytest.approx(5.0, abs=1e-12)
    for want in AT_5:
        assert np.min(np.abs(at5 - want)) < 1e-8, (want, at5)
    assert c["weave"] == pytest.approx(WEAVE, abs=1e-9)
    assert c["capsize"] == pytest.approx(CAPSIZE, abs=1e-9)
    assert c["model"] == "benchmark"
    monkeypatch.setattr(st, "SPEED_RANGE", (1.0, 5.0))
    part = st.stability_curves("benchmark")
    np.testing.assert_allclose(part["v"], 1.0 + np.arange(401) / 100.0, rtol=0, atol=1e-12)
    assert part["weave"] == pytest.approx(WEAVE, abs=1e-9) and part["capsize"] is None


def test_the_curves_and_critical_speeds_of_a_model_with_drag_are_the_drag_free_ones():
    """thesis-disc has drag: its curves and critical speeds are those of the same model with
    cv = 0 (the eigenvalues of the drag-free model computed here, by the linearization, at
    the grid's speeds). Planted: the curves taken on the model as loaded."""
    from reference_model import load_model
    from reference_model.linearize import eigenvalues
    m = load_model("thesis-disc")
    assert m.params.cv > 0
    free = m.with_params(m.params.replace(cv=0.0))
    c = st.stability_curves("thesis-disc")
    for i in (0, 350, 1000):
        lam = eigenvalues(free, float(c["v"][i]))[:4]
        np.testing.assert_allclose(c["re"][i] + 1j * c["im"][i], lam, rtol=0, atol=1e-9)
    # its weave stays unstable over 0-10 m/s (real part > 0 at every 0.5 m/s past 0, checked on
    # the drag-free linearization above): no critical speed, in the curves or by name
    weave_re = np.array([eigenvalues(free, float(v))[0].real for v in c["v"][50::50]])
    assert (weave_re > 0).all()
    assert (c["weave"], c["capsize"]) == (None, None) and st.critical("thesis-disc") == {}


def test_a_bicycle_without_drag_is_kept_and_one_with_drag_is_said():
    """stability_model: a drag-free model as loaded, with no note; one with drag at cv = 0 and
    the note naming it and its cv (printed with :g) in the documented words. Planted: the note's
    words changed; the drag kept."""
    from reference_model import load_model
    model, note = st.stability_model("benchmark")
    assert note == "" and model.params == load_model("benchmark").params
    cv = load_model("thesis-disc").params.cv
    dragged, note = st.stability_model("thesis-disc")
    assert dragged.params.cv == 0.0
    assert dragged.params.replace(cv=cv) == load_model("thesis-disc").params
    assert note == (f"thesis-disc has drag (cv = {cv:g} kg/m), so no steady upright motion: "
                    "linearized and run with cv = 0")


def test_only_the_disc_contact_gets_the_picture():
    """applies: None for the benchmark's knife-edge disc; for the thesis's contact the reason,
    naming the rim point, the disc and the model to load instead. Planted: the reason's words
    changed; the test inverted."""
    assert st.applies("disc") is None
    why = st.applies("thesis")
    assert why == ("its front contact is the thesis's (rim point along the fork's -z axis), not "
                   "the benchmark's knife-edge disc that the linearization and the critical "
                   "speeds are defined for; load it with contact 'disc' (e.g. the named model "
                   "thesis-disc)")
    assert st.applies("anything else") == why


def test_the_runs_scenario_is_upright_with_the_kick_on_the_iftomm_grid():
    """scenario: named for the speed to 4 decimals, on 0:0.01:5 s, the description saying the
    speed, the kick and 5 s; the wheel rate v / R_rear of the drag-free model. Planted: the grid
    or the description changed."""
    from reference_model import load_model
    sc = st.scenario("benchmark", 4.6)
    assert sc.name == "stability-v4.6000"
    assert sc.grid == (0.0, 0.01, 501)
    assert sc.description == "upright at 4.6000 m/s, roll rate 0.05 rad/s, no torques, 5 s"
    R = load_model("benchmark").params.R_rear
    assert sc.dq_ind0 == (0.05, 4.6 / R, 0.0)
    assert sc.model == "benchmark" and sc.kind == "forward"


# -- which setups run, and how --------------------------------------------------------------------

def test_which_setups_simulate_and_which_are_reported(facts):
    """simulating: forward runs and no declared difference; soft_differing: forward runs of an
    engine with a soft contact, its declared difference; a declared difference without a soft
    contact (an LCP contact) is neither, and an engine without forward runs is neither.
    Planted: 'forward' not required; the difference's test inverted; soft_contact's test
    inverted."""
    assert st.simulating(_setup("r", "reference"))
    assert st.simulating(_setup("g", "rigid", ("forward",)))
    assert not st.simulating(_setup("g", "rigid", ("inverse",)))
    assert not st.simulating(_setup("s", "soft"))
    assert st.soft_differing(_setup("s", "soft")) == "a soft contact"
    assert st.soft_differing(_setup("s", "soft", ("inverse",))) is None
    assert st.soft_differing(_setup("g", "rigid")) is None
    assert st.soft_differing(_setup("l", "lcp")) is None
    assert not st.simulating(_setup("l", "lcp"))


class _Recorder:
    """A setup whose engine records the model it was built from and the scenario it ran."""

    def __init__(self, error=None):
        self.built, self.ran, self.error = [], [], error

    def build(self, model):
        if self.error is not None:
            raise self.error
        self.built.append(model)
        outer = self

        class Engine:
            def simulate(self, scenario):
                outer.ran.append(scenario)
                return "the trajectory"
        return Engine()


def test_a_run_is_the_drag_free_models_on_its_scenario():
    """stability_run builds the setup's engine from the model with cv = 0 and simulates
    scenario(spec, speed); differing_run does the same. Planted: the engine built from the model
    as loaded (with drag); another speed's scenario."""
    rec = _Recorder()
    assert st.stability_run("thesis-disc", rec, 4.6) == "the trajectory"
    (model,) = rec.built
    assert model.params.cv == 0.0 and model.name == "thesis-disc"
    assert rec.ran == [st.scenario("thesis-disc", 4.6)]
    rec2 = _Recorder()
    assert st.differing_run("thesis-disc", rec2, 5.5) == "the trajectory"
    assert rec2.ran == [st.scenario("thesis-disc", 5.5)] and rec2.built[0].params.cv == 0.0


def test_an_engine_that_cannot_represent_the_bicycle_is_said_not_failed():
    """differing_run: UnsupportedModel (a declared limitation) becomes 'not run on this model:
    <reason>'; another error is raised. Planted: the words changed; the reason dropped."""
    from engines import UnsupportedModel
    rec = _Recorder(UnsupportedModel("no disc contact here"))
    assert st.differing_run("benchmark", rec, 4.0) == "not run on this model: no disc contact here"
    with pytest.raises(RuntimeError, match="boom"):
        st.differing_run("benchmark", _Recorder(RuntimeError("boom")), 4.0)


# -- the stage ------------------------------------------------------------------------------------

#: the planned critical speeds of the benchmark (round numbers: the runs at 3.6, 4.4, 5.4, 6.6)
CRIT = {"weave": 4.0, "capsize": 6.0}
SETUPS = (_setup("reference", "reference"), _setup("soft", "soft"), _setup("lcp", "lcp"),
          _setup("inv", "rigid", ("inverse",)))


def _plan(quick, setups, models=("benchmark",)):
    ms = tuple(model_spec(m) for m in models)
    return Plan(opts=SimpleNamespace(models=ms, quick=quick), setups=tuple(setups),
                facts={s.engine: FACTS(s.engine) for s in setups}, critical={"benchmark": CRIT})


def test_the_stage_runs_soft_contacts_in_a_full_run_only(facts):
    """tasks: each run on a simulating setup is stability_run; a soft contact's is differing_run
    in a full run and absent in a quick one; an LCP contact's and an inverse-only setup's never;
    each run costs 5 s at its engine's cost per simulated second; the stage is 'stability',
    always selected. Planted: the quick test inverted; differing_run for every setup; the 5 s
    changed."""
    assert (st.StabilityStage.name, st.StabilityStage.section) == ("stability", None)
    full = st.StabilityStage().tasks(_plan(False, SETUPS))
    assert full[0].key == ("curves", "benchmark") and full[0].func is st.stability_curves
    runs = full[1:]
    want = [(mode, f * v, lab) for mode, v in CRIT.items() for f in (0.9, 1.1)
            for lab in ("reference", "soft")]
    assert [t.key[2:] for t in runs] == want
    assert [t.func for t in runs] == [st.stability_run, st.differing_run] * 4
    assert [t.cost for t in runs] == [2.5, 15.0] * 4
    assert [t.engine for t in runs] == [None, "soft"] * 4
    assert [t.args for t in runs[:2]] == [("benchmark", SETUPS[0], 3.6),
                                          ("benchmark", SETUPS[1], 3.6)]
    quick = st.StabilityStage().tasks(_plan(True, SETUPS))
    assert [t.key[2:] for t in quick[1:]] == [k for k in want if k[2] == "reference"]
    assert all(t.func is st.stability_run for t in quick[1:])


def _results(curves_error=None):
    out = {("curves", "benchmark"): TaskResult(("curves", "benchmark"), "the curves", 0.1,
                                               curves_error)}
    out[("run", "benchmark", "weave", 3.6, "reference")] = TaskResult(None, "traj r", 0.1)
    out[("run", "benchmark", "weave", 3.6, "soft")] = TaskResult(None, "traj s", 0.1)
    out[("run", "benchmark", "capsize", 5.4, "reference")] = TaskResult(None, None, 0.1, "boom")
    out[("run", "other", "weave", 3.6, "reference")] = TaskResult(None, "not this model", 0.1)
    out[("curves", "other")] = TaskResult(None, "not these", 0.1)
    return out


def test_the_stage_assembles_each_models_runs_and_errors(facts, monkeypatch):
    """assemble: for a disc model, stability_section with its critical speeds, its curves (None
    when their task failed), its runs' values and its runs' errors keyed (mode, speed, label),
    the simulating setups' labels then the soft ones in the setups' order, and the soft
    contacts' declared differences (none in a quick run, their labels dropped); another model's
    results are not its. A thesis-contact model gets a section saying why it is not computed.
    Planted: errors and values swapped; the curves' error ignored; another model's runs taken;
    the quick test inverted."""
    seen = []
    monkeypatch.setattr(st, "stability_section",
                        lambda *a: seen.append(a) or st.Section(f"section {len(seen)}"))
    plan = _plan(False, SETUPS, models=("thesis", "benchmark"))
    out = st.StabilityStage().assemble(plan, _results())
    first, second = out.sections
    assert first.title.startswith("Stability of thesis (")
    assert [b.text for b in first.blocks if isinstance(b, Text)] == [
        f"Not computed: {st.applies('thesis')}."]
    assert second.title == "section 1"
    (args,) = seen
    m, crit, curves, runs, errors, labels, differences = args
    assert (m.spec, crit, curves) == ("benchmark", CRIT, "the curves")
    assert runs == {("weave", 3.6, "reference"): "traj r", ("weave", 3.6, "soft"): "traj s"}
    assert errors == {("capsize", 5.4, "reference"): "boom"}
    assert labels == ("reference", "soft")
    assert differences == {"soft": "a soft contact"}
    seen.clear()
    quick = _plan(True, SETUPS, models=("benchmark",))
    st.StabilityStage().assemble(quick, _results(curves_error="it failed"))
    (args,) = seen
    assert args[2] is None and args[5] == ("reference",) and args[6] == {}


# -- the judge's rule ------------------------------------------------------------------------------

def _done(status="completed"):
    """What judge_run reads of a run besides its measurement: the status and the end time."""
    return SimpleNamespace(status=status, t_end=5.0)


def test_at_the_weave_speed_the_capsize_prediction_is_the_slow_real_root(monkeypatch):
    """At Table 2's weave speed the weave's real part is zero (the definition of that speed),
    closer to zero than the capsize root there (about -0.98 /s; the capsize decays below its
    speed): judge_run's capsize prediction is the closed form's slower real root (Meijaard's
    closed form, comparisons.judgments.meijaard, written from the paper), not the weave's ~0.
    The run's matrix-pencil exponents are stood in for (the measurement is another test's).
    Planted: the real-root filter letting every eigenvalue through (1e-12 -> 1.000000000001;
    the pool always the whole spectrum)."""
    from comparisons.judgments.meijaard import closed_form, closed_form_eigenvalues
    from reference_model.benchmark import to_benchmark
    model, _ = st.stability_model("benchmark")
    lam = closed_form_eigenvalues(closed_form(to_benchmark(model.params)), WEAVE)
    weave = lam[lam.imag > 0][0]
    assert abs(weave.real) < 1e-9                        # the weave speed's definition
    real = lam[lam.imag == 0].real
    slow = real[np.argmin(np.abs(real))]
    assert slow < -0.5                                   # decays below the capsize speed
    fitted = np.array([-0.9 + 0j, -0.01 + 3.4j, -0.01 - 3.4j, -12.0 + 0j])
    monkeypatch.setattr(st, "identify_eigenvalues", lambda traj: fitted)
    j = st.judge_run(model, "capsize", WEAVE, _done())
    assert j["predicted"] == pytest.approx(slow, rel=0, abs=1e-8)
    assert j["expected"] == "decays" and j["measured"] == -0.9 and j["passed"]
    assert j["how"] == ("capsize eigenvalue from the run (matrix pencil) -0.90000000+0.00000000i "
                        "/s; completed at 5.00 s")


@pytest.mark.parametrize("spectrum, slow", [
    # no real root at all: the slowest of the four
    ((-1 + 3j, -1 - 3j, -0.2 + 0.5j, -0.2 - 0.5j), -0.2),
    # an exact zero root is real (imag == 0): the capsize exactly at its speed
    ((-1 + 3j, -1 - 3j, 0.0, -10.0), 0.0),
    # a complex pair, however small, is not the capsize
    ((1e-7 + 1e-7j, 1e-7 - 1e-7j, -0.5, -10.0), -0.5),
    # the real root nearest zero wherever it stands in the list
    ((-1 + 3j, -1 - 3j, 2.0, -0.1), -0.1),
])
def test_the_capsize_prediction_is_the_real_root_nearest_zero(monkeypatch, spectrum, slow):
    """judge_run's capsize prediction on linearizations made by hand: the real eigenvalue
    (imag exactly 0, as sort_eigenvalues defines real) nearest zero, the module docstring's
    'capsize eigenvalue (real)', and the slowest of all when none is real. Planted: the pool
    always the real roots (an empty pool); the filter '<' (a zero root left out) or
    '1e-12 / |lam|' (a tiny pair let in); the first real root taken instead of the slowest."""
    monkeypatch.setattr("reference_model.linearize.eigenvalues",
                        lambda model, v: np.array(spectrum, dtype=complex))
    monkeypatch.setattr(st, "identify_eigenvalues", lambda traj: np.array([-0.3 + 0j]))
    j = st.judge_run(None, "capsize", 5.0, _done())
    assert j["predicted"] == slow and j["measured"] == -0.3


def test_the_verdict_is_the_sign_of_the_word_it_prints(monkeypatch):
    """judge_run on the weave with its linear real part and the run's envelope rate made by
    hand: the word is 'grows' for a positive real part only (zero is not growth), and the run
    passes when it completed, its rate is finite and it grows (rate > 0) exactly when the word
    says so; the weave's prediction is its pair's real part. Planted: '>=' for '>' in the word,
    in the run's sign or in the prediction's sign."""
    from comparisons.judgments.benchmark import Envelope
    rate = {}
    monkeypatch.setattr(st, "roll_rate_envelope",
                        lambda traj: Envelope(np.arange(4.0), np.ones(4), rate["r"], 1.0))
    for p in (0.3, 0.0, -0.3):
        monkeypatch.setattr("reference_model.linearize.eigenvalues",
                            lambda model, v, p=p: np.array([p + 2j, p - 2j, -1.0, -10.0]))
        for r in (0.2, 0.0, -0.2):
            rate["r"] = r
            j = st.judge_run(None, "weave", 4.0, _done())
            assert j["predicted"] == p and j["measured"] == r
            assert j["expected"] == ("grows" if p > 0 else "decays"), (p, r)
            assert j["passed"] == ((r > 0) == (j["expected"] == "grows")), (p, r, j)
            assert j["how"] == (f"4 peaks of |dtheta/dt| from 1 s, envelope rate {r:+.4f} /s; "
                                "completed at 5.00 s")
            assert not st.judge_run(None, "weave", 4.0, _done("failed"))["passed"]
    rate["r"] = float("nan")
    assert not st.judge_run(None, "weave", 4.0, _done())["passed"]


# -- the section's prose ---------------------------------------------------------------------------

def test_the_sections_prose_says_what_was_computed_and_judged():
    """stability_section's two paragraphs, word for word (module docstring, docs/report.md):
    the linearization over 0-10 m/s on the disc contact without drag and the critical speeds
    to 6 decimals (Table 2's for the benchmark), or 'none in 0-10 m/s'; the runs at 0.9 and
    1.1 x, the kick, what is judged and how, and the setups with a declared difference, comma
    separated. Planted: any of those words changed or cased; the separators changed."""
    m = model_spec("benchmark")
    crit = {"weave": WEAVE, "capsize": CAPSIZE}
    sec = st.stability_section(m, crit, None, {}, {}, ("reference", "mujoco", "drake"),
                               {"mujoco": "soft", "drake": "soft"})
    first, second = [b.text for b in sec.blocks if isinstance(b, Text)]
    assert first == ("Linearized roll/steer dynamics about upright straight running (exact "
                     "derivatives), eigenvalues against speed 0-10 m/s, contact disc, cv = 0. "
                     "Critical speeds: weave 4.292383 m/s, capsize 6.024262 m/s.")
    assert second == (
        "Forward runs at 0.9 and 1.1 x each critical speed: upright, roll rate 0.05 rad/s, no "
        "torques, projection, 5 s. Judged: the sign of the mode's real part measured on the run "
        "equals the linear prediction (weave: envelope of |dtheta/dt| from 1 s; capsize: the "
        "real exponent identified by the matrix pencil). mujoco, drake: a declared model "
        "difference (soft contact), measured the same way and reported, not judged.")
    none = st.stability_section(m, {}, None, {}, {})
    assert none.blocks[0].text == (
        "Linearized roll/steer dynamics about upright straight running (exact derivatives), "
        "eigenvalues against speed 0-10 m/s, contact disc, cv = 0. Critical speeds: none in "
        "0-10 m/s.")
