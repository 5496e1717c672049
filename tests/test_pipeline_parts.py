"""`bicycle-xval run` as a computation (comparisons/stages/pipeline.py), piece by piece and
whole, in this process and in a fraction of a second each: `select` (the command line's lists,
each refusal naming the field and the fix: README "Command line", exit 2 for a usage error),
`Options`, `_versions`, `_cpu`, `environment`, `_engine_modules`, `_core_tasks`,
`_stage_tasks`, `_buildable`, `run_comparison`, `apply_figure_policy`,
`_expected_differences`, `_models_used` and `_models_section`.

The contract: the module's docstrings, docs/report.md (summary.json's keys, the exit-status
table: a dropped engine fails the run, a declared limitation or an engine whose extra is not
installed does not; the `--figures` policies and the *Not drawn* line; *Models of this run*)
and docs/engines.md (an engine's ``prepare``, ``REQUIRES``). The whole run is exercised with
the cheapest real inputs there are: the reference's ``check`` (an inverse run of 0.03 s) and,
for ``--model``, ``check`` and ``benchmark-v4`` on the benchmark and thesis bicycles, with the
catalog's stages replaced by stand-in stages that record what the pipeline gives them, and the
worker pool run without warming the engines' libraries (`pool.run_tasks`' ``warm=()``). Two
plugin engines written in a temporary folder stand for a third party's: one whose ``prepare``
raises and whose runs carry a declared model difference, one whose constructor raises.

Expected values come from those documents, from the scenario registry's own data (grids,
tags), from published numbers (the benchmark bicycle's weave and capsize speeds, 4.2924 and
6.0243 m/s, Meijaard et al. 2007) and from hand-built inputs (fake distributions, a fake
/proc/cpuinfo, fake engine facts), never from the pipeline's own output. Each test names the
bugs planted by hand (in a copy of the module, one at a time) it was seen failing on.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import os
import platform
import sys
import types
from pathlib import Path
from types import SimpleNamespace

import pytest

from comparisons.judgments.rows import Comparison
from comparisons.stages import pipeline, pool
from comparisons.stages import runs as runs_module
from comparisons.stages.cases import Case, ModelSpec, NotRun, model_spec
from comparisons.stages.pipeline import (QUICK, SECTIONS, Options, SelectionError,
                                         apply_figure_policy, run_comparison, select)
from comparisons.stages.pool import Limits, Task
from comparisons.stages.results import Figure, Section, Table, Text
from comparisons.stages.stage import Assembled, Plan, Stage
from engines.facts import FixedStep, SoftContact
from reference_model.scenarios import SCENARIOS, ExpectedDifference, get_scenario

#: every built-in scenario of the thesis (all but the IFToMM manoeuvres, tagged "benchmark")
THESIS_SCENARIOS = {"check", "zigzag", "replay", "stability-psid0", "stability-psid1",
                    "stability-psid5", "stability-psid10", "check-forward"}

#: the benchmark bicycle's parameter file, as a user gives --model FILE
BENCHMARK_FILE = (Path(__file__).resolve().parents[1] / "reference_model" / "parameters"
                  / "benchmark.toml")

PLUGINS = '''
from engines.base import Engine


class Quiet(Engine):
    """No terms, no runs; its runs would carry a declared model difference."""
    name = "quiet"
    capabilities = ()
    contacts = ("thesis", "disc")
    run_difference = "its own soft contact"

    @classmethod
    def prepare(cls):
        raise RuntimeError("no cache here")


class Broken(Engine):
    name = "broken"
    capabilities = ()

    def __init__(self, model):
        raise RuntimeError("cannot   build\\tthis")
'''


@pytest.fixture(scope="module")
def plugins(tmp_path_factory):
    """The specs of the two plugin engines (module docstring)."""
    path = tmp_path_factory.mktemp("plugins") / "third_party.py"
    path.write_text(PLUGINS)
    return SimpleNamespace(quiet=f"{path}:Quiet", broken=f"{path}:Broken")


# ----------------------------------------------------------------------------- select

def test_select_without_lists_runs_the_thesis_scenarios_on_the_reference():
    """No --scenarios: every thesis scenario, in the registry's order, not the IFToMM ones;
    --engines reference alone; the defaults of Options. Planted: the benchmark tag's test
    negated (only the IFToMM manoeuvres run); Options' workers defaulting to 1."""
    opts = select(None, False, "reference")
    assert set(opts.scenarios) == THESIS_SCENARIOS
    assert list(opts.scenarios) == [n for n in SCENARIOS if n in THESIS_SCENARIOS]
    assert opts.engines == ("reference",)
    assert opts.quick is False and opts.workers is None and opts.models == ()
    assert opts.not_installed == () and opts.sections == SECTIONS and opts.figures == ""
    assert opts.figure_policy == "all"


def test_quick_without_scenarios_is_the_four_of_the_quick_subset():
    """docs/report.md: a --quick run is four scenarios (check, zigzag, check-forward,
    stability-psid10); --scenarios given with --quick are kept. Planted: the quick subset
    applied whatever --scenarios says; the quick flag not passed on to Options."""
    opts = select(None, True, "reference")
    assert opts.scenarios == ("check", "zigzag", "check-forward", "stability-psid10") == QUICK
    assert opts.quick is True and opts.figure_policy == "failing"
    assert select("replay", True, "reference").scenarios == ("replay",)


def test_the_lists_are_comma_separated_with_blanks_and_empty_items_ignored():
    """' check , ,zigzag ' is check and zigzag; the reference is put first when not named,
    kept where it is when named, and a name given twice runs once. Planted: the items not
    stripped; the reference appended instead of put first; the duplicates kept."""
    opts = select(" check , ,zigzag ", False, " pinocchio , ")
    assert opts.scenarios == ("check", "zigzag")
    assert opts.engines == ("reference", "pinocchio")
    assert select("check", False, "pinocchio,reference").engines == ("pinocchio", "reference")
    assert select("check", False, "reference,pinocchio,reference").engines == (
        "reference", "pinocchio")


@pytest.mark.parametrize("scenarios", ["", " , ,"])
def test_an_empty_scenario_list_is_refused_with_an_example(scenarios):
    """README: a usage error is one line naming the field and the fix. Planted: the emptiness
    test inverted; the message's field changed."""
    with pytest.raises(SelectionError) as err:
        select(scenarios, False, "reference")
    assert str(err.value) == ("--scenarios is empty; give a comma-separated list, "
                              "e.g. check,zigzag")


def test_an_unknown_scenario_is_named_with_every_choice():
    """Planted: the membership test inverted; the name not quoted."""
    with pytest.raises(SelectionError) as err:
        select("check,chekc", False, "reference")
    assert str(err.value) == ("unknown scenario 'chekc' in --scenarios; choose from "
                              + ", ".join(SCENARIOS))
    assert "benchmark-v8" in str(err.value)


def test_an_unknown_engine_is_named_with_the_registered_ones_and_the_spec_forms():
    """Planted: the registry's list left out of the message."""
    from engines import available_engines
    with pytest.raises(SelectionError) as err:
        select("check", False, "reference,pinochio")
    assert str(err.value) == (f"unknown engine 'pinochio' in --engines; choose from "
                              f"{', '.join(available_engines())} or give a spec "
                              "package.module:Class or path/file.py:Class")


def test_a_bad_spec_is_refused_as_the_registry_says(tmp_path):
    """A ``file.py:Class`` spec whose file does not exist: the registry's own message, after
    '--engines: '. Planted: the spec not resolved (a bad spec accepted)."""
    from engines import EngineSpecError
    from engines.registry import resolve
    spec = f"{tmp_path / 'absent.py'}:Nothing"
    with pytest.raises(EngineSpecError) as why:
        resolve(spec)
    with pytest.raises(SelectionError) as err:
        select("check", False, spec)
    assert str(err.value) == f"--engines: {why.value}"


def test_the_default_engines_leave_out_those_not_installed_and_say_why(monkeypatch):
    """docs/report.md and README: the default list runs the engines installed; one whose extra
    is missing is listed (``not_installed``), not run; named on --engines it is a usage
    error. Planted: the absent engine kept in the list; ``not_installed`` not passed to
    Options; the named engine's check skipped; the absent engines looked for in a named list
    too."""
    import engines
    reason = "not installed (pip install 'bicycle-xval[dart]')"
    monkeypatch.setattr(engines, "not_installed", lambda e: reason if e == "dart" else None)
    opts = select("check", False, None)
    assert opts.not_installed == (("dart", reason),)
    assert opts.engines == tuple(e for e in engines.default_engines() if e != "dart")
    assert opts.engines[0] == "reference"
    with pytest.raises(SelectionError) as err:
        select("check", False, "reference,dart")
    assert str(err.value) == f"--engines: engine 'dart' is {reason}"
    assert select("check", False, "reference,pinocchio").not_installed == ()


def test_options_figure_policy_and_options_per_engine():
    """docs/report.md: `--quick` draws the figures of failing sections by default, a full run
    all of them, and --figures wins over both; ``options_for`` is spec -> options dict.
    Planted: the quick and full defaults swapped; --figures ignored; options_for dropping an
    engine's first option."""
    assert Options(("check",), ("reference",)).figure_policy == "all"
    assert Options(("check",), ("reference",), quick=True).figure_policy == "failing"
    assert Options(("check",), ("reference",), quick=True, figures="none").figure_policy == "none"
    assert Options(("check",), ("reference",), figures="failing").figure_policy == "failing"
    opts = Options(("check",), ("reference", "kane"),
                   engine_options=(("kane", (("a", 1), ("b", "x"))), ("mujoco", ())))
    assert opts.options_for() == {"kane": {"a": 1, "b": "x"}, "mujoco": {}}


# ----------------------------------------------------------------------------- environment

class _FakeMetadata:
    """`importlib.metadata` for hand-made distributions: ``versions`` (distribution ->
    version) and ``providers`` (module -> distributions), counting the providers' look-ups."""

    PackageNotFoundError = importlib.metadata.PackageNotFoundError

    def __init__(self, versions, providers):
        self.versions, self.providers, self.looked_up = versions, providers, 0

    def version(self, name):
        if name not in self.versions:
            raise self.PackageNotFoundError(name)
        return self.versions[name]

    def packages_distributions(self):
        self.looked_up += 1
        return self.providers


CORE = {"numpy": "1.0", "scipy": "2.0", "sympy": "3.0", "pandas": "4.0", "matplotlib": "5.0"}


def test_versions_by_distribution_provider_or_module(monkeypatch):
    """`_versions`' docstring: a module's version is its namesake distribution's, else the
    distribution that installs it, else its ``__version__``, else 'not installed'; Python's
    own version first, then the core in order. The providers are looked up once, and only
    when a namesake is missing. Planted: the provider's last distribution read; the
    providers looked up again for every module; the __version__ of a module not stringified;
    the core list missing pandas; a namesake's version overwritten by the provider look-up;
    Python's version the last word of sys.version; an empty provider list not caught."""
    fake = _FakeMetadata({**CORE, "modd": "7.1", "distx": "9.9"},
                         {"modx": ["distx", "other"], "empty": [], "lost": ["nodist"]})
    monkeypatch.setattr(pipeline, "metadata", fake)
    monkeypatch.setitem(sys.modules, "withver", types.SimpleNamespace(__version__=3))
    monkeypatch.setitem(sys.modules, "nover", types.SimpleNamespace())
    got = pipeline._versions(("modd", "modx", "empty", "lost", "gone", "withver", "nover"))
    assert got == {"python": platform.python_version(), **CORE, "modd": "7.1", "modx": "9.9",
                   "empty": "not installed", "lost": "not installed", "gone": "not installed",
                   "withver": "3", "nover": "not installed"}
    assert list(got)[:6] == ["python", "numpy", "scipy", "sympy", "pandas", "matplotlib"]
    assert fake.looked_up == 1
    fake.looked_up = 0
    assert pipeline._versions(("modd",)) == {"python": platform.python_version(), **CORE,
                                             "modd": "7.1"}
    assert fake.looked_up == 0


class _FakePath:
    text: str | OSError = ""
    read: list = []

    def __init__(self, path):
        self.path = path

    def read_text(self):
        _FakePath.read.append(self.path)
        if isinstance(self.text, OSError):
            raise self.text
        return self.text


def test_cpu_is_the_first_model_name_of_proc_cpuinfo(monkeypatch):
    """The CPU is /proc/cpuinfo's first 'model name' value (not the 'model' number line before
    it, as Linux writes them), runs of blanks made one, a colon inside the name kept.
    Planted: the line's second field split at every colon; any line starting with 'model'
    taken; the blanks kept."""
    monkeypatch.setattr(pipeline, "Path", _FakePath)
    monkeypatch.setattr(_FakePath, "read", [])
    monkeypatch.setattr(_FakePath, "text", "processor\t: 0\nvendor_id\t: AuthenticAMD\n"
                        "cpu family\t: 25\nmodel\t\t: 1\n"
                        "model name\t:  AMD   EPYC 7B13: rev 2 \nmodel name\t: second\n")
    assert pipeline._cpu() == "AMD EPYC 7B13: rev 2"
    assert _FakePath.read == ["/proc/cpuinfo"]


@pytest.mark.parametrize("text", [OSError("no such file"), "processor\t: 0\nflags\t: fpu\n"])
def test_cpu_without_a_model_name_is_the_platform_s_word(monkeypatch, text):
    """No /proc/cpuinfo, or no model name in it: `platform.processor()`, else the machine.
    Planted: the OSError not caught; the machine preferred to the processor."""
    monkeypatch.setattr(pipeline, "Path", _FakePath)
    monkeypatch.setattr(_FakePath, "text", text)
    monkeypatch.setattr(platform, "processor", lambda: "k8-proc")
    monkeypatch.setattr(platform, "machine", lambda: "k8")
    assert pipeline._cpu() == "k8-proc"
    monkeypatch.setattr(platform, "processor", lambda: "")
    assert pipeline._cpu() == "k8"


def test_engine_modules_are_the_top_level_modules_each_once():
    """Planted: the last dotted part kept instead of the first; duplicates kept."""
    facts = [SimpleNamespace(requires=("pydrake.multibody", "numpy")),
             SimpleNamespace(requires=()),
             SimpleNamespace(requires=("pydrake", "scipy.linalg", "numpy.fft"))]
    assert pipeline._engine_modules(facts) == ("pydrake", "numpy", "scipy")


def _facts(name, requires=(), fixed_step=None, soft_contact=None):
    return SimpleNamespace(name=name, requires=requires, fixed_step=fixed_step,
                           soft_contact=soft_contact)


def test_environment_without_a_plan(monkeypatch):
    """What the numbers depend on: the core's versions, the machine, every setup's solver
    settings by label, the steps (the documented horizons and grids; no fixed-step or
    soft-contact engine without a plan), and where the run times are. Planted: the solvers
    keyed by engine instead of label; the output grid not the scenarios' 0.01 s; the cores
    not os.cpu_count(); the horizon runs' rtol under another key."""
    monkeypatch.setattr(pipeline, "_cpu", lambda: "a CPU")
    setups = [SimpleNamespace(label="reference", engine="reference", settings="DOP853"),
              SimpleNamespace(label="exudyn-tree", engine="exudyn", settings="GA h 1e-3")]
    env = pipeline.environment(setups)
    assert set(env) == {"packages", "machine", "solvers", "steps", "run_times"}
    assert list(env["packages"]) == ["python", "numpy", "scipy", "sympy", "pandas",
                                     "matplotlib"]
    assert env["machine"] == {"cpu": "a CPU", "cores": os.cpu_count(),
                              "arch": platform.machine(),
                              "platform": platform.platform(terse=True)}
    assert env["solvers"] == {"reference": "DOP853", "exudyn-tree": "GA h 1e-3"}
    steps = env["steps"]
    assert steps["fixed_step"] == {}
    assert steps["output_grid_s"] == get_scenario("check").grid[1] == 0.01
    assert steps["reference_horizon_runs_rtol"] == 1e-11   # the horizon's reason says so
    assert steps["convergence_horizon_s"] == 0.5
    assert steps["soft_contact_study"] == {"scenario": "stability-psid10", "model": "thesis-disc",
                                           "at_time_s": 0.2, "window_s": 0.5, "engines": []}
    assert "timings.json" in env["run_times"]


@pytest.mark.parametrize("quick, factors", [(False, (5, 2.5, 1.25, 0.625)),
                                            (True, (10, 5, 2.5, 1.25))])
def test_environment_names_each_engine_s_studies_from_its_facts(monkeypatch, quick, factors):
    """With a plan: the versions of the modules the engines declare; each fixed-step engine its
    option, step and convergence steps (docs/report.md: "for Exudyn 5e-3 down to 6.25e-4 s:
    the standard factors times the engine's declared step" of 1e-3 s, i.e. 5, 2.5, 1.25,
    0.625; --quick's halvings shifted one up, fixed_step.QUICK_CONVERGENCE_STEPS' comment);
    the soft-contact engines are listed. Planted: the quick flag not read from the plan; the
    convergence steps of the default step instead of the engine's; the soft-contact list
    taken from the fixed-step engines; the engines' modules not asked for; the fixed-step
    filter inverted."""
    monkeypatch.setattr(pipeline, "_cpu", lambda: "a CPU")
    monkeypatch.setattr(pipeline, "_versions", lambda modules=(): {"asked": modules})
    facts = {"reference": _facts("reference", ("numpy.linalg",)),
             "stepper": _facts("stepper", ("no_such_lib_a.core", "no_such_lib_b"),
                               fixed_step=FixedStep(option="h", step=2e-3)),
             "soft": _facts("soft", ("no_such_lib_a",), soft_contact=SoftContact())}
    plan = Plan(SimpleNamespace(quick=quick), (), facts)
    env = pipeline.environment([], plan)
    assert env["packages"] == {"asked": ("numpy", "no_such_lib_a", "no_such_lib_b")}
    fixed = env["steps"]["fixed_step"]
    assert list(fixed) == ["stepper"]
    assert fixed["stepper"]["option"] == "h" and fixed["stepper"]["step"] == 2e-3
    assert fixed["stepper"]["convergence"] == pytest.approx([2e-3 * f for f in factors])
    assert env["steps"]["soft_contact_study"]["engines"] == ["soft"]


# ----------------------------------------------------------------------------- the stages

def _setups():
    return [SimpleNamespace(label="reference", engine="reference"),
            SimpleNamespace(label="mj-soft", engine="mujoco")]


def _fake_cost(setup, name):
    return len(name) + (100.0 if setup.engine != "reference" else 0.0)


def test_core_tasks_are_every_case_on_every_setup_and_the_forward_horizons(monkeypatch):
    """Every case on every setup (a built-in by name), keyed ("run", label, case), its cost the
    setup's for that scenario, labelled '<case> on <label>', tagged with its engine (None
    for the reference's); then the meaningful horizon of each forward scenario whose
    trajectory is compared (0.3 s). Planted: the engine tag put on the reference's runs; the
    label used as the engine tag; the horizon's cost 3 s; the loops swapped (setup-major);
    the label naming the engine; the cost asked for another name than the case's."""
    monkeypatch.setattr(runs_module, "cost", _fake_cost)
    from comparisons.stages import scenarios
    cases = [Case("check", get_scenario("check"), "thesis"),
             Case("check-forward", get_scenario("check-forward"), "thesis")]
    tasks = pipeline._core_tasks(SimpleNamespace(models=()), _setups(), cases)
    assert [t.key for t in tasks] == [
        ("run", "reference", "check"), ("run", "mj-soft", "check"),
        ("run", "reference", "check-forward"), ("run", "mj-soft", "check-forward"),
        ("horizon", "check-forward")]
    run_ref, run_mj = tasks[0], tasks[3]
    assert run_ref.func is runs_module.run_one
    assert run_ref.args == (_setups()[0], "check")
    assert run_mj.args == (_setups()[1], "check-forward")
    assert [t.cost for t in tasks[:4]] == [5.0, 105.0, 13.0, 113.0]
    assert [t.label for t in tasks] == ["check on reference", "check on mj-soft",
                                        "check-forward on reference", "check-forward on mj-soft",
                                        "check-forward: meaningful horizon"]
    assert [t.engine for t in tasks] == [None, "mujoco", None, "mujoco", None]
    horizon = tasks[4]
    assert horizon.func is scenarios.horizon_of and horizon.args == ("check-forward",)
    assert horizon.cost == 0.3


def test_core_tasks_of_cases_on_models_pass_the_scenario_and_the_model(monkeypatch):
    """With --model (or a scenario file's case) a run gets the case's Scenario object and its
    model spec, the horizon the Scenario; a forward scenario whose trajectory is not
    compared has no horizon. Planted: a file's case run by name; the model's cases run by
    name; the horizon of a model's case asked by name; a horizon for every forward or
    trajectory-compared scenario."""
    monkeypatch.setattr(runs_module, "cost", _fake_cost)
    fwd = dataclasses.replace(get_scenario("check-forward"), name="mine")
    untracked = dataclasses.replace(fwd, name="flat", compared=("mass_matrix",))
    file_cases = [Case("mine", fwd, "thesis-disc", origin="mine.toml"),
                  Case("flat", untracked, "thesis-disc", origin="flat.toml")]
    setups = _setups()[:1]
    tasks = pipeline._core_tasks(SimpleNamespace(models=()), setups, file_cases)
    assert [t.key for t in tasks] == [("run", "reference", "mine"), ("run", "reference", "flat"),
                                      ("horizon", "mine")]
    assert tasks[0].args == (setups[0], fwd, "thesis-disc")
    assert tasks[2].args == (fwd,)
    on_model = [Case("check-forward", get_scenario("check-forward"), "thesis")]
    tasks = pipeline._core_tasks(SimpleNamespace(models=("a model",)), setups, on_model)
    assert tasks[0].args == (setups[0], get_scenario("check-forward"), "thesis")
    assert tasks[1].args == (get_scenario("check-forward"),)


class _Recording(Stage):
    """A stage that records what the pipeline asks of it; ``make`` builds what it assembles."""

    def __init__(self, name, section, tasks=(), make=None, revise=None):
        self.name, self.section = name, section
        self._tasks, self.make, self.revise = list(tasks), make, revise
        self.prepared, self.assembled = [], []

    def prepare(self, plan):
        self.prepared.append(plan)

    def tasks(self, plan):
        return list(self._tasks)

    def assemble(self, plan, results):
        self.assembled.append(dict(results))
        return self.make(plan, results) if self.make else Assembled()

    def revise_claims(self, plan, results, claims):
        return self.revise(claims) if self.revise else claims


def test_stage_tasks_namespaced_by_stage_and_prepared_only_when_selected(monkeypatch):
    """A selected stage (its section in --sections, or none: always run) is prepared once and
    its tasks keyed (stage name, its key), everything else kept; an unselected one is
    neither prepared nor asked. Planted: prepare never called; every stage's tasks taken
    (--sections ignored); the key not namespaced; the stages' tasks in reverse order."""
    a = _Recording("alpha", None, [Task("k1", abs, (-1,), 2.0, "alpha 1", "kane"),
                                   Task(("k", 2), abs, (-2,))])
    b = _Recording("beta", "terms", [Task("k1", abs, (-3,))])
    c = _Recording("gamma", "faults", [Task("k3", divmod, (7, 2), 0.5, "gamma 3")])
    monkeypatch.setattr(pipeline, "STAGES", (a, b, c))
    plan = Plan(Options(("check",), ("reference",), sections=("faults",)), (), {})
    tasks = pipeline._stage_tasks(plan)
    assert [t.key for t in tasks] == [("alpha", "k1"), ("alpha", ("k", 2)), ("gamma", "k3")]
    assert tasks[0] == Task(("alpha", "k1"), abs, (-1,), 2.0, "alpha 1", "kane")
    assert tasks[2] == Task(("gamma", "k3"), divmod, (7, 2), 0.5, "gamma 3")
    assert a.prepared == [plan] and c.prepared == [plan] and b.prepared == []


def test_buildable_tries_specs_and_engines_with_options_in_a_worker(monkeypatch, plugins):
    """_buildable's docstring: every setup is returned; an engine given by spec, or given
    options, is built on the thesis model (in a worker) and dropped with the exception's
    type and message, blanks made one; a registered engine at its declared setups is not
    tried. Planted: the registered engines tried too; the exception's type left out; a spec
    never tried; the command line's options not given to the setups; the dropped engine
    named by its label."""
    from comparisons.stages import isolated as isolated_module
    tried = []

    def recording(setup, *args):
        tried.append(setup.engine)
        return isolated_module.isolated(setup, *args)

    monkeypatch.setattr(pipeline, "isolated", recording)
    opts = Options(("check",), ("reference", "pinocchio", "kane", plugins.quiet, plugins.broken),
                   engine_options=(("kane", (("no_such_option", 1),)),))
    setups, dropped = pipeline._buildable(opts)
    assert [s.engine for s in setups] == list(opts.engines)
    assert tried == ["kane", plugins.quiet, plugins.broken]
    assert [d[0] for d in dropped] == ["kane", plugins.broken]
    assert dropped[0][1].startswith("EngineSpecError: ") and "no_such_option" in dropped[0][1]
    assert dropped[1][1].startswith("EngineLoadError: ")
    assert dropped[1][1].endswith("RuntimeError: cannot build this")


def test_buildable_drops_on_any_exception_in_one_line(monkeypatch, plugins):
    """Any failure of the build drops the engine (not only the loader's, which are one line
    already): type, then the message with its line breaks and runs of blanks made one blank.
    Planted: the message's blanks kept."""
    def failing(setup, *args):
        def build(model):
            raise OSError("disk\n   full\tnow")
        return SimpleNamespace(build=build)

    monkeypatch.setattr(pipeline, "isolated", failing)
    _, dropped = pipeline._buildable(Options(("check",), ("reference", plugins.quiet)))
    assert dropped == [(plugins.quiet, "OSError: disk full now")]


# ----------------------------------------------------------------------------- the whole run

@pytest.fixture
def cheap_pool(monkeypatch):
    """The real pool, not warming the engines' libraries; records its workers and limits."""
    calls = []

    def run(tasks, workers=None, progress=lambda s: None, limits=None):
        calls.append(SimpleNamespace(keys=[t.key for t in tasks], workers=workers,
                                     limits=limits))
        return pool.run_tasks(tasks, workers, progress, warm=(), limits=limits)

    monkeypatch.setattr(pipeline, "run_tasks", run)
    return calls


def _row(scenario, passed, quantity="alpha quantity"):
    return Comparison.of({"quantity": quantity, "scenario": scenario, "model": "thesis",
                          "engines": ["reference"], "max_error": 0.0, "tolerance": 1.0,
                          "passed": passed, "localized_to": "-"})


def _fail(*_):
    raise ZeroDivisionError("on purpose")


def _alpha_section(plan, results):
    sec = Section("Alpha")
    sec.text("alpha first")
    sec.figure("alpha.png", "lines", x=[0, 1])
    sec.comparisons.append(_row("check", True))
    return Assembled([sec], [{"engine": "reference", "verdict": "localized"},
                             {"engine": "reference", "verdict": "not observable"},
                             {"engine": "reference", "verdict": "not run"}],
                     {"alpha_summary": {"n": len(results)}})


def _raising_assembly(plan, results):
    raise RuntimeError("bad\n  news " + "x" * 400)


@pytest.fixture(scope="module")
def full_run(plugins, tmp_path_factory):
    """The reference and the Quiet plugin (its prepare raises) on check and zigzag, the Broken
    plugin (dropped), dart not installed; stages: alpha (always run; two tasks, one raising), beta
    (section terms, not selected), gamma (section faults; its assembly raises)."""
    mp = pytest.MonkeyPatch()
    calls = []

    def run(tasks, workers=None, progress=lambda s: None, limits=None):
        calls.append(SimpleNamespace(keys=[t.key for t in tasks], workers=workers,
                                     limits=limits))
        return pool.run_tasks(tasks, workers, progress, warm=(), limits=limits)

    alpha = _Recording("alpha", None, [Task("one", divmod, (7, 2), 0.5, "alpha one"),
                                       Task("two", _fail, (), 0.4, "alpha two")],
                       make=_alpha_section)
    beta = _Recording("beta", "terms", [Task("b", abs, (-1,), 0.1, "beta")], make=_alpha_section)
    gamma = _Recording("gamma", "faults", make=_raising_assembly)
    mp.setattr(pipeline, "run_tasks", run)
    mp.setattr(pipeline, "STAGES", (alpha, beta, gamma))
    try:
        opts = dataclasses.replace(
            select("check,zigzag", True, f"reference,{plugins.quiet},{plugins.broken}"),
            workers=1, stage_timeout=42.0, sections=("faults",),
            not_installed=(("dart", "not installed (pip install 'bicycle-xval[dart]')"),))
        said = []
        result = run_comparison(opts, said.append)
    finally:
        mp.undo()
    return SimpleNamespace(result=result, said=said, calls=calls, opts=opts, alpha=alpha,
                           beta=beta, gamma=gamma, quiet=plugins.quiet, broken=plugins.broken)


def test_a_run_says_what_it_drops_prepares_and_runs(full_run):
    """The progress lines: each dropped engine with its reason, each default engine not
    installed with why, a prepare that raised (the engine's stages then say what fails), and
    the count of stages, workers, scenarios and setups. Planted: the dropped and the
    not-installed lines skipped; a failed prepare not said; the task count without the
    stages' tasks; the workers' number not passed to the pool; the stage limit not passed
    on; the dropped engines' setups kept."""
    said = full_run.said
    assert said[0].startswith(f"engine {full_run.broken} dropped: EngineLoadError: ")
    assert said[1] == "engine dart not run: not installed (pip install 'bicycle-xval[dart]')"
    assert said[2] == f"engine {full_run.quiet}: preparing failed (RuntimeError: no cache here)"
    # check and zigzag on the reference and on Quiet, alpha's two tasks (beta not selected)
    assert said[3] == ("6 stages on 1 worker(s): 2 scenario(s) on reference, Quiet, "
                       "engine sections, faults ...")
    (call,) = full_run.calls
    assert call.workers == 1 and call.limits == Limits(42.0)
    assert sorted(map(str, call.keys)) == sorted(map(str, [
        ("run", "reference", "check"), ("run", "Quiet", "check"),
        ("run", "reference", "zigzag"), ("run", "Quiet", "zigzag"),
        ("alpha", "one"), ("alpha", "two")]))


def test_a_dropped_engine_fails_the_run_and_is_listed_apart(full_run):
    """docs/report.md's exit-status table: an engine that raises while being built is
    `dropped_engines` (engine, reason) and the run fails; the others' results are kept; an
    engine whose extra is missing is `not_installed_engines`. Planted: the dropped engine
    left in ``engines``; the not-installed engines' reason replaced by the engine."""
    s = full_run.result.summary
    assert s["engines"] == ["reference", full_run.quiet]
    assert full_run.result.options.engines == ("reference", full_run.quiet)
    assert [d["engine"] for d in s["dropped_engines"]] == [full_run.broken]
    assert s["dropped_engines"][0]["reason"].startswith("EngineLoadError: ")
    assert s["not_installed_engines"] == [
        {"engine": "dart", "reason": "not installed (pip install 'bicycle-xval[dart]')"}]
    assert s["passed"] is False


def test_the_runs_are_every_scenario_on_every_setup_left(full_run):
    """runs keyed (label, scenario); engine_runs sorted by scenario then label, each with its
    status and t_end (the check grid's end, 628 x 0.01 s); the plugin that has no inverse
    runs is 'not run' (a declared limitation). Planted: engine_runs sorted by label first;
    t_end rounded to 1 digit; the dropped engines' setups kept."""
    r = full_run.result
    assert set(r.runs) == {("reference", "check"), ("Quiet", "check"),
                           ("reference", "zigzag"), ("Quiet", "zigzag")}
    t0, dt, n = get_scenario("check").grid
    rows = r.summary["engine_runs"]
    assert [(e["engine"], e["scenario"]) for e in rows] == [
        ("Quiet", "check"), ("reference", "check"), ("Quiet", "zigzag"), ("reference", "zigzag")]
    assert rows[1]["status"] == "completed" and rows[1]["model"] == "thesis"
    assert rows[1]["t_end"] == round(t0 + (n - 1) * dt, 6)
    assert rows[0]["status"] == "not run"
    assert [(e["scenario"], e["status"]) for e in r.summary["scenarios"]] == [
        ("check", "completed"), ("zigzag", "completed")]


def test_summary_has_the_documented_keys_and_the_stage_s_own(full_run):
    """docs/report.md: summary.json's keys (those of a run whose stages add no matrix), plus
    the run's own facts and what a stage adds; the figure policy of --quick is 'failing'.
    Planted: the sections list replaced by every section; the quick flag dropped; a stage's
    summary not merged; the solvers keyed by engine; summary.json's figures the raw
    --figures value."""
    s = full_run.result.summary
    documented = {"passed", "summary_table", "comparisons", "claims", "faults", "scenarios",
                  "engine_runs", "checks", "initial_corrections", "expected_differences",
                  "environment", "provenance"}
    own = {"engines", "dropped_engines", "not_installed_engines", "quick", "figures",
           "sections"}
    assert set(s) == documented | own | {"alpha_summary"}
    assert s["quick"] is True and s["figures"] == "failing" and s["sections"] == ["faults"]
    assert s["expected_differences"] == []
    assert "models" not in s and "critical_speeds" not in s and "not_run" not in s
    assert list(s["environment"]["solvers"]) == ["reference", "Quiet"]
    assert s["checks"] and all(c["passed"] for c in s["checks"])


def test_each_stage_gets_its_own_results_and_unselected_ones_nothing(full_run):
    """A stage's results come keyed as it gave them (never another's, never the runs'); a
    failed task is its error; a stage whose section is not selected is not asked. Planted:
    the results keyed by the pipeline's namespaced key; the unselected stage assembled."""
    (mine,) = full_run.alpha.assembled
    assert set(mine) == {"one", "two"}
    assert mine["one"].value == (3, 1) and mine["one"].error is None
    assert "ZeroDivisionError" in mine["two"].error and "on purpose" in mine["two"].error
    assert full_run.beta.assembled == [] and full_run.beta.prepared == []
    assert full_run.gamma.assembled == [{}]
    assert full_run.result.summary["alpha_summary"] == {"n": 2}


def test_sections_in_order_with_a_failed_assembly_as_a_failing_section(full_run):
    """The scenarios' section, then each stage's in catalog order; a stage whose assembly
    raises becomes '<stage>: assembling its section' with its error in one line, cut to 300
    characters, failing the run. Planted: the error's blanks kept; the message not cut; the
    failed stage's section left out; the stages' sections not added."""
    secs = full_run.result.sections
    assert [s.title for s in secs] == ["Every engine on every scenario", "Alpha",
                                       "gamma: assembling its section"]
    (row,) = secs[2].comparisons
    assert row["passed"] is False
    want = "RuntimeError: " + ("bad news " + "x" * 400)[:300]
    assert row["localized_to"] == want
    assert secs[2].blocks[0].text == f"**This stage failed**: {want}"
    assert [c["quantity"] for c in full_run.result.summary["comparisons"]].count("stage") == 1


def test_the_quick_figure_policy_is_applied_to_every_section(full_run):
    """--quick draws the figures of failing sections only: alpha's passes, so its figure gives
    way to the *Not drawn* line, after its text. Planted: the policy not applied; the full
    run's policy used; the stages' sections not added."""
    alpha = full_run.result.sections[1]
    assert alpha.figures == []
    assert alpha.blocks[0] == Text("alpha first")
    assert "`alpha.png`" in alpha.blocks[1].text


def test_claims_say_whether_their_engine_declares_a_model_difference(full_run):
    """docs/report.md: a claim judged on runs of an engine that declares a model difference
    shows it (the engine's ``run_difference``); the reference's claims carry None. Planted:
    the difference looked up by engine spec instead of label."""
    claims = full_run.result.summary["claims"]
    by_engine = {c["engine"]: c["model_difference"] for c in claims}
    assert by_engine == {"reference": None, "Quiet": "its own soft contact"}


def test_timings_are_kept_apart_by_stage_and_run(full_run):
    """The run times (docstring: kept apart, so identical inputs give identical reports): every
    task by label, the judging, each run by '<scenario> on <label>', the total. Planted: the
    stages' times keyed by task key; the engine runs' by label only; a run's label naming
    its engine."""
    t = full_run.result.timings
    assert set(t) == {"stages", "judging in the main process", "engine_run_seconds",
                      "total_seconds"}
    assert set(t["stages"]) == {"check on reference", "check on Quiet", "zigzag on reference",
                                "zigzag on Quiet", "alpha one", "alpha two"}
    assert set(t["engine_run_seconds"]) == {"check on reference", "check on Quiet",
                                            "zigzag on reference", "zigzag on Quiet"}
    assert t["total_seconds"] >= t["judging in the main process"] >= 0
    assert all(v >= 0 for v in t["stages"].values())
    assert "timings" not in full_run.result.summary


def _run_with(monkeypatch, *stages, scenarios="check", engines="reference", **more):
    monkeypatch.setattr(pipeline, "STAGES", stages)
    opts = dataclasses.replace(select(scenarios, False, engines), workers=1, **more)
    return run_comparison(opts)


def test_a_run_where_everything_holds_passes(monkeypatch, cheap_pool):
    """Faults localized, not observable or not run are no failure (docs/report.md); a full run
    draws every figure; summary.json's expected_differences are the scenarios' declared ones
    (here one declared on check for the test, in the registry the workers read). Planted:
    'not run' counted as a failure; the stages' faults not collected; 'all' hiding figures;
    the first scenario's expected differences left out."""
    declared = ExpectedDifference("torques", "reference vs a stand-in", "model difference",
                                  "declared by the test")
    monkeypatch.setitem(SCENARIOS, "check", dataclasses.replace(
        get_scenario("check"), expected_differences=(declared,)))
    alpha = _Recording("alpha", None, make=_alpha_section)
    r = _run_with(monkeypatch, alpha)
    assert r.summary["expected_differences"] == [
        {"scenario": "check", "quantity": "torques", "engines": "reference vs a stand-in",
         "expected": "model difference", "reason": "declared by the test"}]
    assert r.summary["passed"] is True
    assert r.summary["figures"] == "all" and r.sections[1].figures
    assert [f["verdict"] for f in r.summary["faults"]] == ["localized", "not observable",
                                                           "not run"]
    assert r.localization == []


@pytest.mark.parametrize("verdict", ["missed", "mislocalized"])
def test_a_fault_missed_fails_the_run(monkeypatch, cheap_pool, verdict):
    """Planted: the stages' fault rows not collected."""
    stage = _Recording("faulty", None, make=lambda plan, res: Assembled(
        faults=[{"engine": "reference", "verdict": "localized"},
                {"engine": "reference", "verdict": verdict}]))
    assert _run_with(monkeypatch, stage).summary["passed"] is False


def test_a_failing_comparison_fails_the_run_and_keeps_its_figures(monkeypatch, cheap_pool):
    """Planted: a failing row not failing the run; --figures failing hiding the figures of a
    failing section."""
    def failing(plan, res):
        sec = Section("Failing")
        sec.figure("f.png", "lines")
        sec.comparisons.append(_row("check", False))
        return Assembled([sec])
    r = _run_with(monkeypatch, _Recording("failing", None, make=failing), figures="failing")
    assert r.summary["passed"] is False
    assert [f.name for f in r.sections[1].figures] == ["f.png"]


def test_a_failed_reference_run_is_a_failed_run(monkeypatch, cheap_pool):
    """A run whose task raised is a Run 'failed' with the error (engine and scenario kept,
    model and kind '-', t_end 0), and a failed reference run fails the verdict. Planted: the
    failed run's label and scenario swapped."""
    def broken_run(setup, scenario, model=None):
        raise RuntimeError("the solver gave up")
    monkeypatch.setattr(runs_module, "run_one", broken_run)
    r = _run_with(monkeypatch, scenarios="zigzag")
    assert r.summary["checks"] == []     # zigzag has no analytic check: only its row fails
    run = r.runs[("reference", "zigzag")]
    assert (run.engine, run.scenario, run.model, run.status, run.t_end) == (
        "reference", "zigzag", "-", "failed", 0.0)
    assert "the solver gave up" in run.message
    assert r.summary["passed"] is False
    assert r.summary["engine_runs"][0]["status"] == "failed"


@pytest.mark.parametrize("what", ["check", "row"])
def test_a_failed_analytic_check_or_reference_row_alone_fails_the_run(monkeypatch, cheap_pool,
                                                                      what):
    """docs/report.md: a failed analytic check, or a failed reference run in the scenarios'
    table, fails the run by itself, every comparison holding (the verdict turned false where
    the reference's rows are made: a real failed run also fails its 'not compared' rows, see
    the test above). Planted: the checks not read for the verdict; the reference rows not
    read for the verdict."""
    from comparisons.stages import scenarios
    real = scenarios.reference_rows

    def failing(*args):
        rows, checks, corrections = real(*args)
        if what == "check":
            return rows, [{**c, "passed": False} for c in checks], corrections
        return [{**row, "status": "failed"} for row in rows], checks, corrections

    monkeypatch.setattr(scenarios, "reference_rows", failing)
    r = _run_with(monkeypatch)
    assert [c["passed"] for c in r.summary["checks"]] == [what != "check"]
    assert [row["status"] for row in r.summary["scenarios"]] == [
        "failed" if what == "row" else "completed"]
    assert all(c["passed"] is not False for c in r.summary["comparisons"])
    assert r.summary["passed"] is False


def test_a_dropped_engine_alone_fails_the_run(monkeypatch, cheap_pool, plugins):
    """docs/report.md's exit-status table: an engine that raises while being built fails the
    run (exit 1) even when everything else holds. Planted: the dropped engines not read for
    the verdict."""
    r = _run_with(monkeypatch, _Recording("alpha", None, make=_alpha_section),
                  engines=f"reference,{plugins.broken}")
    assert [d["engine"] for d in r.summary["dropped_engines"]] == [plugins.broken]
    assert r.summary["checks"] and all(c["passed"] for c in r.summary["checks"])
    assert all(c["passed"] is not False for c in r.summary["comparisons"])
    assert r.summary["passed"] is False


def test_two_stages_writing_one_summary_key_are_refused(monkeypatch, cheap_pool):
    """stage.Assembled: a key the pipeline or another stage already wrote is refused.
    Planted: the second writer silently winning; the pipeline's own keys overwritable."""
    one = _Recording("one", None, make=lambda p, r: Assembled(summary={"shared": 1}))
    two = _Recording("two", None, make=lambda p, r: Assembled(summary={"shared": 2}))
    with pytest.raises(ValueError, match="stages one and two both write summary.json's "
                                         "'shared'"):
        _run_with(monkeypatch, one, two)
    greedy = _Recording("greedy", None, make=lambda p, r: Assembled(
        summary={"passed": True, "claims": []}))
    with pytest.raises(ValueError) as err:
        _run_with(monkeypatch, greedy)
    assert str(err.value) == ("a stage writes summary.json keys the pipeline owns: "
                              "['claims', 'passed']")


def test_an_untyped_comparison_row_is_a_bug_reported_by_its_quantity(monkeypatch, cheap_pool):
    """Every row is a judgments.rows.Comparison; a dict is refused naming its type and
    quantity. Planted: the type check dropped; the quantity not named."""
    def dict_row(plan, res):
        sec = Section("Untyped")
        sec.comparisons.append({"quantity": "loose", "passed": True})
        return Assembled([sec])
    with pytest.raises(TypeError) as err:
        _run_with(monkeypatch, _Recording("untyped", None, make=dict_row))
    assert str(err.value) == ("comparison rows must be judgments.rows.Comparison; got dict "
                              "for 'loose'")


def test_claims_revised_by_a_stage(monkeypatch, cheap_pool):
    """A stage's revise_claims replaces the claims (stage.Stage), before the model
    difference is added. Planted: the revision discarded."""
    def revise(claims):
        return [{**c, "verdict": "revised"} for c in claims]
    stage = _Recording("rev", None, revise=revise)
    claims = _run_with(monkeypatch, stage).summary["claims"]
    assert claims and {c["verdict"] for c in claims} == {"revised"}
    assert all("model_difference" in c for c in claims)


@pytest.fixture(scope="module")
def model_run():
    """check and benchmark-v4 on --model <the benchmark's parameter file> (spec: the file's
    path, name: benchmark) and --model thesis, the reference only."""
    mp = pytest.MonkeyPatch()
    mp.setattr(pipeline, "STAGES", ())
    mp.setattr(pipeline, "run_tasks", lambda tasks, workers=None, progress=None, limits=None:
               pool.run_tasks(tasks, workers, progress, warm=(), limits=limits))
    try:
        opts = dataclasses.replace(select("check,benchmark-v4", False, "reference"), workers=1,
                                   models=(model_spec(str(BENCHMARK_FILE)), model_spec("thesis")))
        said = []
        return SimpleNamespace(result=run_comparison(opts, said.append), said=said)
    finally:
        mp.undo()


def test_a_model_run_covers_its_models_and_says_what_it_did_not_run(model_run):
    """docs/report.md, "Your own bicycle": *Models of this run* first; each scenario runs on
    each model as <scenario>-on-<model> (on its own named model under its own name), the
    IFToMM manoeuvres on no --model but the named benchmark, with the reason; summary.json
    lists the models and what was not run. Planted: the models section appended last; the
    model's cases run by name; ``models`` written only with --scenario-file; the not-run
    reason replaced by the model; the section's title."""
    r = model_run.result
    assert r.sections[0].title == "Models of this run"
    assert set(r.runs) == {("reference", "check"), ("reference", "check-on-benchmark")}
    models = {e["scenario"]: e["model"] for e in r.summary["engine_runs"]}
    assert models == {"check": "thesis", "check-on-benchmark": "benchmark"}
    assert [m["name"] for m in r.summary["models"]] == ["benchmark", "thesis"]
    assert r.summary["models"][0]["source"] == str(BENCHMARK_FILE)
    assert [m["contact"] for m in r.summary["models"]] == ["disc", "thesis"]
    not_run = r.summary["not_run"]
    assert [(nr["scenario"], nr["model"]) for nr in not_run] == [("benchmark-v4", "benchmark"),
                                                                ("benchmark-v4", "thesis")]
    assert all("benchmark bicycle's critical speeds" in nr["reason"] for nr in not_run)
    assert r.summary["passed"] is True


def test_a_model_run_gives_the_critical_speeds_of_its_disc_models(model_run):
    """summary.json's critical_speeds: each disc-contact --model's weave and capsize speeds by
    name; the benchmark's are Meijaard et al.'s 4.2924 and 6.0243 m/s; the thesis bicycle
    (fork-axis contact) has none; keyed by the model's name, not its spec (here a file's
    path). Planted: the disc test inverted; the critical speeds keyed by spec instead of
    name; the progress line counting every model."""
    crit = model_run.result.summary["critical_speeds"]
    assert list(crit) == ["benchmark"]
    assert crit["benchmark"]["weave"] == pytest.approx(4.2924, abs=1e-4)
    assert crit["benchmark"]["capsize"] == pytest.approx(6.0243, abs=1e-4)
    assert model_run.said[0] == ("2 stages on 1 worker(s): 2 scenario(s) on reference, the "
                                 "stability of 1 model(s) ...")


def test_a_model_run_without_the_thesis_bicycle_judges_no_claim(monkeypatch, cheap_pool):
    """With --model thesis-disc only, check runs as check-on-thesis-disc: no scenario of the
    thesis bicycle ran, so no claim is judged. Planted: claims judged on the --scenarios
    names whatever the models."""
    r = _run_with(monkeypatch, models=(model_spec("thesis-disc"),))
    assert set(r.runs) == {("reference", "check-on-thesis-disc")}
    assert r.summary["claims"] == []


def test_a_model_run_judges_the_claims_on_the_thesis_scenarios_only(model_run):
    """The thesis's claims are about the thesis bicycle: judged on its scenarios only (here
    check on model thesis). Planted: the claims judged on the scenarios of the other models
    (the model test negated)."""
    claims = model_run.result.summary["claims"]
    assert {c["engine"] for c in claims} == {"reference"}
    assert {c["claim_id"] for c in claims} == {"check-pedal-torque"}
    assert all(c["verdict"] == "reproduced" for c in claims)


# ----------------------------------------------------------------------------- pure parts

def _figured(*comparisons):
    sec = Section("S")
    sec.text("first")
    sec.figure("a.png", "lines", x=1)
    sec.table(("h",), [("r",)])
    sec.figure("b.png", "bars")
    sec.text("last")
    sec.comparisons.extend(comparisons)
    return sec


def test_figure_policy_all_or_a_failing_section_keeps_every_figure():
    """Planted: 'all' hiding figures; a failing section's figures hidden under 'failing'."""
    sec = _figured(_row("check", True))
    assert apply_figure_policy(sec, "all") is sec
    failing = _figured(_row("check", True), _row("check", False))
    assert apply_figure_policy(failing, "failing") is failing
    bare = Section("no figures")
    bare.text("t")
    assert apply_figure_policy(bare, "none") is bare


@pytest.mark.parametrize("policy, why", [
    ("failing", "`--figures failing`, the default of `--quick`, draws them where a comparison "
                "failed, and nothing failed here"),
    ("none", "`--figures none`")])
def test_figures_not_drawn_are_one_line_where_the_first_stood(policy, why):
    """apply_figure_policy's docstring: the figures left out become one line naming them, in
    place of the first; nothing else moves; the section given is not changed. A reported row
    (passed None) is no failure. Planted: the line put at the end; a line per figure; the
    figures' names not in backticks; the reason of 'failing' given for 'none'; a reported
    row taken as a failure; the given section's blocks overwritten; the `--figures all` hint
    changed."""
    sec = _figured(_row("check", True), _row("check", None))
    out = apply_figure_policy(sec, policy)
    assert out.blocks == [Text("first"),
                          Text(f"*Not drawn ({why}; `--figures all` draws them): "
                               "`a.png`, `b.png`.*"),
                          Table(("h",), (("r",),)), Text("last")]
    assert out.title == "S" and out.comparisons == sec.comparisons
    assert [b.name for b in sec.blocks if isinstance(b, Figure)] == ["a.png", "b.png"]


def test_an_unknown_figure_policy_is_refused_with_the_choices():
    """Planted: the check dropped (the section returned unchanged)."""
    with pytest.raises(ValueError) as err:
        apply_figure_policy(_figured(), "some")
    assert str(err.value) == "figure policy 'some': choose one of all, failing, none"


def test_expected_differences_of_each_scenario_in_order():
    """Every declared difference of each scenario, in the order of the names then of the
    declarations, with its five fields. Planted: only the first name's differences; the
    reason field dropped; the quantity given the engines."""
    e = [SimpleNamespace(quantity=f"q{i}", engines=[f"e{i}"], expected=f"x{i}",
                         reason=f"r{i}") for i in range(3)]
    cases = {"one": SimpleNamespace(expected_differences=(e[0], e[1])),
             "none": SimpleNamespace(expected_differences=()),
             "two": SimpleNamespace(expected_differences=(e[2],))}
    got = pipeline._expected_differences(["two", "none", "one"], cases)
    assert got == [{"scenario": "two", "quantity": "q2", "engines": ["e2"], "expected": "x2",
                    "reason": "r2"},
                   {"scenario": "one", "quantity": "q0", "engines": ["e0"], "expected": "x0",
                    "reason": "r0"},
                   {"scenario": "one", "quantity": "q1", "engines": ["e1"], "expected": "x1",
                    "reason": "r1"}]
    psid10 = get_scenario("stability-psid10")
    real = pipeline._expected_differences(["stability-psid10"], {"stability-psid10": psid10})
    assert [d["quantity"] for d in real] == [d.quantity for d in psid10.expected_differences]


def _spec(name, contact="disc", warnings=()):
    return ModelSpec(f"/models/{name}.toml", name, f"{name}.toml", contact, 0.0, warnings)


def test_models_used_are_the_models_then_each_case_s_other_model(monkeypatch):
    """summary.json's ``models``: every --model, then every other model a case ran on (a
    scenario file's own), each once. Planted: the cases' models skipped; the membership test
    inverted; a model described again for each of its cases."""
    from comparisons.stages import cases as cases_module
    described = []

    def fake_model_spec(spec):
        described.append(spec)
        return _spec(f"file-{spec}", "thesis")

    monkeypatch.setattr(cases_module, "model_spec", fake_model_spec)
    mine, other = _spec("mine", warnings=("A + B < C",)), _spec("other")
    opts = Options(("check",), ("reference",), models=(mine, other))
    case_list = [SimpleNamespace(model=mine.spec), SimpleNamespace(model="thesis-disc"),
                 SimpleNamespace(model="thesis-disc"), SimpleNamespace(model=other.spec)]
    got = pipeline._models_used(opts, case_list)
    assert got == [{"name": "mine", "source": "mine.toml", "contact": "disc",
                    "warnings": ["A + B < C"]},
                   {"name": "other", "source": "other.toml", "contact": "disc", "warnings": []},
                   {"name": "file-thesis-disc", "source": "file-thesis-disc.toml",
                    "contact": "thesis", "warnings": []}]
    assert described == ["thesis-disc"]


def test_models_section_lists_the_models_and_what_was_not_run():
    """docs/report.md: *Models of this run* lists each model (name, source, contact, its
    warnings or '-') and the scenarios not run on a model, with the reason; the text says
    how the scenarios are named and that an engine that cannot represent a model is a
    declared limitation. Planted: the warnings joined without '; '; '' for no warning; the
    not-run table always written; its reason column dropped; the title; the source column
    given the spec; the naming of the cases changed in the text."""
    opts = Options(("check",), ("reference",),
                   models=(_spec("mine", warnings=("w1", "w2")), _spec("plain", "thesis")))
    sec = pipeline._models_section(opts, [])
    assert sec.title == "Models of this run"
    assert sec.blocks[0] == Table(("model", "source", "contact", "warnings"),
                                  (("mine", "mine.toml", "disc", "w1; w2"),
                                   ("plain", "plain.toml", "thesis", "-")))
    assert len(sec.blocks) == 2 and isinstance(sec.blocks[1], Text)
    text = sec.blocks[1].text
    assert "`<scenario>-on-<model>`" in text and "'not run on this model'" in text
    assert "declared limitation, not a failure" in text
    with_skips = pipeline._models_section(opts, [NotRun("benchmark-v4", "mine", "no speeds")])
    assert with_skips.blocks[2] == Table(("scenario", "model", "not run because"),
                                         (("benchmark-v4", "mine", "no speeds"),))
    assert with_skips.comparisons == []
