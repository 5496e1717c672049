"""Independent calls in forked worker processes, longest first, ended with the main process.

`run_tasks` runs calls in worker processes forked from this one and returns their results
keyed as given; `call_in_worker` runs one call in a worker and returns its value or raises its
exception, so that a long call stays stoppable (Exudyn's solver, in C++, catches the
exception a signal raises in its Python callbacks and runs on or fails with its own error; a
worker is simply killed). The calls are
not pickled (the workers are forks, they know them); results come back through one pipe per
worker, and a worker that dies fails only its own call. Workers start as `signals.child_init`
says: SIGTERM ends them, SIGINT is the main process's to decide, and they die with their
parent however it ends. On SIGTERM or Ctrl-C the main process kills its workers (SIGKILL),
reaps them and re-raises, so the caller can leave the output folder as it was. The pool has no
threads, so nothing is left to join when the process exits.
"""

from __future__ import annotations

import os
import pickle
import signal
import time
from collections import deque
from dataclasses import dataclass, field
from functools import partial
from multiprocessing.connection import Connection, Pipe, wait
from typing import Any, Callable, Hashable

from engines.guard import describe

from .signals import (Terminated, blocked, child_init, flush_streams, raise_terminated,
                      terminating)

__all__ = ["BASE_IMPORTS", "MAX_WORKERS", "Limits", "StageTimeout", "Task", "TaskResult",
           "Terminated", "call_in_worker", "default_workers", "engine_imports", "raise_terminated",
           "run_tasks", "warm_imports"]

MAX_WORKERS = 8
#: imported once in the main process before the stages' workers fork, besides every registered
#: engine's module and the libraries it declares (`engine_imports`); matplotlib is the figure
#: pool's (`comparisons.report.writer`), not imported for runs that draw none
BASE_IMPORTS = ("scipy.integrate",)


def engine_imports() -> tuple[str, ...]:
    """The module of every registered engine (the ``module`` of its ``module:Class`` entry
    point), in the registry's order; nothing is imported to list them. Importing one imports
    its library when it is installed (the engine's package does, docs/engines.md), and
    `warm_imports` imports the modules it declares in ``REQUIRES`` too."""
    from engines.registry import registrations
    return tuple(dict.fromkeys(r.target.partition(":")[0].strip() for r in registrations()))


def warm_imports(names: tuple[str, ...] | None = None) -> None:
    """Import ``names`` (default: `BASE_IMPORTS` and `engine_imports`) so that forked workers
    inherit them instead of each importing them again (about a second of CPU per worker for
    the engines' libraries). A module that does not import is skipped (an engine whose library
    is absent: its stage says so), and so is a declared ``REQUIRES`` (or ``WARM``) that is not
    installed."""
    import importlib

    from engines.registry import missing_modules
    for name in BASE_IMPORTS + engine_imports() if names is None else names:
        try:
            module = importlib.import_module(name)
        except Exception:   # noqa: BLE001 - an engine's library may be absent: its stage says so
            continue
        # the libraries to warm: the package's WARM when it declares one (a library needed
        # only on a cold cache, e.g. to derive equations, need not be), else its REQUIRES
        requires = getattr(module, "WARM", getattr(module, "REQUIRES", ()))
        if isinstance(requires, str) or not isinstance(requires, (tuple, list)):
            continue        # malformed: the registry reports it when the engine is resolved
        for lib in requires:
            if isinstance(lib, str) and not missing_modules((lib.split(".")[0],)):
                try:
                    importlib.import_module(lib)
                except Exception:   # noqa: BLE001 - the engine's own resolution reports it
                    pass


@dataclass(frozen=True)
class Task:
    """One call to run in a worker: ``func(*args)``; ``cost`` (s) orders the queue.
    ``engine``: the engine whose code the call runs (its spec; None: the reference's or the
    harness's own): once a worker dies or times out in one of its calls, its calls still
    queued are not started (`run_tasks`)."""

    key: Hashable
    func: Callable[..., Any]
    args: tuple = ()
    cost: float = 1.0
    label: str = ""
    engine: str | None = None


@dataclass(frozen=True)
class Limits:
    """How long a task may run: ``override`` (s, ``run --stage-timeout``) for every task, else
    its declared cost (the scheduling estimate, s on the 2-core machine) times ``factor``, at
    least ``floor``. The factor and floor leave room for a machine several times slower or
    loaded (a cost is a typical time, not a bound); a task past ``slow`` times its cost (at
    least ``slow_floor``) is named on the progress line once, while it runs."""

    override: float | None = None
    floor: float = 60.0
    factor: float = 20.0
    slow: float = 4.0
    slow_floor: float = 10.0

    def budget(self, task: "Task") -> float:
        return self.override if self.override is not None else max(self.floor,
                                                                    self.factor * task.cost)

    def expected(self, task: "Task") -> float:
        return min(self.budget(task), max(self.slow_floor, self.slow * task.cost))


class StageTimeout(RuntimeError):
    """A call ran past its time limit; its worker was killed."""


@dataclass
class TaskResult:
    key: Hashable
    value: Any
    seconds: float
    error: str | None = None


@dataclass(frozen=True)
class _Reply:
    """What a worker sends back for call ``index``: its value, or its error as text and (when
    it pickles) the exception itself."""

    index: int
    value: Any = None
    seconds: float = 0.0
    error: str | None = None
    exception: bytes | None = None


def _serve(conn: Connection, calls: list[tuple[Callable, tuple]]) -> None:
    """A worker's loop: the index of a call in, its `_Reply` out, until the pipe closes."""
    while True:
        try:
            k = conn.recv()
        except EOFError:
            return
        func, args = calls[k]
        t0 = time.perf_counter()
        try:
            reply = _Reply(k, func(*args), time.perf_counter() - t0)
        except BaseException as exc:   # noqa: BLE001 - a broken call is reported, the others go
            # on (SIGINT is ignored here and SIGTERM kills: any interruption is the call's own)
            try:
                raised = pickle.dumps(exc)
            except Exception:      # noqa: BLE001 - the text is enough
                raised = None
            reply = _Reply(k, error=describe(exc), exception=raised)
        flush_streams()     # what the call printed: the worker ends by SIGKILL, unflushed
        try:
            conn.send(reply)
        except Exception as exc:   # noqa: BLE001 - the value does not pickle
            conn.send(_Reply(k, error=f"its result could not be sent back ({describe(exc)})"))


@dataclass
class _Workers:
    """Forked workers, each with its own pipe; `close` kills and reaps them all."""

    calls: list[tuple[Callable, tuple]]
    busy: dict[Connection, int] = field(default_factory=dict)     # pipe -> call index
    pids: dict[Connection, int] = field(default_factory=dict)     # pipe -> worker pid
    started: dict[Connection, float] = field(default_factory=dict)   # pipe -> when given

    def fork(self) -> Connection:
        parent = os.getpid()
        mine, theirs = Pipe()
        flush_streams()
        with blocked():
            pid = os.fork()
            if pid == 0:   # the worker: never returns into the caller's code
                code = 1
                try:
                    for conn in (mine, *self.pids):
                        conn.close()
                    child_init(parent)
                    _serve(theirs, self.calls)
                    code = 0
                finally:
                    os._exit(code)
            theirs.close()
            self.pids[mine] = pid
        return mine

    def give(self, conn: Connection, k: int) -> None:
        conn.send(k)
        self.busy[conn] = k
        self.started[conn] = time.monotonic()

    def reply(self, timeout: float | None = None) -> tuple[_Reply, Connection | None] | None:
        """The next reply, and the pipe of the worker that is now free (None: it died); None
        when no reply came within ``timeout`` seconds."""
        ready = wait(list(self.busy), timeout)
        if not ready:
            return None
        conn = ready[0]
        k = self.busy.pop(conn)
        try:
            return conn.recv(), conn
        except (EOFError, OSError):
            status = self._end(conn)
            return _Reply(k, error=f"its worker process died ({_how(status)})"), None

    def kill(self, conn: Connection) -> int:
        """End the worker of ``conn`` (a call past its limit): its call index."""
        k = self.busy[conn]
        self._end(conn)
        return k

    def _end(self, conn: Connection) -> int:
        pid = self.pids.pop(conn)
        self.busy.pop(conn, None)
        self.started.pop(conn, None)
        with blocked():
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            status = os.waitpid(pid, 0)[1]
            conn.close()
        return status

    def close(self) -> None:
        with blocked():   # a second signal cannot leave a worker behind
            for conn in list(self.pids):
                self._end(conn)


def _how(status: int) -> str:
    if os.WIFSIGNALED(status):
        return f"killed by {signal.Signals(os.WTERMSIG(status)).name}"
    return f"exit status {os.WEXITSTATUS(status)}"


def default_workers(n_tasks: int) -> int:
    """The machine's cores, never more than the tasks nor MAX_WORKERS."""
    return max(1, min(os.cpu_count() or 1, n_tasks, MAX_WORKERS))


def run_tasks(tasks: list[Task], workers: int | None = None,
              progress: Callable[[str], None] = lambda s: None,
              warm: tuple[str, ...] | None = None,
              limits: Limits | None = None) -> dict[Hashable, TaskResult]:
    """Run every task in worker processes; a task that raises (or whose worker dies) becomes a
    `TaskResult` with ``error`` set (the exception's type and message, one line), never an
    aborted run. ``warm``: modules imported in this process before the workers fork (they
    inherit them; default `warm_imports`' own: the engines'). ``limits``: each task's time
    limit (`Limits`; None: none); a task past it is 'timed out after N s', its worker killed
    and replaced, and one running longer than expected is named on the progress line. Once a
    task of an engine (`Task.engine`) has killed its worker or timed out, that engine's tasks
    still queued are skipped, each a failure that says why: an engine that crashes its process
    or hangs once is not given every other stage's time limit to do it again."""
    if not tasks:
        return {}
    order = sorted(tasks, key=lambda t: -t.cost)
    workers = min(workers or default_workers(len(order)), len(order))
    results: dict[Hashable, TaskResult] = {}
    warm_imports(warm)
    queue = deque(range(len(order)))
    told: set[int] = set()     # tasks already named as slow
    fallen: dict[str, str] = {}    # engine -> why its queued tasks are skipped
    pool = _Workers([(t.func, t.args) for t in order])

    def done(task: Task, result: TaskResult) -> None:
        results[task.key] = result
        progress(_line(len(results), len(order), task, result))

    def next_call() -> int | None:
        """The next queued task to start; the skipped ones before it are recorded."""
        while queue:
            k = queue.popleft()
            why = fallen.get(order[k].engine)
            if why is None:
                return k
            done(order[k], TaskResult(order[k].key, None, 0.0, why))
        return None

    def fell(task: Task, error: str) -> None:
        if task.engine is not None and task.engine not in fallen:
            fallen[task.engine] = (f"skipped: its engine's worker {error.partition(';')[0]} "
                                   f"in '{task.label or task.key}'")

    with terminating():
        try:
            for _ in range(workers):
                if (k := next_call()) is not None:
                    pool.give(pool.fork(), k)
            while pool.busy:
                got = pool.reply(_wait(pool, order, limits, told, progress))
                if got is None:
                    for conn, k in _overdue(pool, order, limits):
                        task = order[k]
                        pool.kill(conn)
                        done(task, TaskResult(task.key, None, limits.budget(task),
                                              _timed_out(limits, task)))
                        fell(task, f"timed out after {limits.budget(task):.3g} s")
                        if (k := next_call()) is not None:
                            pool.give(pool.fork(), k)
                    continue
                reply, free = got
                task = order[reply.index]
                done(task, TaskResult(task.key, reply.value, reply.seconds, reply.error))
                if free is None:
                    fell(task, reply.error.removeprefix("its worker process "))
                if (k := next_call()) is not None:
                    pool.give(free or pool.fork(), k)
        finally:
            pool.close()
    return results


def call_in_worker(func: Callable[..., Any], *args, time_limit: float | None = None,
                   **kwargs) -> Any:
    """``func(*args, **kwargs)`` in one worker process: its value, or its exception raised here
    (a `RuntimeError` with its text when it does not pickle, or when the worker died;
    `StageTimeout` when it ran past ``time_limit`` seconds, and its worker was killed)."""
    pool = _Workers([(partial(func, *args, **kwargs), ())])
    with terminating():
        try:
            pool.give(pool.fork(), 0)
            got = pool.reply(time_limit)
        finally:
            pool.close()
    if got is None:
        raise StageTimeout(f"timed out after {time_limit:.3g} s (its worker was killed)")
    reply, _ = got
    if reply.error is None:
        return reply.value
    raise _exception(reply)


def _exception(reply: _Reply) -> BaseException:
    try:
        return pickle.loads(reply.exception) if reply.exception else RuntimeError(reply.error)
    except Exception:   # noqa: BLE001 - an exception that does not unpickle: its text
        return RuntimeError(reply.error)


def _wait(pool: _Workers, order: list[Task], limits: Limits | None, told: set,
          progress: Callable[[str], None]) -> float | None:
    """Seconds until the next limit or slow-stage notice of a running task (None: no limits,
    or none due, e.g. an infinite limit already past its notice: wait for the next reply);
    names, once, each running task already past its expected time."""
    if limits is None:
        return None
    now, soonest = time.monotonic(), float("inf")
    for conn, k in pool.busy.items():
        task, ran = order[k], now - pool.started[conn]
        expected = limits.expected(task)
        if ran >= expected and k not in told and expected < limits.budget(task):
            told.add(k)
            progress(f"  ... {task.label or task.key}: still running after {ran:.0f} s "
                     f"(expected about {task.cost:g} s; its limit is "
                     f"{limits.budget(task):.0f} s)")
        for at in (expected, limits.budget(task)):
            if at > ran:
                soonest = min(soonest, at - ran)
        if ran >= limits.budget(task):
            soonest = 0.0
    if soonest == float("inf"):   # nothing due: wait for a reply (none running: not at all)
        return None if pool.busy else 0.0
    return max(0.0, soonest)


def _overdue(pool: _Workers, order: list[Task], limits: Limits | None) -> list[tuple]:
    if limits is None:
        return []
    now = time.monotonic()
    return [(conn, k) for conn, k in list(pool.busy.items())
            if now - pool.started[conn] >= limits.budget(order[k])]


def _timed_out(limits: Limits, task: Task) -> str:
    why = ("--stage-timeout" if limits.override is not None else
           f"{limits.factor:g} x its expected {task.cost:g} s, at least {limits.floor:g} s; "
           "--stage-timeout sets it")
    return (f"timed out after {limits.budget(task):.3g} s (limit: {why}); its worker was "
            "killed")


def _line(k: int, n: int, task: Task, r: TaskResult) -> str:
    what = task.label or str(task.key)
    if r.error:
        return f"  [{k}/{n}] {what}: FAILED ({r.error})"
    return f"  [{k}/{n}] {what} ({r.seconds:.1f} s)"
