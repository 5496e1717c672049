"""Mutation testing module by module (``make mutants``): mutmut over one module at a time, each
against its own fast test selection, results kept per module and summed into one table.

    python tests/mutation.py comparisons/judgments/rows.py     # one module (or several)
    python tests/mutation.py --all                             # every module not yet measured
    python tests/mutation.py --table                           # the per-module scores so far
    python tests/mutation.py --list                            # the set and each selection
    python tests/mutation.py --refresh MODULE                  # its survivors against new tests

Why not one ``mutmut run`` over the whole set: mutmut generates every mutant of every module
before it runs any (33 700 mutants in 109 files: 20 min on the project's 2-core machine) and
then runs the whole test selection once for its coverage table (11 min), and a change to one
module or test starts it all again. Here each module is mutated in a scratch copy of the tree
(``build/mutation/<module>/``) whose ``[tool.mutmut]`` names only that module and only the
test files that reach it (``[tool.bicycle-xval.mutation.tests]`` in pyproject.toml; the
whole selection where no entry matches), so a module of a few hundred mutants takes minutes.
The result of each module is written to ``tests/mutation_results/<module>.json`` (committed:
a module's measurement costs minutes to an hour, and a new machine or a fresh clone starts
without ``build/``) with the hashes of the module and of its tests: ``--all`` skips the
modules whose result is still current, so an interrupted ``make mutants`` resumes where it
stopped, and ``--table`` marks a result whose module or tests changed since as stale.
``--refresh`` brings a result whose module is unchanged up to date with tests written after
it: its survivors are run against the module's current selection (as the rerun below), which
is all that can change when tests are only added.

mutmut runs each mutant in a process forked from a fork server that has imported pytest and
collected the tests but run none (``process_isolation = "forkserver"``), not from its main
process, which has run the whole selection once for its stats: a child forked from there
inherits the event loop and threads that the tests' in-process Dask cluster left behind, and
hangs. Measured on ``comparisons/stages/sweep_deadline.py``: forked from the main process,
every mutant timed out, renaming a thread included, and would have counted as killed; from the
fork server, 23 of 55 were killed, 32 survived and none timed out. Timeouts are shown apart in
the table for that reason.

Surviving mutants that cannot change any behaviour a user or caller relies on are listed, each
with its reason, in ``tests/mutation_equivalents.toml``; the table counts them apart from the
survivors left to kill. mutmut runs each mutant only against the tests that executed its
function in its first run, which misses what a module- or session-scoped fixture built for
many tests; so each of mutmut's survivors is run once more, applied alone to the scratch copy,
against the module's whole selection (``--no-rerun`` skips it), and counted as killed if a test
fails there. Counting: tried = killed + survived + suspicious + not reached (timeouts are in
killed, as mutmut counts them, and so is a test run that died by a signal, mutmut's
'segfault': SIGSEGV, or the SIGKILL a mutant of the pool sends its own process group); a
mutant that no selected test reaches is shown apart, as 'not reached', and counts as not
killed: no test could catch it.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import datetime
import fnmatch
import functools
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import time
import tomllib
from pathlib import Path

__all__ = ["Result", "confirm", "equivalents", "exclusive", "main", "measure", "module_set",
           "refresh", "selection_for", "survivors", "has_functions", "table", "text_only"]

ROOT = Path(__file__).resolve().parent.parent
#: the committed measurements, one JSON file per module
RESULTS = ROOT / "tests" / "mutation_results"
#: the earlier rounds' readings of modules with no committed result (tried and killed only)
READINGS = ROOT / "tests" / "mutation_readings.toml"
#: what mutmut prints when it stops because no selected test executes any mutated function
NOTHING_REACHED = "could not find any test case for any mutant"
#: what the scratch copy leaves out: the virtualenv, git, generated reports and caches
COPY_IGNORE = (".venv", ".git", "build", "mutants", "reports", ".cache", "__pycache__",
               ".pytest_cache", ".hypothesis", "*.egg-info", "mutants.log")


@dataclasses.dataclass(frozen=True)
class Result:
    """One module's measurement (``build/mutation/results/<slug>.json``)."""

    module: str
    module_sha: str           # sha256 of the module's source when measured
    tests_sha: str            # sha256 over its selected test files
    tests: tuple[str, ...]
    killed: int               # failing tests, timeouts included
    timeouts: int
    survived: tuple[str, ...]  # mutant names
    suspicious: int
    not_reached: int          # no selected test executes the mutated function
    seconds: float
    when: str
    mutmut: str
    #: each survivor's changed lines ('-' old, '+' new, from ``mutmut show``)
    diffs: dict[str, list[str]] = dataclasses.field(default_factory=dict)
    #: mutants mutmut let survive that the module's whole selection kills when run on the
    #: mutant alone (`confirm`): counted as killed
    killed_on_rerun: tuple[str, ...] = ()
    #: when the survivors were last run against tests written after the measurement
    #: (`refresh`); empty if never
    refreshed: str = ""

    @property
    def tried(self) -> int:
        """Every mutant of the module: the ones no selected test reaches are not killed."""
        return self.killed + len(self.survived) + self.suspicious + self.not_reached

    @property
    def text_only(self) -> tuple[str, ...]:
        """The survivors whose change is inside string literals only (`text_only`)."""
        return tuple(n for n in self.survived if n in self.diffs and text_only(self.diffs[n]))


def _tokens(lines: list[str]) -> list[str] | None:
    """The tokens of ``lines`` with every string literal's contents replaced by one marker
    (lines of a statement the diff cut keep the tokens they have); None if they do not
    tokenize."""
    import io
    import tokenize
    src = "\n".join(ln.strip() for ln in lines) + "\n"
    toks = []
    try:
        for tok in tokenize.generate_tokens(io.StringIO(src).readline):
            toks.append(tok)
    except tokenize.TokenError:
        pass     # a line of a statement cut by the diff (an open bracket): its tokens so far
    except (IndentationError, SyntaxError):
        return None
    skip = {tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT, tokenize.COMMENT,
            tokenize.ENDMARKER}
    return ["<str>" if t.type == tokenize.STRING else t.string for t in toks if t.type not in skip]


def text_only(diff: list[str]) -> bool:
    """Whether a mutant's changed lines differ only inside string literals: the wording or
    case of a message, a label or report prose (the code around it is the same). Whether such
    a text is a contract (a key, a file name, a column) still needs a reader."""
    old = _tokens([ln[1:] for ln in diff if ln.startswith("-")])
    new = _tokens([ln[1:] for ln in diff if ln.startswith("+")])
    return old is not None and old == new


def _pyproject(root: Path) -> dict:
    return tomllib.loads((root / "pyproject.toml").read_text("utf-8"))


def module_set(root: Path = ROOT) -> list[str]:
    """Every module ``[tool.mutmut]`` mutates: ``only_mutate``'s globs less ``do_not_mutate``'s."""
    cfg = _pyproject(root)["tool"]["mutmut"]
    files = sorted(str(p.relative_to(root)) for pattern in cfg["only_mutate"]
                   for p in root.glob(pattern) if p.is_file() and p.suffix == ".py")
    return [f for f in dict.fromkeys(files)
            if not any(fnmatch.fnmatch(f, pat) for pat in cfg.get("do_not_mutate", ()))]


def selection_for(module: str, root: Path = ROOT) -> list[str]:
    """The fast test selection of ``module``: the first ``[tool.bicycle-xval.mutation.tests]``
    entry whose glob matches it, else ``[tool.mutmut]``'s whole selection."""
    data = _pyproject(root)
    per = data.get("tool", {}).get("bicycle-xval", {}).get("mutation", {}).get("tests", {})
    for pattern, tests in per.items():
        if fnmatch.fnmatch(module, pattern):
            return list(tests)
    return list(data["tool"]["mutmut"]["pytest_add_cli_args_test_selection"])


def has_functions(module: str, root: Path = ROOT) -> bool:
    """Whether ``module`` defines a function or method: mutmut mutates nothing else, so a
    module of re-exports and constants has no mutants (no run needed to know it)."""
    import ast
    tree = ast.parse((root / module).read_text("utf-8"))
    return any(isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) for n in ast.walk(tree))


def slug(module: str) -> str:
    return module.removesuffix(".py").replace("/", ".")


def _sha(paths, root: Path = ROOT) -> str:
    h = hashlib.sha256()
    for p in paths:
        h.update(p.encode())
        f = root / p.split("::")[0]
        h.update(f.read_bytes() if f.is_file() else b"-")
    return h.hexdigest()


def _narrowed(text: str, module: str, tests: list[str], children_timeout: float | None) -> str:
    """pyproject.toml with ``[tool.mutmut]``'s ``only_mutate`` and test selection narrowed.

    Entries of ``tests`` that start with ``-`` are pytest options written as one word
    (``--conformance-depth=quick``, ``-k=pinocchio``): they go to ``pytest_add_cli_args``,
    which mutmut gives every run, the per-mutant ones included (it gives those the node ids
    only, not the selection), so the conformance suite's tests of one engine at one depth are
    the same tests in every run."""
    lines = text.splitlines(keepends=True)
    start = next(i for i, ln in enumerate(lines) if ln.strip() == "[tool.mutmut]")
    end = next((i for i in range(start + 1, len(lines)) if re.match(r"^\s*\[", lines[i])),
               len(lines))
    cfg = dict(tomllib.loads("".join(lines[start:end]))["tool"]["mutmut"])
    cfg["only_mutate"] = [module]
    cfg["do_not_mutate"] = []
    options = [t for t in tests if t.startswith("-")]
    cfg["pytest_add_cli_args_test_selection"] = [t for t in tests if not t.startswith("-")]
    cfg["pytest_add_cli_args"] = [*cfg.get("pytest_add_cli_args", []), *options]
    if children_timeout is not None:
        cfg["timeout_multiplier"] = children_timeout
    body = "".join(f"{k} = {json.dumps(v)}\n" for k, v in cfg.items())   # JSON's lists are TOML's
    return "".join(lines[:start]) + "[tool.mutmut]\n" + body + "\n" + "".join(lines[end:])


@contextlib.contextmanager
def exclusive(out: Path):
    """One measuring run per ``out`` at a time: two share the scratch copies
    (``out/<module>``) and spoil each other's figures (seen once: one module's run not
    reportable). An advisory lock on ``out/.lock``, released when the process ends however it
    ends; a second run stops at once with a one-line error."""
    import fcntl
    out.mkdir(parents=True, exist_ok=True)
    with open(out / ".lock", "a+") as fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            fh.seek(0)
            holder = fh.read().strip() or "?"
            raise SystemExit(f"error: another measuring run (pid {holder}) holds {out / '.lock'}; "
                             "wait for it to end, or give another --out") from None
        fh.seek(0)
        fh.truncate()
        fh.write(f"{os.getpid()}\n")
        fh.flush()
        try:
            yield
        finally:
            fh.seek(0)
            fh.truncate()
            fcntl.flock(fh, fcntl.LOCK_UN)


def _mutmut(venv_bin: Path, scratch: Path, *args: str, log=None) -> subprocess.CompletedProcess:
    return subprocess.run([str(venv_bin / "mutmut"), *args], cwd=scratch, text=True,
                          stdout=log or subprocess.PIPE, stderr=subprocess.STDOUT, check=False)


def measure(module: str, *, children: int = 2, out: Path = ROOT / "build" / "mutation",
            results: Path = RESULTS, timeout_multiplier: float | None = None,
            rerun: bool = True, progress=print, root: Path = ROOT,
            venv_bin: Path | None = None) -> Result:
    """Mutate ``module`` alone in a scratch copy under ``out`` and run its selection; the
    result is written to ``results/<slug>.json`` and returned."""
    if module not in module_set(root):
        raise SystemExit(f"error: {module} is not in [tool.mutmut]'s set (see --list); give a "
                         "path relative to the repository, e.g. comparisons/judgments/rows.py")
    tests = selection_for(module, root)
    scratch = out / slug(module)
    if scratch.exists():
        shutil.rmtree(scratch)
    shutil.copytree(root, scratch, ignore=shutil.ignore_patterns(*COPY_IGNORE), symlinks=True)
    (scratch / "pyproject.toml").write_text(
        _narrowed((root / "pyproject.toml").read_text("utf-8"), module, tests, timeout_multiplier),
        "utf-8")
    venv_bin = venv_bin or Path(sys.executable).parent
    progress(f"{module}: mutating in {scratch} against {len(tests)} test selection(s) ...")
    t0 = time.perf_counter()
    with open(scratch / "mutants.log", "w") as log:
        run = _mutmut(venv_bin, scratch, "run", "--max-children", str(children), log=log)
    log_text = (scratch / "mutants.log").read_text(errors="replace")
    # mutmut stops (exit 1) when no selected test reaches any mutant: the module's every
    # mutant is then 'not reached', a result like any other (its code runs only in the slow
    # tests or in other processes), not a failure that ends a run of several modules
    unreached = run.returncode != 0 and NOTHING_REACHED in log_text
    if run.returncode != 0 and not unreached:
        tail = log_text.splitlines()[-15:]
        raise SystemExit(f"error: mutmut failed on {module} (exit {run.returncode}); the end of "
                         f"{scratch / 'mutants.log'}:\n" + "\n".join(tail))
    seconds = time.perf_counter() - t0
    listed = _mutmut(venv_bin, scratch, "results", "--all", "true").stdout
    status: dict[str, str] = {}
    for line in listed.splitlines():
        name, sep, what = line.strip().rpartition(": ")
        if sep and name:
            status[name] = what.strip()
    if unreached:
        status = dict.fromkeys(status, "no tests")
    count = lambda s: sum(1 for v in status.values() if v == s)
    survivors = sorted(n for n, v in status.items() if v == "survived")
    rerun_killed = (confirm(module, survivors, tests, scratch, venv_bin, progress, children)
                    if rerun else ())
    survivors = [n for n in survivors if n not in rerun_killed]
    diffs = _diffs(venv_bin, scratch, survivors, module)
    version = subprocess.run([str(venv_bin / "mutmut"), "--version"], capture_output=True,
                             text=True).stdout.split()[-1]
    res = Result(module=module, module_sha=_sha([module], root), tests_sha=_sha(tests, root),
                 tests=tuple(tests),
                 killed=(count("killed") + count("timeout") + count("segfault")
                         + len(rerun_killed)),
                 timeouts=count("timeout"),
                 survived=tuple(survivors),
                 suspicious=count("suspicious"), not_reached=count("no tests"),
                 seconds=round(time.perf_counter() - t0, 1), diffs=diffs,
                 killed_on_rerun=tuple(rerun_killed),
                 when=_now(), mutmut=version)
    _save(res, results)
    progress(f"{module}: {res.killed}/{res.tried} killed ({_pct(res.killed, res.tried)}), "
             f"{len(res.survived)} survived ({len(res.text_only)} of them in a text only), "
             f"{res.not_reached} not reached, {seconds:.0f} s"
             + (f" (+ {len(res.killed_on_rerun)} killed on the rerun, {res.seconds - seconds:.0f} s)"
                if rerun else ""))
    return res


def _diffs(venv_bin: Path, scratch: Path, names, module: str) -> dict[str, list[str]]:
    """Each mutant's changed lines: the module's source against `mutated_source` (its mutated
    file parsed once), else (a mutant it does not find) from ``mutmut show`` in the scratch
    copy, a process that parses that file again (~5 s a survivor, 40 min for Exudyn's
    engine's 489)."""
    import difflib
    out = {}
    orig = (scratch / module).read_text("utf-8").splitlines()
    for name in names:
        text = mutated_source(scratch, module, name)
        if text is not None:
            shown = list(difflib.unified_diff(orig, text.splitlines(), lineterm="", n=0))
        else:
            shown = _mutmut(venv_bin, scratch, "show", name).stdout.splitlines()
        out[name] = [ln for ln in shown if ln[:1] in "-+" and not ln.startswith(("---", "+++"))]
    return out


def _function(tree, cls: str | None, name: str):
    """The top-level function ``name``, or method ``name`` of class ``cls``, of a libcst
    module (None if there is none)."""
    import libcst as cst
    for child in tree.body:
        if cls is None and isinstance(child, cst.FunctionDef) and child.name.value == name:
            return child
        if cls is not None and isinstance(child, cst.ClassDef) and child.name.value == cls:
            for item in child.body.body:
                if isinstance(item, cst.FunctionDef) and item.name.value == name:
                    return item
    return None


def _parsed(path: Path):
    """``path`` parsed by libcst, kept while the file is unchanged (its size and mtime): a
    module's mutated file holds all its mutants (1 359 functions for the benchmark stage) and
    took ~40 s to parse on the loaded 2-core machine, once for every survivor rerun."""
    st = path.stat()
    return _parse_file(str(path), st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=4)
def _parse_file(path: str, mtime_ns: int, size: int):
    import libcst as cst
    return cst.parse_module(Path(path).read_text("utf-8"))


def mutated_source(scratch: Path, module: str, name: str) -> str | None:
    """``module``'s source (in the scratch copy) with mutant ``name`` in place of the function
    or method it mutates, read from mutmut's mutated file (``scratch/mutants/<module>``); None
    if either is not found.

    Not ``mutmut apply``: mutmut 3.8.1 finds the method to replace by its name alone, so a
    mutant of ``TreeBuild.__init__`` was written over the file's first ``__init__``
    (``ThesisFrontContact``'s), breaking that class instead: 16 mutants of
    ``engines/exudyn/tree.py`` were counted killed by the rerun, 8 of which survive."""
    import libcst as cst
    key = name.rpartition(".")[2]               # xǁTreeBuildǁ__init____mutmut_1, x_read__mutmut_3
    base = key.rsplit("__mutmut_", 1)[0]
    cls, func = (base.split("ǁ")[1:3] if base.startswith("xǁ") else (None, base[2:]))
    try:
        orig = _parsed(scratch / module)
        mutants = _parsed(scratch / "mutants" / module)
    except (OSError, cst.ParserSyntaxError):
        return None
    target, mutant = _function(orig, cls, func), _function(mutants, cls, key)
    if target is None or mutant is None:
        return None
    return orig.deep_replace(target, mutant.with_changes(name=cst.Name(func))).code


def confirm(module: str, names, tests: list[str], scratch: Path, venv_bin: Path,
            progress=print, workers: int = 1) -> tuple[str, ...]:
    """The survivors among ``names`` that the whole selection ``tests`` kills.

    mutmut runs each mutant only against the tests that executed its function in its first
    run, and a function that ran while a module- or session-scoped fixture was built is
    recorded for the first test that built it only: a mutant of an engine's constructor is
    then run against one test, while every test using the fixture would see it. Here each
    survivor is written into the module's source alone (`mutated_source`) and the whole
    selection run (pytest, stopping at the first failure) on a copy of the scratch tree
    holding that module: ``workers`` copies, one pytest each at a time. The selection is run
    once on the unmutated copy first: if it fails there, nothing is counted (SystemExit)."""
    import concurrent.futures
    import queue
    if not names:
        return ()
    source = scratch / module
    original = source.read_bytes()
    args = [str(venv_bin / "python"), "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
            "-m", "not slow and not bicycles", *tests]
    workers = max(1, min(workers, len(names) or 1))
    trees = queue.Queue()
    for k in range(workers):
        tree = scratch.parent / f"{scratch.name}.rerun{k}"
        if tree.exists():
            shutil.rmtree(tree)
        shutil.copytree(scratch, tree, symlinks=True,
                        ignore=shutil.ignore_patterns(*COPY_IGNORE))
        trees.put(tree)
    done, killed = [0], []
    # the selection must pass on the unmutated tree, or every survivor would count as killed
    # (seen: a refresh ran today's tests of a module changed since on its measured copy)
    tree = trees.get()
    try:
        baseline = subprocess.run(args, cwd=tree, capture_output=True, text=True, timeout=1800,
                                  check=False)
    finally:
        trees.put(tree)
    if baseline.returncode not in (0, 5):
        while not trees.empty():
            shutil.rmtree(trees.get(), ignore_errors=True)
        tail = [ln for ln in baseline.stdout.splitlines() if ln.strip()][-3:]
        raise SystemExit(f"error: {module}: its selection fails on the unmutated scratch copy "
                         f"{scratch} ({' / '.join(tail)}); the code or tests changed since the "
                         f"measurement: measure {module} again")

    def one(name: str) -> bool:
        text = mutated_source(scratch, module, name)
        mutated = None if text is None else text.encode("utf-8")
        if mutated is None or mutated == original:
            return False
        tree = trees.get()
        try:
            (tree / module).write_bytes(mutated)
            run = subprocess.run(args, cwd=tree, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL, timeout=1800, check=False)
        finally:
            (tree / module).write_bytes(original)
            trees.put(tree)
        return run.returncode not in (0, 5)     # 1: a test failed; 2-4: it broke collection

    try:
        with concurrent.futures.ThreadPoolExecutor(workers) as pool:
            for name, dead in zip(names, pool.map(one, names)):
                done[0] += 1
                if dead:
                    killed.append(name)
                if done[0] % 10 == 0 or done[0] == len(names):
                    progress(f"  {module}: rerun {done[0]}/{len(names)} survivors on the whole "
                             f"selection, {len(killed)} killed")
    finally:
        source.write_bytes(original)
        while not trees.empty():
            shutil.rmtree(trees.get(), ignore_errors=True)
    return tuple(killed)


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")


def refresh(module: str, *, out: Path = ROOT / "build" / "mutation", results: Path = RESULTS,
            children: int = 2, progress=print, root: Path = ROOT,
            venv_bin: Path | None = None, added_only: bool = False) -> Result:
    """``module``'s result brought up to date with tests written after it: its survivors are
    run against the module's current selection (`confirm`, in the scratch copy the
    measurement left under ``out``), those killed move to ``killed_on_rerun``, and the result
    takes the selection's current hash. The mutants no test reached run too (when the scratch
    copy's ``.meta`` names them all): those killed now count as killed; the rest stay not
    reached. Sound when the module is unchanged and tests were only added since (a test
    removed or weakened could let a killed mutant live: measure again).

    ``added_only``: the survivors run against the selection's files that the measurement did
    not have (and its pytest options) only: a kill there is a kill by the current selection,
    and a survivor the files it had did not kill before is not run through them again (an
    Engine's conformance files cost tens of seconds a survivor). A file of the old selection
    edited since is not rerun: what it would kill now still counts as surviving (the score can
    read low, never high)."""
    res = load_result(module, results)
    if res is None:
        raise SystemExit(f"error: {module} has not been measured; run "
                         f"python tests/mutation.py {module}")
    if res.module_sha != _sha([module], root):
        raise SystemExit(f"error: {module} changed since it was measured; measure it again "
                         f"(python tests/mutation.py {module})")
    scratch = out / slug(module)
    if not (scratch / "mutants").is_dir():
        raise SystemExit(f"error: the scratch copy {scratch} is gone; measure {module} again")
    tests = selection_for(module, root)
    run = tests
    if added_only:
        run = [t for t in tests if t.startswith("-") or t not in res.tests]
        if not any(not t.startswith("-") for t in run):
            raise SystemExit(f"error: {module}: no test file was added to its selection since "
                             f"its measurement; refresh it without --added-only")
    # the scratch copy takes the tests as they are now: tests/ whole (its helpers and data
    # too), and the selection's files elsewhere (the conformance suite)
    shutil.copytree(root / "tests", scratch / "tests", dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns(*COPY_IGNORE))
    for t in tests:
        if not t.startswith("-") and not t.startswith("tests/"):
            src, dst = root / t.split("::")[0], scratch / t.split("::")[0]
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dst)
    # the mutants no test of the measurement reached run too: a test written since for
    # their functions is what reaches them (if the scratch copy names them all)
    unreached = _unreached(scratch, module)
    if len(unreached) != res.not_reached:
        unreached = []
    killed = confirm(module, [*res.survived, *unreached], run, scratch,
                     venv_bin or Path(sys.executable).parent, progress, children)
    reached = sum(1 for n in killed if n in unreached)
    new = dataclasses.replace(
        res, tests_sha=_sha(tests, root), tests=tuple(tests), killed=res.killed + len(killed),
        survived=tuple(n for n in res.survived if n not in killed),
        not_reached=res.not_reached - reached,
        killed_on_rerun=(*res.killed_on_rerun, *killed), refreshed=_now())
    _save(new, results)
    progress(f"{module}: {len(killed) - reached} of {len(res.survived)} survivors"
             + (f" and {reached} of {len(unreached)} unreached mutants" if unreached else "")
             + f" killed by the current selection; {new.killed}/{new.tried} killed "
               f"({_pct(new.killed, new.tried)})")
    return new


def _unreached(scratch: Path, module: str) -> list[str]:
    """The mutants of ``module`` that no selected test reached in the measurement that left
    ``scratch`` (mutmut's exit code 33, "no tests", in its ``.meta`` file); [] without one."""
    meta = scratch / "mutants" / f"{module}.meta"
    if not meta.is_file():
        return []
    codes = json.loads(meta.read_text("utf-8")).get("exit_code_by_key", {})
    return sorted(n for n, code in codes.items() if code == 33)


def survivors(module: str, out: Path = ROOT / "build" / "mutation",
              results: Path = RESULTS) -> str:
    """The surviving mutants of ``module``'s last measurement, each with its change and, if
    listed, the reason it is equivalent (the diffs are read from the scratch copy once and
    kept in the result)."""
    res = load_result(module, results)
    if res is None:
        raise SystemExit(f"error: {module} has not been measured; run "
                         f"python tests/mutation.py {module}")
    missing = [n for n in res.survived if n not in res.diffs]
    if missing:
        scratch = out / slug(module)
        if not (scratch / "mutants").is_dir():
            raise SystemExit(f"error: the scratch copy {scratch} is gone; measure {module} again")
        res = dataclasses.replace(res, diffs={**res.diffs, **_diffs(Path(sys.executable).parent,
                                                                   scratch, missing, module)})
        _save(res, results)
    eq = equivalents()
    lines = []
    for n in res.survived:
        tag = ("equivalent: " + eq[n]) if n in eq else ("text only" if n in res.text_only else "left")
        lines += [f"{n}  [{tag}]", *("    " + d for d in res.diffs.get(n, []))]
    return "\n".join(lines) + ("\n" if lines else "")


def _result_path(module: str, results: Path) -> Path:
    return results / f"{slug(module)}.json"


def _save(res: Result, results: Path) -> Path:
    path = _result_path(res.module, results)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(dataclasses.asdict(res), indent=1) + "\n")
    os.replace(tmp, path)
    return path


def _pct(a: int, b: int) -> str:
    return f"{100 * a / b:.1f} %" if b else "-"


def load_result(module: str, results: Path = RESULTS) -> Result | None:
    path = _result_path(module, results)
    if not path.is_file():
        return None
    d = json.loads(path.read_text())
    d["tests"], d["survived"] = tuple(d["tests"]), tuple(d["survived"])
    d.setdefault("diffs", {})
    d["killed_on_rerun"] = tuple(d.get("killed_on_rerun", ()))
    return Result(**d)


def current(res: Result) -> bool:
    """Whether ``res`` still describes the module and its tests as they are now."""
    return (res.module_sha == _sha([res.module])
            and res.tests_sha == _sha(selection_for(res.module)))


def equivalents(root: Path = ROOT) -> dict[str, str]:
    """The surviving mutants listed as equivalent (``tests/mutation_equivalents.toml``):
    mutant name -> reason."""
    path = root / "tests" / "mutation_equivalents.toml"
    if not path.is_file():
        return {}
    out = {}
    for module, names in tomllib.loads(path.read_text("utf-8")).items():
        for name, reason in names.items():
            out[name] = reason
    return out


def readings(path: Path = READINGS) -> dict[str, dict]:
    """The earlier rounds' readings (``tests/mutation_readings.toml``): module -> its table
    (tried, killed, round, date, and the flags sweep_tests, stopped and same_name_rerun)."""
    if not path.is_file():
        return {}
    return tomllib.loads(path.read_text("utf-8"))


def table(results: Path = RESULTS, readings_path: Path = READINGS) -> str:
    """The per-module scores as a markdown table, with the sum over the measured modules: a
    module's committed result where there is one, else the earlier rounds' reading of it
    (tried and killed only, marked as a reading), else it is listed as not measured.
    'timeouts': killed by running out of time, not by a failing assertion (counted as
    killed, as mutmut counts them; shown apart because a run environment that hangs makes
    every mutant one); 'text only': survivors that change only a string literal's contents
    (`text_only`); 'equivalent': survivors listed in tests/mutation_equivalents.toml;
    'left': the others."""
    eq = equivalents()
    rows = ["| module | tried | killed | % | timeouts | survived | text only | equivalent | left | "
            "not reached | measured |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    tot = dict.fromkeys(("tried", "killed", "timeouts", "survived", "text", "eq", "left",
                         "unreached"), 0)
    old = readings(readings_path)
    read = dict.fromkeys(("n", "tried", "killed"), 0)
    read_rows = []
    missing, empty = [], []
    for module in module_set():
        res = load_result(module, results)
        if res is None and module in old:
            r = old[module]
            flags = "".join([", its selection starts the sweep's Dask tests" if r.get("sweep_tests") else "",
                             ", stopped before its end" if r.get("stopped") else "",
                             ", its rerun may have put a survivor into another method of its "
                             "name" if r.get("same_name_rerun") else ""])
            read_rows.append(f"| `{module}` | {r['tried']} | {r['killed']} | "
                             f"{_pct(r['killed'], r['tried'])} | ? | {r['tried'] - r['killed']} | "
                             f"? | ? | ? | ? | reading of the {r['round']} round ({r['date']}){flags} |")
            read["n"] += 1
            read["tried"] += r["tried"]
            read["killed"] += r["killed"]
            continue
        if res is None:
            (missing if has_functions(module) else empty).append(module)
            continue
        n_eq = sum(1 for n in res.survived if n in eq)
        n_text = len(res.text_only)
        left = sum(1 for n in res.survived if n not in eq)
        when = res.when + (f", refreshed {res.refreshed}" if res.refreshed else "")
        rows.append(f"| `{module}` | {res.tried} | {res.killed} | {_pct(res.killed, res.tried)} "
                    f"| {res.timeouts} | {len(res.survived)} | {n_text} | {n_eq} | {left} "
                    f"| {res.not_reached} | {when}{'' if current(res) else ' (stale)'} |")
        for k, v in (("tried", res.tried), ("killed", res.killed), ("timeouts", res.timeouts),
                     ("survived", len(res.survived)), ("text", n_text), ("eq", n_eq),
                     ("left", left), ("unreached", res.not_reached)):
            tot[k] += v
    n_res = len(module_set()) - len(missing) - len(empty) - read["n"]
    rows.append(f"| **{n_res} measured** | {tot['tried']} | "
                f"{tot['killed']} | {_pct(tot['killed'], tot['tried'])} | {tot['timeouts']} | "
                f"{tot['survived']} | {tot['text']} | {tot['eq']} | {tot['left']} | "
                f"{tot['unreached']} | |")
    if read_rows:
        t, k = tot["tried"] + read["tried"], tot["killed"] + read["killed"]
        rows += read_rows
        rows.append(f"| **{n_res + read['n']} measured, {read['n']} of them earlier readings** | "
                    f"{t} | {k} | {_pct(k, t)} | | | | | | | |")
    text = "\n".join(rows) + "\n"
    if missing:
        text += f"\nNot measured yet ({len(missing)}): " + ", ".join(f"`{m}`" for m in missing) + "\n"
    if empty:
        text += (f"\nNo function to mutate ({len(empty)}: re-exports and constants): "
                 + ", ".join(f"`{m}`" for m in empty) + "\n")
    return text


def equivalents_list(root: Path = ROOT) -> str:
    """The equivalent mutants of ``tests/mutation_equivalents.toml`` as markdown, module by
    module (sorted), each mutant by its name within the module, with its reason."""
    path = root / "tests" / "mutation_equivalents.toml"
    listed = tomllib.loads(path.read_text("utf-8")) if path.is_file() else {}
    lines = [f"{sum(len(v) for v in listed.values())} equivalent mutants in "
             f"{len(listed)} modules, each with the reason it cannot change what a user or "
             "caller relies on (`tests/mutation_equivalents.toml`):", ""]
    for module in sorted(listed):
        prefix = module.removesuffix(".py").replace("/", ".") + "."
        lines.append(f"- `{module}` ({len(listed[module])})")
        for name, reason in listed[module].items():
            short = name.removeprefix(prefix)
            lines.append(f"  - `{short}`: {' '.join(reason.split())}")
    return "\n".join(lines) + "\n"


#: the README's generated blocks: marker -> the function writing the block
README_BLOCKS = ("mutants-table", "mutants-equivalents")


def readme_blocks(results: Path = RESULTS, readings_path: Path = READINGS,
                  root: Path = ROOT) -> dict[str, str]:
    """What the README's generated blocks hold: the table, and the equivalents' list folded
    in a ``<details>`` element."""
    return {"mutants-table": table(results, readings_path),
            "mutants-equivalents": ("<details><summary>The equivalent mutants, with their "
                                    "reasons</summary>\n\n" + equivalents_list(root)
                                    + "\n</details>\n")}


def with_readme_blocks(text: str, blocks: dict[str, str]) -> str:
    """``text`` (the README) with each block between ``<!-- NAME: ... -->`` and
    ``<!-- /NAME -->`` replaced by ``blocks[NAME]``. A missing marker is a SystemExit naming
    it."""
    for name, body in blocks.items():
        m = re.search(rf"(<!-- {name}:[^\n]*-->\n)(.*?)(<!-- /{name} -->)", text, re.S)
        if m is None:
            raise SystemExit(f"error: README.md has no '<!-- {name}: ... -->' ... "
                             f"'<!-- /{name} -->' block; add the two markers where it belongs")
        text = text[:m.start(2)] + body + text[m.end(2):]
    return text


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tests/mutation.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("modules", nargs="*", help="modules to measure (paths from the repository root)")
    ap.add_argument("--all", action="store_true",
                    help="every module of the set whose result is missing or stale")
    ap.add_argument("--table", action="store_true", help="print the per-module scores so far")
    ap.add_argument("--readme", action="store_true",
                    help="write the table and the list of equivalent mutants into README.md's "
                         "generated blocks (a test checks they are current)")
    ap.add_argument("--list", action="store_true", help="print the set and each test selection")
    ap.add_argument("--survivors", metavar="MODULE",
                    help="print the surviving mutants of MODULE's last measurement, with their changes")
    ap.add_argument("--children", type=int, default=2, help="mutmut worker processes [2]")
    ap.add_argument("--no-rerun", action="store_true",
                    help="do not rerun mutmut's survivors against the module's whole selection")
    ap.add_argument("--refresh", metavar="MODULE", action="append", default=[],
                    help="run MODULE's survivors against its current selection (tests written "
                         "after its measurement); needs its scratch copy")
    ap.add_argument("--added-only", action="store_true",
                    help="with --refresh: run the survivors against the test files added to "
                         "the selection since the measurement only (conservative, faster)")
    ap.add_argument("--out", type=Path, default=ROOT / "build" / "mutation",
                    help="scratch copies [build/mutation]")
    ap.add_argument("--results", type=Path, default=RESULTS,
                    help="the measurements, one JSON file a module [tests/mutation_results]")
    a = ap.parse_args(argv)
    if a.children < 1:
        ap.error(f"--children must be at least 1; got {a.children}")
    if a.list:
        for m in module_set():
            print(m, "<-", " ".join(selection_for(m)))
        return 0
    if a.survivors:
        print(survivors(a.survivors, a.out, a.results), end="")
        return 0
    if a.readme:
        readme = ROOT / "README.md"
        text = readme.read_text("utf-8")
        new = with_readme_blocks(text, readme_blocks(a.results))
        if new != text:
            tmp = readme.with_name(readme.name + ".tmp")
            tmp.write_text(new, "utf-8")
            os.replace(tmp, readme)
        print(f"README.md: {'updated' if new != text else 'already current'}")
        return 0
    todo = list(a.modules)
    if a.all:
        todo += [m for m in module_set() if has_functions(m)
                 and ((r := load_result(m, a.results)) is None or not current(r))]
    if not todo and not a.table and not a.refresh:
        ap.error("name a module, or give --all, --table, --refresh or --list")
    if todo or a.refresh:
        with exclusive(a.out):
            for m in a.refresh:
                refresh(m, out=a.out, results=a.results, children=a.children,
                        added_only=a.added_only)
            for i, m in enumerate(dict.fromkeys(todo), 1):
                print(f"[{i}/{len(todo)}]", end=" ", flush=True)
                measure(m, children=a.children, out=a.out, results=a.results,
                        rerun=not a.no_rerun)
    if a.table or todo or a.refresh:
        print(table(a.results), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
