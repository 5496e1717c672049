"""The sweep's tasks on a Dask client: a bounded window of chunks in flight, and a lost task
narrowed down to the bicycle that loses it.

    failed_tasks = compute(client, spec, todo, limit, on_chunk, on_bicycles)

* **Window**: at most two tasks per worker are in flight; the rest wait on this side, so a
  large sweep holds a few futures, not one per chunk, and an interrupt has little to cancel.
* **A lost task** (its worker died, Dask gave up with ``KilledWorker``, or the task raised
  through `sweep_deadline`) proves nothing about any one of its bicycles: when a worker dies,
  Dask also fails the tasks queued beside it on that worker, healthy ones included. So a lost
  chunk is split into one task per bicycle, and each of those runs **alone** (nothing else of
  the sweep in flight, after every other chunk): a bicycle whose lone task is lost again is the
  one that loses it and becomes a "failed" row (``task lost: ...``); the others are computed
  again and keep their results.
* **A task past its deadline** (its bicycles' limits, ``PER_WORKER`` deep, plus `GRACE`): the
  per-bicycle limit is kept inside the task (`sweep_deadline`), by a thread that needs the
  interpreter's lock; an engine that holds it forever (a C loop that never releases the GIL)
  freezes the whole worker process, its limit and its heartbeats included. Seen from here,
  such a task never ends: it is cancelled, its worker process restarted through its nanny (a
  local cluster's, or any ``dask worker`` started with one), and it is lost like the others:
  narrowed down, and the bicycle that freezes its worker alone is a "failed" row. A cluster of
  threads (``--processes`` off) has no process to restart: there the sweep cannot be saved.
* ``on_chunk(i, rows)`` is called once per chunk, with all its rows, as soon as the chunk is
  complete (the sweep writes its file there); ``on_bicycles(n)`` as rows arrive (the progress
  bar).
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass

from .sweep_deadline import limited_chunk_rows, one_line
from .sweep_spec import SweepSpec, spec_hash
from .sweep_task import failed_row

__all__ = ["GRACE", "PER_WORKER", "TaskOverdue", "Work", "compute", "deadline"]

PER_WORKER = 2      # tasks in flight per worker: one running, one ready behind it
POLL = 0.05         # s between two looks at the finished futures (a task takes ~3 s)
GRACE = 30.0        # s past its bicycles' limits before a task's worker counts as frozen:
                    # a worker process starting (imports, the generated code: ~3-10 s loaded)


class TaskOverdue(Exception):
    """A task that did not end by its deadline: its worker froze (module docstring)."""


@dataclass(frozen=True)
class Work:
    """One task: bicycles of chunk ``chunk``; ``alone``: run with nothing else in flight."""

    chunk: int
    bicycles: tuple[int, ...]
    alone: bool = False


def compute(client, spec: SweepSpec, todo, limit: float, on_chunk, on_bicycles=None,
            task=limited_chunk_rows, check=lambda: None, say=lambda line: None,
            grace: float = GRACE) -> int:
    """Every chunk of ``todo`` (pairs of chunk number and bicycles) computed on ``client``
    (module docstring); returns how many tasks were lost. ``task``: the Dask task,
    ``task(spec, bicycles, limit) -> rows``; ``check``: called while waiting, raises to stop
    (`sweep_signals.StopRequest.check`); ``say``: one line for the user per lost task;
    ``grace``: seconds past its bicycles' limits before a task's worker counts as frozen."""
    from distributed import as_completed
    h = spec_hash(spec)
    workers = max(1, len(client.scheduler_info(n_workers=-1)["workers"]))
    window = PER_WORKER * workers
    fresh = iter(todo)                        # chunks not submitted yet (made as they go)
    pending: deque[Work] = deque()
    alone: deque[Work] = deque()
    rows: dict[int, list[dict]] = {}
    left: dict[int, int] = {}                 # tasks outstanding per chunk submitted

    def refill() -> None:
        if not pending:
            for i, c in fresh:
                rows[i], left[i] = [], 1
                pending.append(Work(i, tuple(c)))
                return

    flight: dict = {}
    due: dict = {}                            # future -> monotonic time it must end by
    done = as_completed()
    lost = 0

    def submit(w: Work) -> None:
        suffix = f"-{w.bicycles[0]}-alone" if w.alone else ""
        f = client.submit(task, spec, w.bicycles, limit, pure=False,
                          key=f"sweep-{h}-{w.chunk:06d}{suffix}")
        flight[f] = w
        due[f] = time.monotonic() + deadline(len(w.bicycles), limit, 1 if w.alone else PER_WORKER,
                                                 grace)
        done.add(f)

    refill()
    while pending or alone or flight:
        while pending and len(flight) < window:
            submit(pending.popleft())
            refill()
        if not flight:                         # every other task finished: one suspect alone
            submit(alone.popleft())
        for fut, overdue in _finished(done, check, due, client, say):
            if fut not in flight:              # a cancelled one, already counted
                continue
            w = flight.pop(fut)
            due.pop(fut, None)
            try:
                if overdue is not None:
                    raise overdue
                got = fut.result()
            except Exception as exc:           # noqa: BLE001 -- a lost task: narrowed down
                lost += 1
                got = []
                if w.alone:
                    why = f"task lost when run alone: {one_line(exc)}"
                    got = [failed_row(spec, k, why) for k in w.bicycles]
                    say(f"sweep: bicycle {w.bicycles[0]} loses its task even alone "
                        f"({type(exc).__name__}): a failed row")
                else:
                    say(f"sweep: a task of chunk {w.chunk} was lost ({type(exc).__name__}); its "
                        f"{len(w.bicycles)} bicycle{'s' if len(w.bicycles) > 1 else ''} run again "
                        "one at a time, alone, to find the one that loses it")
                    alone.extend(Work(w.chunk, (k,), alone=True) for k in w.bicycles)
                    left[w.chunk] += len(w.bicycles) - 1
            finally:
                fut.release()
            if got:
                rows[w.chunk] += got
                left[w.chunk] -= 1
                if on_bicycles:
                    on_bicycles(len(got))
            if left[w.chunk] == 0:
                on_chunk(w.chunk, rows.pop(w.chunk))
    return lost


def deadline(n_bicycles: int, limit: float, depth: int, grace: float = GRACE) -> float:
    """Seconds a task of ``n_bicycles`` may take from its submission: each bicycle's
    ``limit``, behind at most ``depth`` tasks like it on its worker, plus ``grace``."""
    return depth * n_bicycles * limit + grace


def _finished(done, check, due: dict, client, say, poll: float = POLL) -> list[tuple]:
    """(future, None) for the futures finished so far, or (future, `TaskOverdue`) for those past
    their deadline in ``due`` (cancelled, their workers restarted); at least one. Waits in steps
    of ``poll`` seconds, calling ``check()`` between them (it raises to stop:
    `sweep_signals`)."""
    while True:
        check()
        batch = done.next_batch(block=False)
        if batch:
            return [(f, None) for f in batch]
        now = time.monotonic()
        late = [f for f, at in due.items() if now > at and not f.done()]
        if late:
            return [(f, _abandon(client, f, say)) for f in late]
        time.sleep(poll)


def _abandon(client, fut, say) -> TaskOverdue:
    """Cancel ``fut`` and restart the worker process running it (it froze: module docstring)."""
    where = [w for w, keys in client.processing().items() if fut.key in keys]
    client.cancel(fut)
    why = "its worker froze (no reply by its deadline: an engine holding the interpreter lock?)"
    if where:
        try:
            client.restart_workers(where, timeout=60)
            why += "; the worker process was restarted"
        except Exception as exc:   # noqa: BLE001 - a worker with no nanny: said, not hidden
            why += f"; its worker could not be restarted ({one_line(exc)})"
    say(f"sweep: task {fut.key} {why}")
    return TaskOverdue(why)
