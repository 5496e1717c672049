"""More of the worker pool (comparisons/stages/pool.py) held to its contract, for the edges
tests/test_pool_edges.py leaves open: the slow-stage notice and the skip after a time-out seen
through `run_tasks` itself (docs/report.md: '... <stage>: still running after N s (expected
about C s; its limit is L s)'; docs/robustness.md: 'skipped: its engine's worker ... (or
`timed out after 2 s in ...`)'), the keys of results that never ran, `_wait` at a task exactly
at its limit and with nothing running, a worker whose own loop fails (it ends as a Python
process with an uncaught exception does: exit status 1), an entry point whose target has a
second colon (the module is what the registry imports, `engines.registry._resolve_target`:
the part before the first colon) and a declared library whose package raises on import.

The helpers (a pool on the test's clock, recorded forks) are test_pool_edges.py's; calls in
workers are tiny, and a hang is that file's `HANG` sleep, killed at a limit of 0.2 s. Each test
names the planted bugs (mutants of the module, one at a time) it was seen failing on.
"""

from __future__ import annotations

import os
import re
import sys
import time
from types import SimpleNamespace

import pytest

from comparisons.stages import pool
from comparisons.stages.pool import Limits, Task, run_tasks
from test_pool_edges import HANG, PATIENCE, _busy, _reaped, _recording_forks, modules_on_path


class Escapes(BaseException):
    """Not an Exception: what a worker's loop does not catch around sending its reply."""


class _EscapingValue:
    """A value whose pickling raises `Escapes`: the worker's loop itself fails sending it."""

    def __reduce__(self):
        raise Escapes("cannot be sent")


def _escaping_value():
    return _EscapingValue()


# ----------------------------------------------------------------------------- run_tasks

def test_a_task_running_long_is_named_once_on_the_progress_line():
    """A task past its expected time (here 0.05 s: slow factor 0, slow floor 0.05 s) but under
    its limit (3 s) is named once while it runs, with its label, its cost and its limit
    (docs/report.md: '... <stage>: still running after N s (expected about C s; its limit is
    L s)'), then finishes as usual. Planted: the tasks already named kept in None (a TypeError);
    the progress callback not passed to `_wait` (the notice called on None)."""
    lines = []
    done = run_tasks([Task("slow", time.sleep, (0.3,), cost=1.0, label="slowpoke")],
                     workers=1, progress=lines.append, warm=(),
                     limits=Limits(floor=3.0, factor=0.0, slow=0.0, slow_floor=0.05))
    assert (done["slow"].key, done["slow"].error) == ("slow", None)
    assert len(lines) == 2, lines
    assert re.fullmatch(r"  \.\.\. slowpoke: still running after \d+ s \(expected about 1 s; "
                        r"its limit is 3 s\)", lines[0]), lines[0]
    assert re.fullmatch(r"  \[1/1\] slowpoke \(\d+\.\d s\)", lines[1]), lines[1]


def test_a_time_out_skips_its_engines_queued_tasks_each_under_its_own_key(monkeypatch):
    """One worker, every limit 0.2 s: engine 'e''s first task hangs and is timed out; e's
    queued task is then skipped, saying so ('skipped: its engine's worker timed out after
    0.2 s in '<label>'', docs/robustness.md), taking no time; engine 'f''s task runs. Every
    result carries its own task's key, the skipped and the timed-out ones too (`TaskResult.key`).
    Planted: the time-out's reason passed to the skip as None (an AttributeError); the key None in
    a skipped task's result; the key None in a timed-out task's result."""
    forks = _recording_forks(monkeypatch)
    tasks = [Task("hangs", time.sleep, (HANG,), cost=3.0, label="e hangs", engine="e"),
             Task("queued", abs, (-2,), cost=2.0, engine="e"),
             Task("other", abs, (-1,), cost=1.0, engine="f")]
    t0 = time.monotonic()
    done = run_tasks(tasks, workers=1, warm=(), limits=Limits(override=0.2))
    assert time.monotonic() - t0 < PATIENCE
    assert {k: r.key for k, r in done.items()} == {"hangs": "hangs", "queued": "queued",
                                                   "other": "other"}
    assert (done["hangs"].value, done["hangs"].seconds, done["hangs"].error) == (
        None, 0.2, "timed out after 0.2 s (limit: --stage-timeout); its worker was killed")
    assert (done["queued"].value, done["queued"].seconds, done["queued"].error) == (
        None, 0.0, "skipped: its engine's worker timed out after 0.2 s in 'e hangs'")
    assert (done["other"].value, done["other"].error) == (1, None)
    assert all(_reaped(p) for p in forks)


def test_a_task_skipped_after_a_death_keeps_its_key():
    """Engine 'e''s first task ends its worker; its queued task is a failure whose result is
    keyed, and names itself, by that task's key. Planted: the key None in a skipped task's
    result."""
    done = run_tasks([Task("dies", os._exit, (3,), cost=2.0, engine="e"),
                      Task(("e", "queued"), abs, (-1,), cost=1.0, engine="e")],
                     workers=1, warm=())
    skipped = done[("e", "queued")]
    assert (skipped.key, skipped.value, skipped.seconds) == (("e", "queued"), None, 0.0)
    assert skipped.error == "skipped: its engine's worker died (exit status 3) in 'dies'"


def test_a_worker_whose_own_loop_fails_exits_with_status_1(monkeypatch):
    """A value whose pickling raises a BaseException that is not an Exception (which the
    worker's loop does not catch around sending): the worker ends as any Python process with an
    uncaught exception does, exit status 1, so the task fails 'its worker process died (exit
    status 1)' (docs/robustness.md's wording) and its engine's queued task is skipped saying so;
    nothing is left running. Planted: exit code None on a failed loop (os._exit(None) raises in
    the worker, which never exits: timed out); exit code 2."""
    forks = _recording_forks(monkeypatch)
    done = run_tasks([Task("escapes", _escaping_value, cost=2.0, engine="e"),
                      Task("queued", abs, (-1,), cost=1.0, engine="e")],
                     workers=1, warm=(), limits=Limits(override=PATIENCE))
    assert (done["escapes"].value, done["escapes"].error) == (
        None, "its worker process died (exit status 1)")
    assert done["queued"].error == ("skipped: its engine's worker died (exit status 1) in "
                                    "'escapes'")
    assert all(_reaped(p) for p in forks)


# ----------------------------------------------------------------------------- _wait

def test_wait_wakes_now_for_a_task_exactly_at_its_limit(monkeypatch):
    """Two tasks of cost 1 (named at 10 s, limit 60 s, README): one has run exactly 60 s, the
    other 3 s (7 s to its notice). A task at its limit is overdue (`_overdue`: at or past), so
    the pool wakes at once to kill it, not 7 s later. Planted: only a task strictly past its
    limit waking the pool (> for >=)."""
    limits = Limits()
    workers, order, _ = _busy(monkeypatch, limits, [(Task("at", abs), 60.0),
                                                    (Task("early", abs), 3.0)])
    assert pool._overdue(workers, order, limits) == [("pipe0", 0)]
    assert pool._wait(workers, order, limits, {0}, lambda s: None) == 0.0


def test_wait_with_nothing_running_waits_for_nothing(monkeypatch):
    """No worker busy: no reply, limit or notice can come, so the time to wait is none at all,
    0 s; `reply` on that then returns at once (waiting 1 s would be a second lost; an infinite
    time is no timeout the pipes' `wait` accepts). Planted: 1 s with nothing running; the
    infinite time returned as it is."""
    workers, order, _ = _busy(monkeypatch, Limits(), [])
    assert pool._wait(workers, order, Limits(), set(), lambda s: None) == 0.0
    t0 = time.monotonic()
    assert workers.reply(pool._wait(workers, order, Limits(), set(), lambda s: None)) is None
    assert time.monotonic() - t0 < 0.5


# ----------------------------------------------------------------------------- imports

def test_engine_imports_take_the_module_before_the_first_colon(monkeypatch):
    """A target with a second colon ('pkg.mod:Outer:Inner'): its module is the part before the
    first colon, as the registry imports it when it resolves the engine
    (`engines.registry._resolve_target` partitions at the first colon). Planted: the part
    before the last colon ('pkg.mod:Outer')."""
    import engines.registry as registry
    targets = ["pkg.mod:Outer:Inner", "other:Cls"]
    monkeypatch.setattr(registry, "registrations",
                        lambda: [SimpleNamespace(target=t) for t in targets])
    module_of = [t.partition(":")[0] for t in targets]          # the registry's own reading
    assert pool.engine_imports() == tuple(module_of) == ("pkg.mod", "other")


@pytest.fixture
def broken_package(tmp_path, monkeypatch):
    """A package ``pool_more_broken`` whose __init__ raises (its submodule ``sub`` is there),
    a library ``pool_more_after`` and an engine module ``pool_more_engine`` requiring both;
    all forgotten after."""
    files = {"pool_more_broken/__init__.py": "raise RuntimeError('broken package')\n",
             "pool_more_broken/sub.py": "", "pool_more_after.py": "",
             "pool_more_engine.py": "REQUIRES = ('pool_more_broken.sub', 'pool_more_after')\n"}
    yield from modules_on_path(tmp_path, monkeypatch, files,
                               lambda name: name.startswith("pool_more_"))


def test_warm_imports_skips_a_library_whose_package_raises_and_goes_on(broken_package):
    """A declared dotted library is checked installed by its top-level package (found without
    importing it, as `engines.registry` checks REQUIRES), then imported; its package raising
    on import is skipped (the engine's own resolution reports it) and the next library is
    still warmed. Planted: the installed check given the whole dotted name, split on whitespace
    or on a separator it never contains (finding 'pool_more_broken.sub' imports the raising
    package: the RuntimeError escaped warm_imports)."""
    pool.warm_imports(("pool_more_engine",))
    assert "pool_more_after" in sys.modules
    assert "pool_more_broken.sub" not in sys.modules


def test_wait_for_a_task_with_no_limit_left_blocks_for_its_reply(monkeypatch):
    """A task whose limit is infinite (`run_tasks(..., limits=Limits(override=inf))`, open to
    direct callers) and already named as slow has nothing due: the pool waits for its reply
    (None, no timeout), not 0 s, which polled the pipes at full CPU until the task ended
    (0.41 s of CPU over a 0.5 s task, found by a helper writing these tests). Planted: 0 s
    returned when nothing is due."""
    limits = Limits(override=float("inf"))
    workers, order, _ = _busy(monkeypatch, limits, [(Task("long", abs), 30.0)])
    assert pool._wait(workers, order, limits, {0}, lambda s: None) is None
