"""A chunk's bicycles one at a time, each under a time limit (the sweep's Dask task).

    rows = limited_chunk_rows(spec, indices, limit)

Each bicycle (`sweep_task.bicycle_row`) runs in a helper thread of the worker process while the
task's own thread waits at most ``limit`` seconds for it. A bicycle past its limit is a
"failed" row, ``timed out after N s``, and the chunk goes on with the next bicycle in a fresh
helper thread: the late one cannot be stopped from outside (a thread cannot be killed, and the
engine may be inside C), so it is left to finish or to sleep in its daemon thread until the
worker process ends (a local cluster ends with the sweep). Something an engine raises that
`bicycle_row` lets through (``SystemExit``, ``KeyboardInterrupt``, any ``BaseException``) is
that bicycle's failed row too, never the end of the worker.

An engine that holds the interpreter's lock forever (a C loop that never releases the GIL)
stops the waiting thread as well: that case is caught from the client's side, where the task
passes its deadline and its worker process is restarted (`sweep_schedule`).
"""

from __future__ import annotations

import queue
import threading

from .sweep_spec import SweepSpec
from .sweep_task import bicycle_row, failed_row

__all__ = ["limited_chunk_rows", "one_line"]


def one_line(exc: BaseException) -> str:
    """An exception as ``Type: message`` on one line, at most 500 characters."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"[:500]


class _Helper:
    """A daemon thread computing one job at a time: ``(function, args)`` in, ``(ok, value)`` out."""

    def __init__(self) -> None:
        self.jobs: queue.SimpleQueue = queue.SimpleQueue()
        self.results: queue.SimpleQueue = queue.SimpleQueue()
        threading.Thread(target=self._loop, name="bicycle-xval-bicycle", daemon=True).start()

    def _loop(self) -> None:
        while (job := self.jobs.get()) is not None:
            fn, args = job
            try:
                self.results.put((True, fn(*args)))
            except BaseException as exc:      # noqa: BLE001 -- the bicycle's failure, reported
                self.results.put((False, exc))

    def run(self, fn, args, limit: float):
        """``(ok, value)`` of ``fn(*args)``; `queue.Empty` past ``limit`` seconds."""
        self.jobs.put((fn, args))
        return self.results.get(timeout=limit)

    def stop(self) -> None:
        """End the thread after its current job (at once when idle)."""
        self.jobs.put(None)


def limited_chunk_rows(spec: SweepSpec, indices, limit: float) -> list[dict]:
    """The rows of ``indices`` (module docstring); top-level and picklable for Dask."""
    rows: list[dict] = []
    helper = None
    try:
        for k in indices:
            helper = helper or _Helper()
            try:
                ok, value = helper.run(bicycle_row, (spec, k), limit)
            except queue.Empty:
                rows.append(failed_row(spec, k, f"timed out after {limit:g} s"))
                helper.stop()          # ends the late thread if its bicycle ever returns
                helper = None
                continue
            rows.append(value if ok else failed_row(spec, k, f"raised {one_line(value)}"))
    finally:
        if helper is not None:
            helper.stop()
    return rows
