"""`make mutants`' module-by-module runner (tests/mutation.py): the set it mutates, the test
selection each module gets, and the scratch copy's narrowed configuration. Expected values are
read from pyproject.toml itself with tomllib and fnmatch (the documented meaning of mutmut's
globs), not from the runner."""

from __future__ import annotations

import fnmatch
import tomllib
from pathlib import Path

import pytest

import mutation

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parent.parent
CFG = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))["tool"]


def test_the_set_is_every_hand_written_module_and_nothing_generated():
    modules = mutation.module_set()
    tracked = {str(p.relative_to(ROOT)) for pat in CFG["mutmut"]["only_mutate"]
               for p in ROOT.glob(pat)}
    # every module of the four trees is in, each once, and the generated-code
    # machinery is out
    assert len(modules) == len(set(modules))
    for tree in ("comparisons/judgments/", "comparisons/stages/", "reference_model/", "engines/"):
        assert any(m.startswith(tree) for m in modules), tree
    for engine in ("drake", "dart", "fmu", "symbrim", "exudyn", "kane", "mujoco", "pinocchio"):
        assert f"engines/{engine}/engine.py" in modules, engine
    for out in ("reference_model/equations/codegen.py", "engines/kane/codegen.py",
                "engines/symbrim/derivation.py"):
        assert (ROOT / out).is_file() and out not in modules, out
    assert "engines/symbrim/derivation.py" in tracked   # matched by a glob, then left out
    assert all(m.endswith(".py") for m in modules)


def test_a_module_gets_its_own_selection_or_the_whole_one():
    per = CFG["bicycle-xval"]["mutation"]["tests"]
    pattern, tests = next(iter(per.items()))
    module = next(m for m in mutation.module_set() if fnmatch.fnmatch(m, pattern))
    assert mutation.selection_for(module) == tests
    unmatched = next(m for m in mutation.module_set()
                     if not any(fnmatch.fnmatch(m, p) for p in per))
    assert mutation.selection_for(unmatched) == CFG["mutmut"]["pytest_add_cli_args_test_selection"]
    # every selected test file exists (a typo would make mutmut collect nothing)
    for tests in per.values():
        for t in tests:
            assert t.startswith("-") or (ROOT / t.split("::")[0]).is_file(), t


def test_the_scratch_configuration_narrows_only_the_mutmut_table():
    text = (ROOT / "pyproject.toml").read_text("utf-8")
    out = tomllib.loads(mutation._narrowed(text, "engines/runs.py", ["tests/test_a.py"], 3.0))
    before = tomllib.loads(text)
    mm = out["tool"]["mutmut"]
    assert mm["only_mutate"] == ["engines/runs.py"]
    assert mm["do_not_mutate"] == []
    assert mm["pytest_add_cli_args_test_selection"] == ["tests/test_a.py"]
    assert mm["timeout_multiplier"] == 3.0
    # mutmut's other keys and every other table are kept as they were
    for k in ("source_paths", "also_copy", "pytest_add_cli_args", "process_isolation"):
        assert mm[k] == before["tool"]["mutmut"][k]
    # the mutants' pytest forked from a fork server, not from the process that ran the stats
    # (the sweep's in-process Dask cluster left a loop there that hangs a forked child)
    assert mm["process_isolation"] == "forkserver"
    assert out["project"] == before["project"]
    assert out["tool"]["bicycle-xval"] == before["tool"]["bicycle-xval"]
    assert out["tool"]["pytest"] == before["tool"]["pytest"]


def test_options_in_a_selection_reach_every_run_of_it():
    """mutmut gives its per-mutant runs the node ids and ``pytest_add_cli_args`` only: an option
    left in the selection (the conformance suite's depth, an engine's -k) would be lost there,
    and the mutant run at another depth than the one its tests were recorded at."""
    text = (ROOT / "pyproject.toml").read_text("utf-8")
    sel = ["tests/test_a.py", "comparisons/conformance/test_conformance.py",
           "--conformance-depth=quick", "-k=pinocchio"]
    mm = tomllib.loads(mutation._narrowed(text, "engines/pinocchio/engine.py", sel, None))["tool"]["mutmut"]
    before = tomllib.loads(text)["tool"]["mutmut"]["pytest_add_cli_args"]
    assert mm["pytest_add_cli_args_test_selection"] == sel[:2]
    assert mm["pytest_add_cli_args"] == [*before, "--conformance-depth=quick", "-k=pinocchio"]


def test_a_result_is_stale_once_its_module_changes(tmp_path):
    module = "engines/runs.py"
    res = mutation.Result(module=module, module_sha=mutation._sha([module]),
                          tests_sha=mutation._sha(mutation.selection_for(module)),
                          tests=tuple(mutation.selection_for(module)), killed=3, timeouts=1,
                          survived=("x__mutmut_1",), suspicious=0, not_reached=2, seconds=1.0,
                          when="now", mutmut="3")
    assert res.tried == 6          # killed (timeouts in it) + survived + suspicious + not reached
    assert mutation.current(res)
    assert not mutation.current(
        mutation.Result(**{**res.__dict__, "module_sha": mutation._sha(["engines/base.py"])}))


def test_a_change_inside_a_string_is_text_only_and_any_other_is_not():
    # mutmut's own string mutants: wrapped in XX, case changed, an f-string's literal part
    assert mutation.text_only(['-    raise ValueError(f"bad {x}: use y")',
                               '+    raise ValueError(f"XXbad {x}: use yXX")'])
    assert mutation.text_only(['-    label = "Weave"', '+    label = "weave"'])
    # an operator, a number, a keyword argument's name, a dropped argument: code, not text
    assert not mutation.text_only(['-    a = b + 1', '+    a = b - 1'])
    assert not mutation.text_only(['-    a = f(x, 2.0)', '+    a = f(x, 3.0)'])
    assert not mutation.text_only(['-    a = f(x, dtype=float)', '+    a = f(x, dtype=None)'])
    assert not mutation.text_only(['-    a = f("x", y)', '+    a = f("x", )'])
    # a string turned into None, a key's text (still a string: text only by this rule,
    # which is why the table leaves equivalence to a reader)
    assert not mutation.text_only(['-    a = "x"', '+    a = None'])
    assert mutation.text_only(['-    d["xc"]', '+    d["XXxcXX"]'])


def test_a_line_cut_from_a_longer_statement_is_still_classified():
    # the diff shows one line of a call spread over several: unbalanced brackets
    assert mutation.text_only(['-        num(d), "pass" if ok else "FAIL"))',
                               '+        num(d), "pass" if ok else "fail"))'])
    assert not mutation.text_only(['-        num(d), "pass" if ok else "FAIL"))',
                                   '+        num(d), "pass" if not ok else "FAIL"))'])


def test_a_module_without_functions_has_nothing_to_mutate(tmp_path):
    (tmp_path / "shim.py").write_text('"""doc"""\nfrom x import *  # noqa\nA = 1\nclass C:\n    b = 2\n')
    (tmp_path / "code.py").write_text("class C:\n    def f(self):\n        return 1\n")
    assert not mutation.has_functions("shim.py", tmp_path)
    assert mutation.has_functions("code.py", tmp_path)


# -- the rerun of mutmut's survivors, and the lock ------------------------------------------

def _fake_venv(tmp_path: Path, mutants: dict[str, str | None], scratch: Path) -> Path:
    """A bin/ with the interpreter running these tests as ``python``, and mutmut's mutated file
    ``scratch/mutants/mod.py`` holding each mutant of ``mutants`` as mutmut names it (the
    function ``add`` renamed to the mutant's key; None: a name the file does not have)."""
    import stat
    import sys
    bin_ = tmp_path / "bin"
    bin_.mkdir()
    # pytest without the installed plugins (hypothesis, the project's conformance plugin and
    # the engines it imports: ~4 s a start on the 2-core machine); the fake projects need none
    (bin_ / "python").write_text(
        f'#!/bin/sh\nPYTEST_DISABLE_PLUGIN_AUTOLOAD=1 exec "{sys.executable}" "$@"\n')
    (bin_ / "python").chmod((bin_ / "python").stat().st_mode | stat.S_IXUSR)
    (scratch / "mutants").mkdir(parents=True, exist_ok=True)
    (scratch / "mutants" / "mod.py").write_text("".join(
        body.replace("def add(", f"def {name.rpartition('.')[2]}(") + "\n\n"
        for name, body in mutants.items() if body is not None))
    return bin_


def test_confirm_counts_a_survivor_killed_only_by_the_whole_selection(tmp_path):
    """Of three survivors, the one the selection's test catches is returned; an equivalent
    one and one that cannot be applied are not; the scratch source is restored and the
    rerun copies are removed. Planted: confirm returning every survivor its pytest ran (the
    exit status read the wrong way round) returns the equivalent one too."""
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    original = "def add(a, b):\n    return a + b\n"
    (scratch / "mod.py").write_text(original)
    (scratch / "test_mod.py").write_text("from mod import add\n\n\n"
                                         "def test_add():\n    assert add(2, 3) == 5\n")
    names = ["mod.x_add__mutmut_1", "mod.x_add__mutmut_2", "mod.x_add__mutmut_3"]
    bin_ = _fake_venv(tmp_path, {names[0]: "def add(a, b):\n    return a - b\n",
                                 names[1]: "def add(a, b):\n    return b + a\n",
                                 names[2]: None}, scratch)
    seen = []
    killed = mutation.confirm("mod.py", names, ["test_mod.py"], scratch, bin_,
                              progress=seen.append, workers=2)
    assert killed == (names[0],)
    assert (scratch / "mod.py").read_text() == original
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin", "scratch"]
    assert seen and seen[-1].endswith("rerun 3/3 survivors on the whole selection, 1 killed")


def test_a_methods_mutant_replaces_that_classs_method_only(tmp_path):
    """Two classes with an __init__ each: a mutant of the second class's __init__ (mutmut's
    key names the class) goes into that class, the first is left as it was; a top-level
    function's mutant replaces that function. Written out by hand. ``mutmut apply`` (3.8.1)
    wrote it over the first __init__ of the file: 16 mutants of engines/exudyn/tree.py were
    then counted killed by the rerun, 8 of which survive."""
    scratch = tmp_path / "s"
    (scratch / "mutants").mkdir(parents=True)
    (scratch / "mod.py").write_text(
        "class A:\n    def __init__(self):\n        self.x = 1\n\n\n"
        "class B:\n    def __init__(self):\n        self.y = 2\n\n\n"
        "def f(v):\n    return v + 1\n")
    (scratch / "mutants" / "mod.py").write_text(
        "class A:\n    def __init__(self):\n        self.x = 1\n"
        "    def xǁAǁ__init____mutmut_1(self):\n        self.x = 2\n\n\n"
        "class B:\n    def __init__(self):\n        self.y = 2\n"
        "    def xǁBǁ__init____mutmut_1(self):\n        self.y = 3\n\n\n"
        "def x_f__mutmut_2(v):\n    return v - 1\n")
    assert mutation.mutated_source(scratch, "mod.py", "mod.xǁBǁ__init____mutmut_1") == (
        "class A:\n    def __init__(self):\n        self.x = 1\n\n\n"
        "class B:\n    def __init__(self):\n        self.y = 3\n\n\n"
        "def f(v):\n    return v + 1\n")
    assert mutation.mutated_source(scratch, "mod.py", "mod.x_f__mutmut_2").endswith(
        "def f(v):\n    return v - 1\n")
    assert "self.x = 2" in mutation.mutated_source(scratch, "mod.py", "mod.xǁAǁ__init____mutmut_1")
    assert mutation.mutated_source(scratch, "mod.py", "mod.xǁCǁ__init____mutmut_1") is None


def test_mutated_source_parses_each_file_once_until_it_changes(tmp_path, monkeypatch):
    """Three mutants of one module: the module and its mutated file are parsed once each (the
    mutated file holds every mutant; parsing it per survivor cost ~40 s each on the benchmark
    stage), and a mutated file rewritten since is parsed again, its new text used.
    Planted: no cache (6 parses); a cache keyed by the path alone (the stale mutant)."""
    import libcst
    scratch = tmp_path / "s"
    (scratch / "mutants").mkdir(parents=True)
    (scratch / "mod.py").write_text("def f(v):\n    return v + 1\n")
    mutated = scratch / "mutants" / "mod.py"
    mutated.write_text("def x_f__mutmut_1(v):\n    return v - 1\n"
                       "def x_f__mutmut_2(v):\n    return v * 1\n"
                       "def x_f__mutmut_3(v):\n    return v + 2\n")
    parses = []
    real = libcst.parse_module
    monkeypatch.setattr(libcst, "parse_module", lambda text: parses.append(1) or real(text))
    mutation._parse_file.cache_clear()
    got = [mutation.mutated_source(scratch, "mod.py", f"mod.x_f__mutmut_{i}") for i in (1, 2, 3)]
    assert [g.splitlines()[1] for g in got] == ["    return v - 1", "    return v * 1",
                                                 "    return v + 2"]
    assert len(parses) == 2
    mutated.write_text("def x_f__mutmut_1(v):\n    return v - 10\n")
    assert mutation.mutated_source(scratch, "mod.py", "mod.x_f__mutmut_1").endswith(
        "    return v - 10\n")
    assert len(parses) == 3


def test_a_second_measuring_run_on_the_same_out_stops_at_once(tmp_path):
    """Two runs sharing build/mutation's scratch copies spoiled a module's figures once: the
    second now stops with one line naming the holder, and the lock is free once the first
    ends. (flock locks belong to the open file: a second open in one process conflicts as a
    second process would.)"""
    import os
    import pytest
    with mutation.exclusive(tmp_path):
        assert (tmp_path / ".lock").read_text() == f"{os.getpid()}\n"
        with pytest.raises(SystemExit, match=rf"^error: another measuring run \(pid "
                                             rf"{os.getpid()}\) holds .*; wait for it"):
            with mutation.exclusive(tmp_path):
                pass
    with mutation.exclusive(tmp_path):     # free again
        pass


def test_a_shared_fixtures_work_is_credited_to_every_test_that_uses_it(pytester):
    """mutmut credits what a module fixture calls to the first test using it alone, so a mutant
    there never ran the later tests that read the fixture's result. With the credit plugin each
    test using the fixture is credited with the fixture's functions; a test not using it is not.
    The expected sets are written from the inner tests' own calls (independent of the plugin)."""
    from mutation_credit import FixtureCredit

    hits: set[str] = set()
    credited: dict[str, set[str]] = {}

    class Collector:          # mutmut's StatsCollector, reduced to its teardown
        def pytest_runtest_teardown(self, item, nextitem):
            credited[item.name] = set(hits)
            hits.clear()

    pytester.makepyfile(test_inner="""
        import pytest
        HITS = None
        @pytest.fixture(scope="module")
        def shared():
            HITS.add("model.solve")
            return 1
        @pytest.fixture
        def own(shared):
            HITS.add("model.own")
        def test_first(shared):
            HITS.add("judge.first")
        def test_second(shared):
            pass
        def test_through_another(own):
            pass
        def test_unrelated():
            HITS.add("judge.unrelated")
    """)

    class Inject:
        def pytest_collection_modifyitems(self, items):
            items[0].module.HITS = hits

    result = pytester.inline_run("-p", "no:cacheprovider",
                                 plugins=[FixtureCredit(lambda: hits), Collector(), Inject()])
    result.assertoutcome(passed=4)
    assert credited == {"test_first": {"model.solve", "judge.first"},
                        "test_second": {"model.solve"},
                        "test_through_another": {"model.solve", "model.own"},
                        "test_unrelated": {"judge.unrelated"}}


def test_a_mutants_tests_run_cheapest_file_first_each_file_whole_and_in_order():
    """The order is worked out by hand: a.py's tests took 3 s in all, b.py's 0.5 s, c.py has a
    test never measured (last, as does a file never measured); each file's tests stay together
    in their own order, and the ids mutmut gives with its ``mutants/`` prefix match too."""
    from mutation_order import file_order

    seconds = {"tests/a.py::t1": 1.0, "tests/a.py::t2": 2.0, "tests/b.py::t1": 0.5,
               "mutants/tests/c.py::t1": 0.0}
    given = ["tests/a.py::t2", "tests/c.py::t1", "tests/b.py::t1", "tests/a.py::t1",
             "tests/c.py::t2", "tests/d.py::t1"]
    assert file_order(given, seconds) == [
        "tests/b.py::t1", "tests/a.py::t2", "tests/a.py::t1", "tests/c.py::t1", "tests/c.py::t2",
        "tests/d.py::t1"]
    assert file_order([], seconds) == []


def test_the_stats_run_records_seconds_and_a_mutants_run_reads_them(pytester):
    """End to end through pytest: the stats half writes each test's seconds (a 0.2 s sleep
    in the slow file's fixture counts for its test), the mutant half then runs the quick file
    first although pytest collects the slow one first; the forced-fail run keeps pytest's."""
    from mutation_order import SECONDS_FILE, register

    pytester.makepyfile(
        test_a_slow="""
            import time, pytest
            @pytest.fixture
            def build():
                time.sleep(0.2)
            def test_slow(build):
                pass
        """,
        test_b_quick="""
            def test_quick():
                pass
        """)
    order: list[str] = []

    class Seen:
        def pytest_runtest_logstart(self, nodeid, location):
            order.append(nodeid.split("::")[1])

    class Register:
        def __init__(self, mutant):
            self.mutant = mutant

        def pytest_configure(self, config):
            register(config, self.mutant, pytester.path)

    pytester.inline_run("-p", "no:cacheprovider", plugins=[Register("stats"), Seen()])
    assert order == ["test_slow", "test_quick"]                       # pytest's own order
    seconds = __import__("json").loads((pytester.path / SECONDS_FILE).read_text())
    assert seconds["test_a_slow.py::test_slow"] >= 0.2 > seconds["test_b_quick.py::test_quick"]
    order.clear()
    pytester.inline_run("-p", "no:cacheprovider",
                        plugins=[Register("engines.batching.x_batched__mutmut_3"), Seen()])
    assert order == ["test_quick", "test_slow"]
    order.clear()
    pytester.inline_run("-p", "no:cacheprovider", plugins=[Register("fail"), Seen()])
    assert order == ["test_slow", "test_quick"]


def test_every_listed_equivalent_is_filed_under_the_module_it_mutates():
    """A mutant's name starts with its module's dotted path: an entry under another module's
    table is never matched (seen: 13 of diagnose's entries appended under the stages runs'
    table), and each entry gives its reason."""
    root = Path(__file__).resolve().parents[1]
    listed = tomllib.loads((root / "tests" / "mutation_equivalents.toml").read_text("utf-8"))
    misfiled = [(module, name) for module, names in listed.items() for name in names
                if not name.startswith(module.removesuffix(".py").replace("/", ".") + ".x")]
    assert not misfiled, misfiled
    assert all(reason.strip() for names in listed.values() for reason in names.values())
    assert all((root / module).is_file() for module in listed)


# -- the committed results: table and refresh --------------------------------------------

def _result(module, root, **kw):
    base = dict(module=module, module_sha=mutation._sha([module], root),
                tests_sha="old", tests=("tests/test_mod.py",), killed=5, timeouts=2,
                survived=(), suspicious=0, not_reached=1, seconds=1.0,
                when="2026-12-06 01:00 UTC", mutmut="3.8.1")
    return mutation.Result(**{**base, **kw})


def test_the_table_shows_timeouts_apart_and_sums_them(tmp_path):
    """A measured module's row gives its timeouts beside its killed (they count as killed) and
    the sum row adds them; a module without a result is listed as not measured. The figures
    are the result's own, written here."""
    module = "engines/runs.py"
    mutation._save(_result(module, ROOT, killed=7, timeouts=3, survived=("a", "b"),
                           diffs={"a": ['-    x = "a"', '+    x = "XXaXX"']}), tmp_path)
    text = mutation.table(tmp_path, tmp_path / "no-readings.toml")
    head = text.splitlines()[0]
    assert "| timeouts |" in head
    row = next(ln for ln in text.splitlines() if ln.startswith(f"| `{module}`"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    # module, tried, killed, %, timeouts, survived, text only, equivalent, left, not reached
    # the one mutant no test reaches is tried and not killed: 7 of 10
    assert cells[1:10] == ["10", "7", "70.0 %", "3", "2", "1", "0", "2", "1"]
    total = next(ln for ln in text.splitlines() if ln.startswith("| **1 measured**"))
    assert [c.strip() for c in total.strip("|").split("|")][1:5] == ["10", "7", "70.0 %", "3"]
    assert "`engines/base.py`" in text.split("Not measured yet")[1]


def _refresh_tree(tmp_path):
    """A project of one module with one survivor the new test kills and one it does not, its
    scratch copy left by a measurement holding the old test (which kills neither)."""
    root = tmp_path / "root"
    (root / "tests").mkdir(parents=True)
    (root / "pyproject.toml").write_text(
        '[tool.mutmut]\nonly_mutate = ["mod.py"]\npytest_add_cli_args_test_selection = []\n'
        '[tool.bicycle-xval.mutation.tests]\n"mod.py" = ["tests/test_mod.py"]\n')
    original = "def add(a, b):\n    return a + b\n"
    (root / "mod.py").write_text(original)
    (root / "tests" / "test_mod.py").write_text(
        "from mod import add\n\n\ndef test_add():\n    assert add(2, 3) == 5\n")
    scratch = tmp_path / "out" / "mod"
    (scratch / "mutants").mkdir(parents=True)
    (scratch / "tests").mkdir()
    (scratch / "mod.py").write_text(original)
    (scratch / "tests" / "test_mod.py").write_text("def test_nothing():\n    pass\n")
    names = ["mod.x_add__mutmut_1", "mod.x_add__mutmut_2"]
    bin_ = _fake_venv(tmp_path, {names[0]: "def add(a, b):\n    return a - b\n",
                                 names[1]: "def add(a, b):\n    return b + a\n"}, scratch)
    return root, scratch, names, bin_


def test_refresh_runs_the_survivors_against_the_tests_written_since(tmp_path):
    """Of two survivors the new test kills one (a - b; b + a is equivalent): it moves to
    killed_on_rerun, the killed count grows by one, and the result takes the selection's
    current hash so the table no longer calls it stale. Planted: the scratch copy's old test
    kept (nothing killed)."""
    root, scratch, names, bin_ = _refresh_tree(tmp_path)
    results = tmp_path / "results"
    mutation._save(_result("mod.py", root, survived=tuple(names)), results)
    new = mutation.refresh("mod.py", out=tmp_path / "out", results=results, root=root,
                           venv_bin=bin_, children=1, progress=lambda *a: None)
    assert new.survived == (names[1],)
    assert new.killed_on_rerun == (names[0],)
    assert (new.killed, new.tried) == (6, 8)     # the result's one unreached mutant is tried
    assert new.tests_sha == mutation._sha(["tests/test_mod.py"], root) and new.refreshed
    assert mutation.load_result("mod.py", results) == new
    assert (scratch / "mod.py").read_text() == (root / "mod.py").read_text()


def test_refresh_runs_the_mutants_no_test_reached_and_counts_the_ones_killed_now(tmp_path):
    """A mutant mutmut recorded as reached by no test (exit code 33 in the scratch copy's
    .meta) runs against the tests written since: the new test kills a - b, which leaves the
    not-reached count and joins the killed; b + a (equivalent) stays not reached, not a
    survivor nobody listed. A .meta that does not name every unreached mutant runs none.
    Planted: the .meta's exit code read as 1 (nothing run); the count not lowered."""
    import json
    root, scratch, names, bin_ = _refresh_tree(tmp_path)
    (scratch / "mutants" / "mod.py.meta").write_text(json.dumps(
        {"exit_code_by_key": {names[0]: 33, names[1]: 33, "mod.x_add__mutmut_3": 1}}))
    results = tmp_path / "results"
    kw = dict(out=tmp_path / "out", results=results, root=root, venv_bin=bin_, children=1,
              progress=lambda *a: None)
    mutation._save(_result("mod.py", root, survived=(), not_reached=2), results)
    new = mutation.refresh("mod.py", **kw)
    assert (new.killed, new.survived, new.not_reached, new.tried) == (6, (), 1, 7)
    assert new.killed_on_rerun == (names[0],)
    mutation._save(_result("mod.py", root, survived=(), not_reached=3), results)
    assert mutation.refresh("mod.py", **kw).not_reached == 3


def test_refresh_added_only_runs_the_files_added_since_and_not_the_old_ones(tmp_path):
    """With ``added_only`` the survivors run against the files the measurement did not have:
    the new test kills a - b as before, and the old file (which writes a marker when it runs)
    is not run for any survivor; with no file added it refuses in one line. Planted: the whole
    selection run (the marker appears); the filter inverted (the new file skipped, nothing
    killed)."""
    import pytest
    root, scratch, names, bin_ = _refresh_tree(tmp_path)
    marker = tmp_path / "old-ran"
    (root / "tests" / "test_old.py").write_text(
        f"def test_old():\n    open({str(marker)!r}, 'a').write('x')\n")
    text = (root / "pyproject.toml").read_text()
    (root / "pyproject.toml").write_text(text.replace(
        '"mod.py" = ["tests/test_mod.py"]', '"mod.py" = ["tests/test_old.py", "tests/test_mod.py"]'))
    results = tmp_path / "results"
    kw = dict(out=tmp_path / "out", results=results, root=root, venv_bin=bin_, children=1,
              progress=lambda *a: None, added_only=True)
    mutation._save(_result("mod.py", root, survived=tuple(names), tests=("tests/test_old.py",)),
                   results)
    new = mutation.refresh("mod.py", **kw)
    assert new.killed_on_rerun == (names[0],) and new.survived == (names[1],)
    assert not marker.exists()
    assert new.tests_sha == mutation._sha(["tests/test_old.py", "tests/test_mod.py"], root)
    mutation._save(_result("mod.py", root, survived=(names[1],),
                           tests=("tests/test_old.py", "tests/test_mod.py")), results)
    with pytest.raises(SystemExit, match=r"^error: mod.py: no test file was added to its "
                                         r"selection since its measurement"):
        mutation.refresh("mod.py", **kw)


def test_refresh_refuses_what_it_cannot_bring_up_to_date(tmp_path):
    """Not measured, the module changed since (its other mutants may differ), or the scratch
    copy gone: each one line saying to measure."""
    import pytest
    root, scratch, names, bin_ = _refresh_tree(tmp_path)
    results = tmp_path / "results"
    kw = dict(out=tmp_path / "out", results=results, root=root, venv_bin=bin_,
              progress=lambda *a: None)
    with pytest.raises(SystemExit, match=r"^error: mod.py has not been measured; run "):
        mutation.refresh("mod.py", **kw)
    mutation._save(_result("mod.py", root, survived=tuple(names), module_sha="x"), results)
    with pytest.raises(SystemExit, match=r"^error: mod.py changed since it was measured"):
        mutation.refresh("mod.py", **kw)
    mutation._save(_result("mod.py", root, survived=tuple(names)), results)
    __import__("shutil").rmtree(scratch / "mutants")
    with pytest.raises(SystemExit, match=r"^error: the scratch copy .* is gone; measure mod.py"):
        mutation.refresh("mod.py", **kw)


def test_a_module_no_fast_test_reaches_is_a_result_not_a_failure(tmp_path):
    """mutmut stops with exit 1 when no selected test runs any mutated function (the FMU's
    co-simulation runs only in slow tests): the module is recorded with its every mutant 'not
    reached' and none tried, and a run of several modules goes on. A mutmut failure of any
    other kind still stops with the end of its log."""
    import stat
    import sys

    import pytest
    root = tmp_path / "root"
    (root / "tests").mkdir(parents=True)
    (root / "pyproject.toml").write_text(
        '[tool.mutmut]\nonly_mutate = ["mod.py"]\npytest_add_cli_args_test_selection = []\n'
        '[tool.bicycle-xval.mutation.tests]\n"mod.py" = ["tests/test_mod.py"]\n')
    (root / "mod.py").write_text("def add(a, b):\n    return a + b\n")
    (root / "tests" / "test_mod.py").write_text("def test_other():\n    pass\n")
    bin_ = tmp_path / "bin"
    bin_.mkdir()

    def fake_mutmut(run_says: str) -> None:
        (bin_ / "mutmut").write_text(
            f"#!{sys.executable}\nimport sys\n"
            "if sys.argv[1] == 'run':\n"
            f"    print({run_says!r})\n    sys.exit(1)\n"
            "if sys.argv[1] == 'results':\n"
            "    print('    mod.x_add__mutmut_1: not checked')\n"
            "    print('    mod.x_add__mutmut_2: not checked')\n"
            "if sys.argv[1] == '--version':\n    print('mutmut, version 3.8.1')\n")
        (bin_ / "mutmut").chmod((bin_ / "mutmut").stat().st_mode | stat.S_IXUSR)

    fake_mutmut("Stopping early, because we could not find any test case for any mutant. It "
                "seems that the selected tests do not cover any code that we mutated.")
    kw = dict(out=tmp_path / "out", results=tmp_path / "results", root=root, venv_bin=bin_,
              progress=lambda *a: None)
    res = mutation.measure("mod.py", **kw)
    assert (res.tried, res.killed, res.not_reached, res.survived) == (2, 0, 2, ())
    assert mutation.load_result("mod.py", tmp_path / "results") == res

    fake_mutmut("Traceback (most recent call last):\nImportError: no module named x")
    with pytest.raises(SystemExit, match=r"(?s)^error: mutmut failed on mod.py \(exit 1\).*"
                                         r"ImportError: no module named x"):
        mutation.measure("mod.py", **kw)


def test_an_earlier_reading_stands_in_for_a_missing_result_and_is_summed_apart(tmp_path):
    """A module with no committed result but an earlier round's reading gets a row marked as
    that reading (its flags spelt out), the committed results keep their own sum, and the last
    row adds both: 7 of 9 and 40 of 50 are 47 of 59 (79.7 %). A committed result wins over a
    reading of the same module. The figures are written here."""
    results, path = tmp_path / "results", tmp_path / "readings.toml"
    mutation._save(_result("engines/runs.py", ROOT, killed=7, timeouts=0, survived=("a", "b")),
                   results)
    path.write_text('["engines/base.py"]\ntried = 50\nkilled = 40\nround = "fourth"\n'
                    'date = "2026-12-02"\nsweep_tests = true\nstopped = true\n'
                    'same_name_rerun = true\n'
                    '["engines/runs.py"]\ntried = 1\nkilled = 0\nround = "third"\n'
                    'date = "2026-12-02"\n')
    text = mutation.table(results, path)
    lines = text.splitlines()
    row = next(ln for ln in lines if ln.startswith("| `engines/base.py`"))
    assert row.startswith("| `engines/base.py` | 50 | 40 | 80.0 % |")
    assert row.endswith("| reading of the fourth round (2026-12-02), its selection starts the "
                        "sweep's Dask tests, stopped before its end, its rerun may have put a "
                        "survivor into another method of its name |")
    runs = [ln for ln in lines if ln.startswith("| `engines/runs.py`")]
    assert len(runs) == 1 and runs[0].startswith("| `engines/runs.py` | 10 | 7 |")
    assert any(ln.startswith("| **1 measured** | 10 | 7 | 70.0 % |") for ln in lines)
    assert any(ln.startswith("| **2 measured, 1 of them earlier readings** | 60 | 47 | 78.3 % |")
               for ln in lines)
    assert "`engines/base.py`" not in text.split("Not measured yet")[1]


def test_a_rerun_refuses_a_selection_that_fails_on_the_unmutated_copy(tmp_path):
    """Today's tests run on a scratch copy measured before a change they expect fail for every
    survivor: all would count as killed (seen: the FMU mapping's four equivalent mutants
    'killed' by a co-simulation test written for code changed since). The rerun runs the
    selection on the unmutated copy first and stops in one line saying to measure again."""
    import pytest
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    (scratch / "mod.py").write_text("def add(a, b):\n    return a + b\n")
    (scratch / "test_mod.py").write_text("from mod import add\n\n\n"
                                         "def test_add():\n    assert add(2, 3) == 6\n")
    names = ["mod.x_add__mutmut_1"]
    bin_ = _fake_venv(tmp_path, {names[0]: "def add(a, b):\n    return a - b\n"}, scratch)
    with pytest.raises(SystemExit, match=r"^error: mod.py: its selection fails on the unmutated "
                                         r"scratch copy .*: measure mod.py again$"):
        mutation.confirm("mod.py", names, ["test_mod.py"], scratch, bin_, progress=lambda *a: None)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin", "scratch"]


# -- the README's generated blocks ---------------------------------------------------------

def test_the_readme_holds_the_current_table_and_list_of_equivalents():
    """README.md's table and list of equivalent mutants are what the committed results,
    readings and equivalents give (`make mutants-readme` writes them). Planted: one committed
    result's killed count raised by one, and one equivalent's reason reworded: each fails."""
    readme = (mutation.ROOT / "README.md").read_text("utf-8")
    assert mutation.with_readme_blocks(readme, mutation.readme_blocks()) == readme, (
        "README.md's mutation table or equivalents list is out of date: run make mutants-readme")


def test_the_equivalents_list_names_each_mutant_within_its_module_with_its_reason(tmp_path):
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "mutation_equivalents.toml").write_text(
        '["engines/b.py"]\n"engines.b.x_f__mutmut_2" = "a default\\n  always overridden"\n'
        '["engines/a.py"]\n"engines.a.xǁCǁm__mutmut_1" = "r1"\n"engines.a.x_g__mutmut_3" = "r3"\n')
    assert mutation.equivalents_list(tmp_path).splitlines() == [
        "3 equivalent mutants in 2 modules, each with the reason it cannot change what a user "
        "or caller relies on (`tests/mutation_equivalents.toml`):", "",
        "- `engines/a.py` (2)", "  - `xǁCǁm__mutmut_1`: r1", "  - `x_g__mutmut_3`: r3",
        "- `engines/b.py` (1)", "  - `x_f__mutmut_2`: a default always overridden"]


def test_readme_blocks_are_replaced_between_their_markers_and_a_missing_one_is_named():
    text = ("intro\n<!-- mutants-table: note -->\nold\nrows\n<!-- /mutants-table -->\n"
            "middle\n<!-- mutants-equivalents: x -->\n<!-- /mutants-equivalents -->\nend\n")
    out = mutation.with_readme_blocks(text, {"mutants-table": "T\n", "mutants-equivalents": "E\n"})
    assert out == ("intro\n<!-- mutants-table: note -->\nT\n<!-- /mutants-table -->\n"
                   "middle\n<!-- mutants-equivalents: x -->\nE\n<!-- /mutants-equivalents -->\nend\n")
    with pytest.raises(SystemExit, match=r"README.md has no '<!-- mutants-list: \.\.\. -->'"):
        mutation.with_readme_blocks(text, {"mutants-list": "L\n"})
