"""The hand-written worker pool (comparisons/stages/pool.py) held to its contract: the module's
docstrings, README ("Written by hand, and why"; a stage's limit is its expected time times 20,
at least 60 s, or ``--stage-timeout``; a stage four times longer than expected is named),
docs/report.md (the slow-stage notice, "at least 10 s") and docs/robustness.md (the messages of
a dead, timed-out or skipped task; SIGTERM and Ctrl-C end every worker).

Most of the pool's code runs in forked workers, where a mutation tool cannot see it; these
tests call its pieces in the test's own process wherever they can: `_serve` (a worker's loop)
on a stand-in pipe, `_wait` and `_overdue` on a pool whose clock is the test's, `_how` on wait
statuses built by the POSIX encoding (exit code in the high byte, signal number in the low),
`_exception`, `_timed_out`, `_line`, `Limits`, `default_workers`, `engine_imports` and
`warm_imports` on modules written in a temporary folder. Where a worker is needed the calls
are tiny (``abs``, ``divmod``, ``int``); a hang is a 5 s sleep in the worker (`HANG`), which the
pool kills at a limit of 0.2-0.3 s, and every worker a test starts is checked reaped. The
signal cases run the pool in a forked child of the test, so that a pool that failed to catch
SIGTERM would end that child, not pytest. Expected values come from the documents above and
from first principles (a call's time is its end minus its start; longest first is decreasing
cost), never from the pool's own output. Each test names the bugs planted by hand (in a copy
of the module, one at a time) it was seen failing on.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
import threading
import time
from types import SimpleNamespace

import pytest

from comparisons.stages import pool
from comparisons.stages.pool import (Limits, StageTimeout, Task, TaskResult, Terminated,
                                     call_in_worker, run_tasks)

#: how long a test waits for a process that should end at once before it kills it and fails
PATIENCE = 3.0
#: a call that hangs sleeps this long (s): far past the tests' limits of 0.2-0.3 s, short
#: enough that a pool that fails to stop it costs seconds, not minutes
HANG = 5.0


# ----------------------------------------------------------------------------- helpers

def _exit_now(code):
    os._exit(code)


def _signal_self(sig):
    os.kill(os.getpid(), sig)
    time.sleep(HANG)        # never reached: the signal ends the worker


def _signal_parent_then_hang(sig):
    os.kill(os.getppid(), sig)
    time.sleep(HANG)        # the pool kills this worker when the signal reaches it


def _deaf_sleep(seconds):
    """A call that ignores SIGTERM (as a library in the worker may), sleeps, then ends its
    worker (so that a pool that waits for it is late, not stuck)."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    time.sleep(seconds)
    os._exit(0)


def _unpicklable_value():
    return threading.Lock()


class TwoArgs(Exception):
    """Pickles (by its args, one here) but does not unpickle: its __init__ wants two."""

    def __init__(self, a, b):
        super().__init__(a)


@pytest.fixture(autouse=True)
def _two_args_pickled_plainly(monkeypatch):
    """TwoArgs as Python pickles it: importing Dask's distributed (another test file of the same
    pytest worker may) runs tblib's ``pickling_support.install()``, which registers a reducer in
    copyreg's table for every exception class then defined, and that reducer rebuilds TwoArgs
    without calling its __init__: it would then unpickle, and the tests below would no longer
    see an exception that does not."""
    import copyreg
    monkeypatch.delitem(copyreg.dispatch_table, TwoArgs, raising=False)


def _raise_two_args():
    raise TwoArgs("half of it", "the other half")


class _Pipe:
    """The worker's end of a pipe, in the test's process: the indices it will receive, then
    end of file; what is sent must pickle (as `Connection.send` requires), and is kept."""

    def __init__(self, incoming):
        self.incoming = list(incoming)
        self.sent = []

    def recv(self):
        if not self.incoming:
            raise EOFError
        return self.incoming.pop(0)

    def send(self, obj):
        pickle.dumps(obj)
        self.sent.append(obj)


def _clock(monkeypatch, *, now=None, perf=()):
    """The pool's clock replaced: ``time.monotonic`` returns ``now[0]`` (a one-item list the
    test changes), ``time.perf_counter`` the values of ``perf`` in turn."""
    values = iter(perf)
    fake = SimpleNamespace(monotonic=(lambda: now[0]) if now else time.monotonic,
                           perf_counter=lambda: next(values))
    monkeypatch.setattr(pool, "time", fake)


def _recording_forks(monkeypatch) -> list[int]:
    """The pids of every worker the pool forks, in order."""
    pids = []
    real = pool._Workers.fork

    def fork(self):
        conn = real(self)
        pids.append(self.pids[conn])
        return conn
    monkeypatch.setattr(pool._Workers, "fork", fork)
    return pids


def _recording_starts(monkeypatch) -> list[tuple]:
    """The arguments of each call the pool gives a worker, in the order it gives them."""
    given = []
    real = pool._Workers.give

    def give(self, conn, k):
        given.append(self.calls[k][1])
        real(self, conn, k)
    monkeypatch.setattr(pool._Workers, "give", give)
    return given


def _reaped(pid: int) -> bool:
    """The worker ``pid`` has ended and been waited for (by the pool)."""
    try:
        os.waitpid(pid, os.WNOHANG)
    except ChildProcessError:
        return True
    return False


def _wait_for_exit(pid: int) -> int:
    """The exit code of child ``pid`` (waited for here), killing it after `PATIENCE` s."""
    deadline = time.monotonic() + PATIENCE
    while time.monotonic() < deadline:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            return os.waitstatus_to_exitcode(status)
        time.sleep(0.005)
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    raise AssertionError(f"process {pid} still running after {PATIENCE} s")


# ----------------------------------------------------------------------------- pure parts

def test_limits_follow_the_documented_rule():
    """A stage's limit is its cost times 20, at least 60 s, or --stage-timeout for every stage
    (README); it is named as slow past four times its cost, at least 10 s (docs/report.md),
    never later than its limit. Planted: min for max in the limit; slow plus cost for slow times
    cost; a slow floor of 1 s; the expected time not capped at the limit; a floor of 30 s; a factor
    of 10; the override tested the wrong way round."""
    defaults = Limits()
    cheap, dear = Task("cheap", abs, cost=1.0), Task("dear", abs, cost=10.0)
    assert defaults.budget(cheap) == 60.0          # max(60, 20 x 1)
    assert defaults.budget(dear) == 200.0          # max(60, 20 x 10)
    assert defaults.expected(cheap) == 10.0        # max(10, 4 x 1)
    assert defaults.expected(dear) == 40.0         # max(10, 4 x 10)
    override = Limits(override=5.0)
    assert override.budget(cheap) == override.budget(dear) == 5.0
    assert override.expected(dear) == 5.0          # min(5, 40): not past the limit
    custom = Limits(floor=2.0, factor=3.0, slow=1.5, slow_floor=0.5)
    assert custom.budget(Task("t", abs, cost=0.5)) == 2.0      # the floor
    assert custom.budget(Task("t", abs, cost=4.0)) == 12.0     # 3 x 4
    assert custom.expected(Task("t", abs, cost=0.2)) == 0.5    # the slow floor
    assert custom.expected(Task("t", abs, cost=4.0)) == 6.0    # 1.5 x 4


def test_a_task_defaults_to_no_arguments_unit_cost_and_no_engine():
    """``Task(key, func)`` is ``func()``, cost 1 (as the limits' rule reads it), no label, the
    harness's own (engine None). Planted: a default cost of 0."""
    task = Task("k", abs)
    assert (task.args, task.cost, task.label, task.engine) == ((), 1.0, "", None)
    assert TaskResult("k", 1, 0.5).error is None


def test_wait_statuses_are_named_by_exit_code_or_signal():
    """A dead worker's status, in the POSIX encoding (exit code << 8; a signal's number):
    'exit status N' or 'killed by SIGNAME'. Planted: the raw status as the exit status; WIFEXITED
    for WIFSIGNALED."""
    assert pool._how(3 << 8) == "exit status 3"
    assert pool._how(0) == "exit status 0"
    assert pool._how(int(signal.SIGTERM)) == "killed by SIGTERM"
    assert pool._how(int(signal.SIGSEGV)) == "killed by SIGSEGV"


def test_default_workers_are_the_cores_but_never_more_than_the_tasks_or_eight(monkeypatch):
    """The machine's cores, at most the tasks and MAX_WORKERS (8), at least one (README:
    --jobs; docs/robustness.md: never more workers than stages, at most 8). Planted: at least 0
    workers; MAX_WORKERS dropped; an unknown core count read as 2."""
    assert pool.MAX_WORKERS == 8
    for cores, tasks, expected in ((4, 3, 3), (4, 10, 4), (16, 20, 8), (16, 8, 8), (2, 1, 1),
                                   (None, 5, 1), (4, 0, 1)):
        monkeypatch.setattr(os, "cpu_count", lambda cores=cores: cores)
        assert pool.default_workers(tasks) == expected, (cores, tasks)


def test_timed_out_message_names_the_limit_and_where_it_comes_from():
    """'timed out after N s (limit: ...); its worker was killed' (docs/robustness.md), the
    limit the --stage-timeout's or the cost rule's with its numbers. Planted: the floor printed for
    the factor; the override tested the wrong way round (here and in `Limits.budget`); min for max
    in the limit."""
    task = Task("t", abs, cost=0.25)
    assert pool._timed_out(Limits(override=2.0), task) == (
        "timed out after 2 s (limit: --stage-timeout); its worker was killed")
    assert pool._timed_out(Limits(floor=60.0, factor=20.0), Task("t", abs, cost=4.5)) == (
        "timed out after 90 s (limit: 20 x its expected 4.5 s, at least 60 s; "
        "--stage-timeout sets it); its worker was killed")
    assert pool._timed_out(Limits(floor=0.5, factor=0.0), task) == (
        "timed out after 0.5 s (limit: 0 x its expected 0.25 s, at least 0.5 s; "
        "--stage-timeout sets it); its worker was killed")


def test_progress_lines_count_name_and_time_each_task():
    """'  [k/n] <label or key> (S s)', or ': FAILED (<error>)'. Planted: k and n swapped in a
    FAILED line; the seconds with no decimal."""
    labelled, bare = Task("k", abs, label="the stage"), Task(("term", "pin"), abs)
    assert pool._line(2, 5, labelled, TaskResult("k", 1, 1.26)) == "  [2/5] the stage (1.3 s)"
    assert pool._line(5, 5, bare, TaskResult(bare.key, 1, 0.0)) == (
        "  [5/5] ('term', 'pin') (0.0 s)")
    assert pool._line(1, 3, labelled, TaskResult("k", None, 0.1, "ValueError: no")) == (
        "  [1/3] the stage: FAILED (ValueError: no)")


def test_exception_comes_back_as_itself_or_as_its_text():
    """`_exception`: the worker's exception unpickled; its text as a RuntimeError when it was
    not pickled or does not unpickle. Planted: the text returned whenever the exception was pickled
    (the test inverted); only ImportError caught around the unpickling."""
    back = pool._exception(pool._Reply(0, error="ValueError: v",
                                       exception=pickle.dumps(ValueError("v"))))
    assert type(back) is ValueError and back.args == ("v",)
    for exception in (None, pickle.dumps(TwoArgs("a", "b"))):
        back = pool._exception(pool._Reply(0, error="TwoArgs: a", exception=exception))
        assert type(back) is RuntimeError and back.args == ("TwoArgs: a",)


# ----------------------------------------------------------------------------- a worker's loop

def test_serve_answers_each_index_with_its_call_until_the_pipe_closes(monkeypatch):
    """`_serve` in this process: each index received is answered with that call's value and
    its time (end minus start on the clock), in the order asked, the same call again when
    asked again; end of file ends the loop. Planted: the time as start minus end; the previous call
    run (calls[k - 1])."""
    _clock(monkeypatch, perf=[10.0, 12.5, 20.0, 20.25, 30.0, 31.0])
    conn = _Pipe([1, 0, 1])
    pool._serve(conn, [(abs, (-2,)), (divmod, (7, 2))])
    assert conn.sent == [pool._Reply(1, (3, 1), 2.5), pool._Reply(0, 2, 0.25),
                         pool._Reply(1, (3, 1), 1.0)]
    assert conn.incoming == []


def test_serve_reports_a_raising_call_and_goes_on(monkeypatch):
    """A call that raises, even KeyboardInterrupt or SystemExit, is its reply's error (the
    exception's type and message, docs/robustness.md) with the exception pickled; an exception
    that does not pickle leaves its text; the next call still runs. Planted: ``except Exception``
    for ``BaseException`` (KeyboardInterrupt escaped the loop); the pickled exception dropped;
    str(exc) for describe(exc); calls[k - 1]."""
    class Local(Exception):
        pass                # a local class does not pickle

    def local():
        raise Local("boom")

    def interrupt():
        raise KeyboardInterrupt

    calls = [(int, ("zz",)), (interrupt, ()), (sys.exit, (4,)), (local, ()), (abs, (-9,))]
    conn = _Pipe(range(5))
    try:
        pool._serve(conn, calls)
    except BaseException as exc:      # noqa: BLE001 - not to pytest: it would stop the session
        pytest.fail(f"_serve let {exc!r} out")
    assert [r.index for r in conn.sent] == [0, 1, 2, 3, 4]
    bad_int, stop, exit_, unpicklable, fine = conn.sent
    assert bad_int.error == "ValueError: invalid literal for int() with base 10: 'zz'"
    assert bad_int.value is None
    assert pickle.loads(bad_int.exception).args == ("invalid literal for int() with base 10: "
                                                    "'zz'",)
    assert stop.error == "KeyboardInterrupt"
    assert type(pickle.loads(stop.exception)) is KeyboardInterrupt
    assert exit_.error == "SystemExit: 4"
    assert (unpicklable.error, unpicklable.exception) == ("Local: boom", None)
    assert (fine.value, fine.error, fine.exception) == (9, None, None)


def test_serve_says_when_a_value_cannot_be_sent_back():
    """A value that does not pickle (a lock) is a failure of its call, not of the worker:
    'its result could not be sent back (<its error>)'. Planted: the message reworded ('its value
    could not be sent back'); calls[k - 1]."""
    conn = _Pipe([0, 1])
    pool._serve(conn, [(_unpicklable_value, ()), (abs, (-1,))])
    refused, fine = conn.sent
    assert refused.index == 0 and refused.value is None
    assert refused.error.startswith("its result could not be sent back (TypeError: "), refused
    assert refused.error.endswith(")") and "pickle" in refused.error
    assert fine.value == 1


# ----------------------------------------------------------------------------- _wait, _overdue

def _busy(monkeypatch, limits, tasks_and_ran, now=1000.0):
    """A pool whose workers run ``tasks_and_ran`` [(task, seconds it has run)], at ``now``."""
    clock = [now]
    _clock(monkeypatch, now=clock)
    workers = pool._Workers([])
    order = [task for task, _ in tasks_and_ran]
    for k, (_, ran) in enumerate(tasks_and_ran):
        workers.busy[f"pipe{k}"] = k
        workers.started[f"pipe{k}"] = now - ran
    return workers, order, clock


def test_wait_sleeps_until_the_next_notice_or_limit_and_names_a_slow_task_once(monkeypatch):
    """With the documented limits (cost 1 s: named at 10 s, limit 60 s): at 3 s the pool waits
    7 s; at 10 s it names the task once ('... <label>: still running after 10 s (expected
    about 1 s; its limit is 60 s)') and waits 50 s; at 12 s it does not name it again; at or
    past its limit it waits no more. Planted: the notice only strictly past the expected time; the
    notice repeated on every wake; max for min over the events; only the expected time waited for;
    the expected time shown as the cost; the key shown despite a label; a default cost of 0; the
    documented limits changed (min for max, slow floor, the cap, floor, the override test)."""
    lines, told = [], set()
    workers, order, clock = _busy(monkeypatch, Limits(), [(Task("k", abs, label="lbl"), 3.0)])
    assert pool._wait(workers, order, Limits(), told, lines.append) == 7.0
    assert lines == [] and told == set()
    clock[0] += 7.0
    assert pool._wait(workers, order, Limits(), told, lines.append) == 50.0
    assert lines == ["  ... lbl: still running after 10 s (expected about 1 s; its limit is "
                     "60 s)"]
    assert told == {0}
    clock[0] += 2.0
    assert pool._wait(workers, order, Limits(), told, lines.append) == 48.0
    assert len(lines) == 1
    clock[0] += 48.0
    assert pool._wait(workers, order, Limits(), told, lines.append) == 0.0
    clock[0] += 5.0
    assert pool._wait(workers, order, Limits(), told, lines.append) == 0.0


def test_wait_takes_the_soonest_event_of_all_running_tasks(monkeypatch):
    """Two tasks: cost 1 at 3 s (7 s to its notice) and cost 5 (notice at 20 s) at 15 s: 5 s.
    A task named by its key when it has no label. Without limits the pool waits for a reply
    however long (None). Planted: max for min over the events; an overdue task not waking the pool
    (soonest = 0 dropped); the notice showing the expected time as the time run, or as the cost;
    slow plus cost; a factor of 10."""
    lines = []
    tasks = [(Task("a", abs, cost=1.0), 3.0), (Task(("term", "pin"), abs, cost=5.0), 15.0)]
    workers, order, _ = _busy(monkeypatch, Limits(), tasks)
    assert pool._wait(workers, order, Limits(), set(), lines.append) == 5.0
    workers, order, _ = _busy(monkeypatch, Limits(), [(tasks[1][0], 21.0), (tasks[0][0], 1.0)])
    assert pool._wait(workers, order, Limits(), set(), lines.append) == 9.0   # 10 - 1
    assert lines == ["  ... ('term', 'pin'): still running after 21 s (expected about 5 s; "
                     "its limit is 100 s)"]
    assert pool._wait(workers, order, None, set(), lines.append) is None
    # one task past its limit: the pool wakes now, whatever the other's next event
    workers, order, _ = _busy(monkeypatch, Limits(), [(tasks[0][0], 1.0), (tasks[0][0], 70.0)])
    assert pool._wait(workers, order, Limits(), {0, 1}, lines.append) == 0.0


def test_wait_names_no_task_whose_limit_comes_first(monkeypatch):
    """--stage-timeout 5 s for a cost-1 task (expected 10 s, cut to its limit): it is never
    'still running', it is timed out; the pool wakes at the limit. Planted: the notice given when
    the expected time equals the limit (<= for <); max for min; a slow floor of 1 s."""
    lines, limits = [], Limits(override=5.0)
    workers, order, clock = _busy(monkeypatch, limits, [(Task("k", abs), 2.0)])
    assert pool._wait(workers, order, limits, set(), lines.append) == 3.0
    clock[0] += 3.0
    assert pool._wait(workers, order, limits, set(), lines.append) == 0.0
    assert lines == []


def test_overdue_lists_the_tasks_at_or_past_their_limit(monkeypatch):
    """`_overdue`: the workers whose task has run its limit or more (a task exactly at its
    limit is overdue: the pool woke for it); none without limits. Planted: strictly past (> for
    >=); the expected time for the limit; min for max in the limit."""
    # limits 2 s, 2 s, 5 s; expected 1 s, 0.5 s, 5 s: a task past its expected time but under
    # its limit is not overdue
    limits = Limits(floor=2.0, factor=1.0, slow=1.0, slow_floor=0.5)
    tasks = [(Task("at", abs, cost=1.0), 2.0), (Task("under", abs, cost=0.5), 1.5),
             (Task("past", abs, cost=5.0), 7.0)]
    workers, order, _ = _busy(monkeypatch, limits, tasks)
    assert pool._overdue(workers, order, limits) == [("pipe0", 0), ("pipe2", 2)]
    assert pool._overdue(workers, order, None) == []


# ----------------------------------------------------------------------------- _Workers

def test_a_worker_answers_its_calls_and_is_reaped_on_close():
    """One worker, two calls in turn: each reply is the call's, from the same worker (its pipe
    handed back as free); while a call runs the worker is busy with it since it was given;
    `close` kills and reaps it and closes its pipe. Planted: the worker's parent read as
    os.getppid() (every worker exits at once); the start time not recorded; busy with call 0;
    busy.get for busy.pop; waitpid with WNOHANG (the worker left unreaped); the pipe not closed;
    close ending only the busy workers; the pid recorded under the worker's end; the time as start
    minus end; calls[k - 1]."""
    workers = pool._Workers([(abs, (-4,)), (divmod, (7, 2))])
    try:
        conn = workers.fork()
        pid = workers.pids[conn]
        assert pid != os.getpid()
        before = time.monotonic()
        workers.give(conn, 1)
        assert workers.busy == {conn: 1}
        assert before <= workers.started[conn] <= time.monotonic()
        reply, free = workers.reply(PATIENCE)
        assert free is conn and workers.busy == {}
        assert (reply.index, reply.value, reply.error) == (1, (3, 1), None)
        assert reply.seconds >= 0.0
        workers.give(conn, 0)
        reply, free = workers.reply(PATIENCE)
        assert (reply.index, reply.value, free) == (0, 4, conn)
    finally:
        workers.close()
    assert workers.pids == {} and conn.closed and _reaped(pid)


def test_a_busy_worker_is_no_reply_within_the_timeout_and_is_killed_by_index():
    """A call that hangs, deaf to SIGTERM: `reply` gives None after its timeout and the worker
    stays busy; `kill` returns the call's index, kills (SIGKILL: at once, the call's 3 s sleep
    cut) and reaps the worker, forgets it. Planted: kill not ending the worker; SIGTERM for SIGKILL
    (the call's 3 s sleep waited for); the start time kept after the end; busy with call 0; the
    pipe not closed; waitpid with WNOHANG; the worker's parent read as os.getppid()."""
    workers = pool._Workers([(abs, (-1,)), (_deaf_sleep, (3.0,))])
    try:
        conn = workers.fork()
        pid = workers.pids[conn]
        workers.give(conn, 1)
        assert workers.reply(0.05) is None
        assert workers.busy == {conn: 1}
        t0 = time.monotonic()
        assert workers.kill(conn) == 1
        assert time.monotonic() - t0 < 1.5
        assert (workers.busy, workers.pids, workers.started) == ({}, {}, {})
        assert conn.closed and _reaped(pid)
    finally:
        workers.close()


@pytest.mark.parametrize("func, args, how", [
    (_exit_now, (3,), "exit status 3"),
    (_signal_self, (signal.SIGTERM,), "killed by SIGTERM")])
def test_a_dead_worker_fails_its_own_call_with_how_it_died(func, args, how):
    """A worker that exits or is killed by a signal while running call 1: the reply is
    'its worker process died (<how>)' for that call and no free pipe (docs/robustness.md);
    the worker is reaped and forgotten. Planted: a dead worker's pipe handed back as free; 'its
    worker died'; the raw status for `_how`'s words; the raw status as the exit status; WIFEXITED
    for WIFSIGNALED; busy with call 0."""
    workers = pool._Workers([(abs, (-1,)), (func, args)])
    try:
        conn = workers.fork()
        pid = workers.pids[conn]
        workers.give(conn, 1)
        got = workers.reply(PATIENCE)
        assert got is not None, "no reply from a dead worker"
        reply, free = got
        assert free is None
        assert (reply.index, reply.value) == (1, None)
        assert reply.error == f"its worker process died ({how})"
        assert workers.pids == {} and workers.busy == {} and _reaped(pid)
    finally:
        workers.close()


def test_an_idle_worker_ends_cleanly_when_its_pipe_closes():
    """Two workers forked in turn; closing the first one's pipe in the parent ends it with exit
    status 0 (its loop sees end of file: the second worker holds no copy of that pipe, nor does
    the first hold its own parent end). Planted: the other workers' pipes not closed in the child
    (no end of file: killed after 3 s); the child's own copy of its parent end not closed (the
    same); exit status 1 after a clean end of file; the pid recorded under the worker's end."""
    workers = pool._Workers([(abs, (-1,))])
    try:
        first = workers.fork()
        workers.fork()
        pid = workers.pids.pop(first)
        first.close()
        assert _wait_for_exit(pid) == 0
    finally:
        workers.close()


# ----------------------------------------------------------------------------- run_tasks

def test_no_tasks_no_workers_and_no_imports(monkeypatch):
    """An empty list is an empty result, before any import or fork. Planted: the empty list not
    short-cut (warm_imports called)."""
    monkeypatch.setattr(pool, "warm_imports", lambda names=None: pytest.fail("warmed"))
    monkeypatch.setattr(pool._Workers, "fork", lambda self: pytest.fail("forked"))
    assert run_tasks([]) == {}


def test_tasks_start_longest_first_and_come_back_keyed_with_their_times(monkeypatch):
    """One worker: the tasks start in decreasing cost (equal costs as given), each result
    under its key with the call's value and its time in the worker (end minus start on the
    worker's clock, forked from the test's); the progress line counts, names and times each.
    The modules given as ``warm`` are warmed. Planted: shortest first; the workers argument
    ignored; the warm argument dropped; a new worker for every task (the free one not reused); the
    count one ahead; the death test inverted (``free is not None``); the time as start minus end;
    close ending only the busy workers."""
    warmed = []
    monkeypatch.setattr(pool, "warm_imports", warmed.append)
    _clock(monkeypatch, perf=[1.0, 3.5, 4.0, 4.375, 5.0, 5.5, 6.0, 6.0])
    forks, starts, lines = _recording_forks(monkeypatch), _recording_starts(monkeypatch), []
    tasks = [Task("small", abs, (-1,), cost=0.5), Task("big", abs, (-2,), cost=9.0, label="B"),
             Task(("mid", 1), divmod, (7, 2), cost=3.0), Task("mid2", abs, (-4,), cost=3.0)]
    done = run_tasks(tasks, workers=1, progress=lines.append, warm=("a.module",))
    assert warmed == [("a.module",)]
    assert starts == [(-2,), (7, 2), (-4,), (-1,)]
    assert {k: (r.key, r.value, r.seconds, r.error) for k, r in done.items()} == {
        "big": ("big", 2, 2.5, None), ("mid", 1): (("mid", 1), (3, 1), 0.375, None),
        "mid2": ("mid2", 4, 0.5, None), "small": ("small", 1, 0.0, None)}
    assert lines == ["  [1/4] B (2.5 s)", "  [2/4] ('mid', 1) (0.4 s)", "  [3/4] mid2 (0.5 s)",
                     "  [4/4] small (0.0 s)"]
    assert len(forks) == 1 and _reaped(forks[0])


def test_the_first_workers_take_the_longest_tasks(monkeypatch):
    """Three workers for five tasks: the three dearest start first, then the others as
    workers come free, dearest first; no more workers than asked, and no more than the tasks
    (workers=0 or None: the machine's, here two cores). Planted: shortest first; the workers
    argument ignored; a new worker for every task; close ending only the busy workers; the death
    test inverted."""
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    forks, starts = _recording_forks(monkeypatch), _recording_starts(monkeypatch)
    tasks = [Task(k, abs, (-k,), cost=float(k)) for k in (2, 5, 1, 4, 3)]
    done = run_tasks(tasks, workers=3, warm=())
    assert {k: r.value for k, r in done.items()} == {k: k for k in (1, 2, 3, 4, 5)}
    assert sorted(starts[:3]) == [(-5,), (-4,), (-3,)] and sorted(starts[3:]) == [(-2,), (-1,)]
    assert starts[3] == (-2,)
    assert len(forks) == 3 and all(_reaped(p) for p in forks)
    for asked in (0, None):
        forks.clear()
        run_tasks(tasks, workers=asked, warm=())
        assert len(forks) == 2
    forks.clear()
    run_tasks(tasks[:2], workers=6, warm=())
    assert len(forks) == 2


def test_a_task_without_arguments_runs_in_a_worker_not_here():
    """``Task(key, func)`` calls ``func()`` in a worker process: os.getpid there is not the
    test's. Planted: the death test inverted (``free is not None``: fell() on a reply with no
    error); calls[k - 1]."""
    done = run_tasks([Task("pid", os.getpid), Task("none", dict)], warm=())
    assert done["pid"].error is None and done["pid"].value != os.getpid()
    assert done["none"].value == {}


def test_a_failing_task_is_its_result_and_the_worker_goes_on(monkeypatch):
    """A task that raises is a TaskResult with the exception's type and message and no value,
    a FAILED progress line; one whose value does not pickle says so; the same worker runs the
    rest. Planted: the unsendable value's reply sent for call 0; the message reworded; str(exc) for
    describe(exc); k and n swapped in a FAILED line; shortest first; a new worker for every task;
    the count one ahead."""
    forks, lines = _recording_forks(monkeypatch), []
    tasks = [Task("bad", int, ("zz",), cost=3.0), Task("lock", _unpicklable_value, cost=2.0),
             Task("good", abs, (-5,), cost=1.0)]
    done = run_tasks(tasks, workers=1, progress=lines.append, warm=())
    msg = "ValueError: invalid literal for int() with base 10: 'zz'"
    assert (done["bad"].value, done["bad"].error) == (None, msg)
    assert done["lock"].error.startswith("its result could not be sent back (TypeError: ")
    assert (done["good"].value, done["good"].error) == (5, None)
    assert lines[0] == f"  [1/3] bad: FAILED ({msg})"
    assert len(forks) == 1


def test_a_dead_workers_engine_is_skipped_and_the_worker_replaced(monkeypatch):
    """One worker; engine 'e''s first task (no label) ends its worker (exit 3): it fails
    'its worker process died (exit status 3)', a new worker is forked, e's queued task is a
    failure naming the task by its key ('skipped: its engine's worker died (exit status 3) in
    'first''), taking no time; engine 'f''s task runs. Planted: the fallen engines looked up by
    task key; the skip's reason stored as its value; the prefix 'its worker process ' kept in the
    skip's reason; a dead worker's pipe handed back as free; 'its worker died'; the raw status; the
    count one ahead; k and n swapped; the workers argument ignored."""
    forks, lines = _recording_forks(monkeypatch), []
    tasks = [Task("first", _exit_now, (3,), cost=3.0, engine="e"),
             Task("second", abs, (-2,), cost=2.0, engine="e"),
             Task("other", abs, (-1,), cost=1.0, engine="f")]
    done = run_tasks(tasks, workers=1, progress=lines.append, warm=())
    assert done["first"].error == "its worker process died (exit status 3)"
    skipped = "skipped: its engine's worker died (exit status 3) in 'first'"
    assert (done["second"].value, done["second"].seconds, done["second"].error) == (
        None, 0.0, skipped)
    assert (done["other"].value, done["other"].error) == (1, None)
    assert lines[1] == f"  [2/3] second: FAILED ({skipped})"
    assert len(forks) == 2 and all(_reaped(p) for p in forks)


def test_a_task_past_its_limit_is_timed_out_and_the_harness_goes_on(monkeypatch):
    """One worker, --stage-timeout 0.2 s: the hanging task (the harness's own, engine None) is
    'timed out after 0.2 s (limit: --stage-timeout); its worker was killed', its time the
    limit; its worker is killed and replaced and the next harness task runs (engine None is
    no engine to skip). Planted: engine None recorded as fallen (the next harness task skipped);
    the timed-out task's seconds 0; no replacement worker after a time-out; kill not ending the
    worker; the start time not recorded; the override tested the wrong way round (a 5 s wait); k
    and n swapped."""
    forks, lines = _recording_forks(monkeypatch), []
    tasks = [Task("hangs", time.sleep, (HANG,), cost=2.0, label="stuck"),
             Task("after", abs, (-6,), cost=1.0)]
    t0 = time.monotonic()
    done = run_tasks(tasks, workers=1, progress=lines.append, warm=(),
                     limits=Limits(override=0.2))
    assert time.monotonic() - t0 < PATIENCE
    why = "timed out after 0.2 s (limit: --stage-timeout); its worker was killed"
    assert (done["hangs"].value, done["hangs"].seconds, done["hangs"].error) == (None, 0.2, why)
    assert (done["after"].value, done["after"].error) == (6, None)
    assert lines[0] == f"  [1/2] stuck: FAILED ({why})"
    assert len(forks) == 2 and all(_reaped(p) for p in forks)


def test_an_engine_is_skipped_for_its_first_fall_not_a_later_one(monkeypatch):
    """Two workers, every limit 0.3 s: engine 'x''s first task dies at once, its second (already
    running) then passes its limit; a harness task that hangs keeps the queue from reaching
    x's last task until that time-out. The last task is skipped for the first fall (the
    death), as docs/robustness.md's 'skipped: its engine's worker died ...'. Planted: a later fall
    overwriting the first; the key named despite a label; the fallen engines looked up by key; the
    prefix 'its worker process ' kept; no replacement worker after a time-out; the floor printed
    for the factor."""
    tasks = [Task("dies", _exit_now, (3,), cost=9.0, label="dies first", engine="x"),
             Task("hangs", time.sleep, (HANG,), cost=8.0, label="hangs later", engine="x"),
             Task("harness", time.sleep, (HANG,), cost=5.0),
             Task("last", abs, (-1,), cost=1.0, engine="x")]
    forks = _recording_forks(monkeypatch)
    done = run_tasks(tasks, workers=2, warm=(), limits=Limits(floor=0.3, factor=0.0))
    assert done["hangs"].error.startswith("timed out after 0.3 s (limit: 0 x its expected 8 s")
    assert done["last"].error == ("skipped: its engine's worker died (exit status 3) in "
                                  "'dies first'")
    assert all(_reaped(p) for p in forks)


# ----------------------------------------------------------------------------- call_in_worker

def test_call_in_worker_returns_the_value_of_the_call_with_its_arguments(monkeypatch):
    """Positional and keyword arguments reach the call; its value comes back; the worker is
    reaped. Planted: the keyword arguments dropped; close ending only the busy workers; waitpid
    with WNOHANG."""
    forks = _recording_forks(monkeypatch)
    assert call_in_worker(divmod, 17, 5) == (3, 2)
    assert call_in_worker(int, "ff", base=16) == 255
    assert call_in_worker(dict) == {}
    assert call_in_worker(os.getpid) != os.getpid()
    assert len(forks) == 4 and all(_reaped(p) for p in forks)


def test_call_in_worker_raises_the_calls_exception_or_its_text(monkeypatch):
    """The call's exception raised here as itself; as a RuntimeError with its text when it
    does not pickle (a local class) or unpickle; a dead worker a RuntimeError saying how.
    Planted: success read from a missing pickled exception (``reply.exception is None``); the text
    returned whenever the exception was pickled; only ImportError caught around the unpickling; the
    pickled exception dropped; str(exc) for describe(exc); 'its worker died'; the raw status."""
    class Local(Exception):
        pass

    def local():
        raise Local("boom")

    forks = _recording_forks(monkeypatch)
    with pytest.raises(ValueError, match=r"^invalid literal for int\(\) with base 10: 'zz'$"):
        call_in_worker(int, "zz")
    with pytest.raises(RuntimeError, match="^Local: boom$"):
        call_in_worker(local)
    with pytest.raises(RuntimeError, match="^TwoArgs: half of it$"):
        call_in_worker(_raise_two_args)
    with pytest.raises(RuntimeError, match=r"^its worker process died \(exit status 5\)$"):
        call_in_worker(_exit_now, 5)
    assert all(_reaped(p) for p in forks)


def test_call_in_worker_past_its_time_limit_is_a_stage_timeout(monkeypatch):
    """A call past ``time_limit`` raises StageTimeout 'timed out after 0.2 s (its worker was
    killed)', soon, and the worker is reaped. Planted: the message 'timed out in'; RuntimeError for
    StageTimeout; waitpid with WNOHANG."""
    forks = _recording_forks(monkeypatch)
    t0 = time.monotonic()
    with pytest.raises(StageTimeout, match=r"^timed out after 0\.2 s \(its worker was killed\)$"):
        call_in_worker(time.sleep, HANG, time_limit=0.2)
    assert 0.2 <= time.monotonic() - t0 < PATIENCE
    assert len(forks) == 1 and _reaped(forks[0])


def test_what_a_worker_prints_is_written_once(tmp_path, monkeypatch):
    """stdout a block-buffered file (as when redirected): the text the test wrote before the
    fork is written once (flushed before the fork, not again by the worker), and what the call
    printed is written before its worker is killed. Planted: no flush after the call (its line lost
    with the killed worker); no flush before the fork (the test's 'before;' written twice)."""
    with open(tmp_path / "out", "w", encoding="utf-8") as out:
        monkeypatch.setattr(sys, "stdout", out)
        out.write("before;")
        call_in_worker(print, "worker")
        out.write("after")
    assert (tmp_path / "out").read_text(encoding="utf-8") == "before;worker\nafter"


# ----------------------------------------------------------------------------- signals

def _child_runs(body, sig) -> int:
    """``body`` in a forked child of the test with SIGTERM at its default and SIGINT raising
    KeyboardInterrupt, both unblocked; its exit code: 0 when the signal ``sig``, sent by its
    worker to it, was raised out of the pool as its exception and no worker of the child is
    left, unwaited; 1 when the pool returned; 2 when a worker was left; 3 another exception."""
    pool.flush_streams()
    pid = os.fork()
    if pid == 0:
        code = 3
        try:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            signal.signal(signal.SIGINT, signal.default_int_handler)
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
            expected = Terminated if sig == signal.SIGTERM else KeyboardInterrupt
            try:
                body()
                code = 1
            except expected:
                try:
                    os.waitpid(-1, os.WNOHANG)
                    code = 2
                except ChildProcessError:
                    code = 0
        finally:
            os._exit(code)
    return _wait_for_exit(pid)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_ends_run_tasks_and_every_worker_at_once(sig):
    """SIGTERM (Terminated) or Ctrl-C (KeyboardInterrupt) reaching the main process while two
    workers run (one signals it, the other hangs): run_tasks raises it, every worker killed
    and reaped, well within the 2 s of README. Planted: run_tasks without terminating() (SIGTERM
    ended the child); the workers closed only on an Exception (KeyboardInterrupt and Terminated
    left them running); close ending only the busy workers."""
    t0 = time.monotonic()
    assert _child_runs(lambda: run_tasks([
        Task("signals", _signal_parent_then_hang, (sig,), cost=2.0),
        Task("hangs", time.sleep, (HANG,), cost=1.0)], workers=2, warm=()), sig) == 0
    assert time.monotonic() - t0 < 2.0


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_ends_call_in_worker_and_its_worker_at_once(sig):
    """The same for one call in a worker: raised out of call_in_worker, its worker reaped.
    Planted: call_in_worker without terminating() (SIGTERM ended the child); waitpid with
    WNOHANG."""
    t0 = time.monotonic()
    assert _child_runs(lambda: call_in_worker(_signal_parent_then_hang, sig), sig) == 0
    assert time.monotonic() - t0 < 2.0


# ----------------------------------------------------------------------------- imports

def test_engine_imports_are_the_registered_modules_once_each_in_order(monkeypatch):
    """The module part of each ``module:Class`` target, stripped, first appearance order,
    duplicates once. Planted: the class part of the target read as its module; the targets not
    stripped; sorted, not in the registry's order; the duplicates kept."""
    import engines.registry as registry
    targets = ["pkg.alpha:A", " pkg.beta : B", "pkg.alpha:Other", "gamma:G"]
    monkeypatch.setattr(registry, "registrations",
                        lambda: [SimpleNamespace(target=t) for t in targets])
    assert pool.engine_imports() == ("pkg.alpha", "pkg.beta", "gamma")


@pytest.fixture
def probe_modules(tmp_path, monkeypatch):
    """Modules in a temporary folder on sys.path, named ``pool_edges_*``; forgotten after."""
    files = {
        "pool_edges_warm.py": "WARM = ('pool_edges_w',)\nREQUIRES = ('pool_edges_r',)\n",
        "pool_edges_str.py": "REQUIRES = 'z'\n",      # a name, not a tuple: its letters
        "pool_edges_set.py": "REQUIRES = {'pool_edges_s'}\n",
        "z.py": "",
        "pool_edges_mixed.py": ("REQUIRES = ('pool_edges_pkg.sub', 5, 'pool_edges_absent',\n"
                                "            'pool_edges_broken', 'pool_edges_last')\n"),
        "pool_edges_raises.py": "raise RuntimeError('cannot import')\n",
        "pool_edges_base.py": "", "pool_edges_engine.py": "",
        "pool_edges_w.py": "", "pool_edges_r.py": "", "pool_edges_s.py": "",
        "pool_edges_broken.py": "raise RuntimeError('broken library')\n",
        "pool_edges_last.py": "",
        "pool_edges_pkg/__init__.py": "", "pool_edges_pkg/sub.py": ""}
    yield from modules_on_path(tmp_path, monkeypatch, files,
                               lambda name: name.startswith("pool_edges_") or name == "z")


def modules_on_path(tmp_path, monkeypatch, files: dict, ours):
    """Write ``files`` (path: text) under ``tmp_path``, put it on sys.path for the test, and
    forget every imported module ``ours(name)`` accepts after it (a fixture's body)."""
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text(text)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield
    for name in list(sys.modules):
        if ours(name):
            del sys.modules[name]


def test_warm_imports_takes_warm_over_requires_and_skips_what_fails(probe_modules):
    """Each named module is imported; a module that does not import is skipped and the next
    one still warmed; its ``WARM`` libraries are imported instead of its ``REQUIRES``; a
    ``REQUIRES`` not a tuple or list (a string, whose letters would be module names; a set)
    is malformed and skipped; a dotted library is found by its top-level
    package; a non-string entry, a library not installed or one that raises on import is
    skipped and the rest imported. Planted: break at the first module that does not import;
    REQUIRES read before WARM; a string REQUIRES not refused (its letter 'z' imported); a set
    REQUIRES not refused; a dotted library looked up by its last part; the installed test
    inverted."""
    assert "z" not in sys.modules
    pool.warm_imports(("pool_edges_nowhere", "pool_edges_raises", "pool_edges_warm",
                       "pool_edges_str", "pool_edges_set", "pool_edges_mixed"))
    imported = {n for n in sys.modules if n.startswith("pool_edges_") or n == "z"}
    assert imported == {"pool_edges_warm", "pool_edges_w", "pool_edges_str", "pool_edges_set",
                        "pool_edges_mixed", "pool_edges_pkg", "pool_edges_pkg.sub",
                        "pool_edges_last"}


def test_warm_imports_by_default_warms_the_base_and_the_engines(probe_modules, monkeypatch):
    """With no names: `BASE_IMPORTS` and then every `engine_imports` module. Planted: the default
    names without the engines'."""
    monkeypatch.setattr(pool, "BASE_IMPORTS", ("pool_edges_base",))
    monkeypatch.setattr(pool, "engine_imports", lambda: ("pool_edges_engine",))
    pool.warm_imports()
    assert "pool_edges_base" in sys.modules and "pool_edges_engine" in sys.modules
