"""Independent stages in worker processes, longest first, ended with the main process.

`run_tasks` runs picklable top-level calls in a `ProcessPoolExecutor` and returns their results
keyed as given. Workers ignore SIGINT (the main process decides) and, on Linux, ask the kernel
to end them when their parent dies (``PR_SET_PDEATHSIG``), so a killed run never leaves
workers behind. On SIGTERM or Ctrl-C the main process cancels what has not started, terminates
the workers and re-raises, so the caller can leave the output folder as it was.
"""

from __future__ import annotations

import os
import signal
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from typing import Any, Callable, Hashable

MAX_WORKERS = 8
#: imported once in the main process before the stages' workers fork, so each worker does not
#: import them again (about a second of CPU per worker for the engines' libraries); matplotlib
#: is the figure pool's (`comparisons.report.writer`), not imported for runs that draw none
WARM_IMPORTS = ("scipy.integrate", "pinocchio", "exudyn", "mujoco",
                "engines.pinocchio", "engines.exudyn", "engines.kane", "engines.mujoco")


def warm_imports(names: tuple[str, ...] = WARM_IMPORTS) -> None:
    import importlib
    for name in names:
        try:
            importlib.import_module(name)
        except Exception:   # noqa: BLE001 - an engine's library may be absent: its stage says so
            pass


@dataclass(frozen=True)
class Task:
    """One call to run in a worker: ``func(*args)``; ``cost`` (s) orders the queue."""

    key: Hashable
    func: Callable[..., Any]
    args: tuple = ()
    cost: float = 1.0
    label: str = ""


@dataclass
class TaskResult:
    key: Hashable
    value: Any
    seconds: float
    error: str | None = None


def _worker_init() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:   # Linux: die with the parent (PR_SET_PDEATHSIG = 1)
        import ctypes
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)
    except (OSError, AttributeError):
        pass


def _timed(func, args):
    t0 = time.perf_counter()
    return func(*args), time.perf_counter() - t0


class Terminated(KeyboardInterrupt):
    """SIGTERM reached the main process: an interruption like Ctrl-C (never caught by an
    ``except Exception``), so every ``finally`` and context manager on the way out runs."""


def raise_terminated(signum, frame):
    """A SIGTERM handler: turn the signal into `Terminated`."""
    raise Terminated("terminated (SIGTERM)")


def default_workers(n_tasks: int) -> int:
    """The machine's cores, never more than the tasks nor MAX_WORKERS."""
    return max(1, min(os.cpu_count() or 1, n_tasks, MAX_WORKERS))


def run_tasks(tasks: list[Task], workers: int | None = None,
              progress: Callable[[str], None] = lambda s: None,
              warm: tuple[str, ...] = WARM_IMPORTS) -> dict[Hashable, TaskResult]:
    """Run every task; a task that raises becomes a `TaskResult` with ``error`` set (the
    exception's type and message), never an aborted run. ``warm``: modules imported in this
    process before the workers fork (they inherit them)."""
    if not tasks:
        return {}
    workers = min(workers or default_workers(len(tasks)), len(tasks))
    order = sorted(tasks, key=lambda t: -t.cost)
    results: dict[Hashable, TaskResult] = {}
    n = len(order)
    if workers <= 1:
        for k, task in enumerate(order, 1):
            results[task.key] = _run_here(task)
            progress(_line(k, n, task, results[task.key]))
        return results
    previous = signal.getsignal(signal.SIGTERM)
    signal.signal(signal.SIGTERM, raise_terminated)
    warm_imports(warm)
    pool = ProcessPoolExecutor(max_workers=workers, initializer=_worker_init)
    try:
        pending = {pool.submit(_timed, t.func, t.args): t for t in order}
        done_count = 0
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                task = pending.pop(fut)
                try:
                    value, seconds = fut.result()
                    results[task.key] = TaskResult(task.key, value, seconds)
                except Exception as exc:   # a broken stage is reported, the others go on
                    results[task.key] = TaskResult(task.key, None, 0.0,
                                                   f"{type(exc).__name__}: {exc}")
                done_count += 1
                progress(_line(done_count, n, task, results[task.key]))
    except BaseException:
        for p in list(getattr(pool, "_processes", {}).values()):
            p.terminate()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    else:
        pool.shutdown()
    finally:
        signal.signal(signal.SIGTERM, previous)
    return results


def _run_here(task: Task) -> TaskResult:
    try:
        value, seconds = _timed(task.func, task.args)
        return TaskResult(task.key, value, seconds)
    except Exception as exc:
        return TaskResult(task.key, None, 0.0, f"{type(exc).__name__}: {exc}")


def _line(k: int, n: int, task: Task, r: TaskResult) -> str:
    what = task.label or str(task.key)
    if r.error:
        return f"  [{k}/{n}] {what}: FAILED ({r.error})"
    return f"  [{k}/{n}] {what} ({r.seconds:.1f} s)"
