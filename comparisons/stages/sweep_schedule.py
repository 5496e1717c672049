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

__all__ = ["PER_WORKER", "Work", "compute"]

PER_WORKER = 2      # tasks in flight per worker: one running, one ready behind it
POLL = 0.05         # s between two looks at the finished futures (a task takes ~3 s)


@dataclass(frozen=True)
class Work:
    """One task: bicycles of chunk ``chunk``; ``alone``: run with nothing else in flight."""

    chunk: int
    bicycles: tuple[int, ...]
    alone: bool = False


def compute(client, spec: SweepSpec, todo, limit: float, on_chunk, on_bicycles=None,
            task=limited_chunk_rows, check=lambda: None, say=lambda line: None) -> int:
    """Every chunk of ``todo`` (pairs of chunk number and bicycles) computed on ``client``
    (module docstring); returns how many tasks were lost. ``task``: the Dask task,
    ``task(spec, bicycles, limit) -> rows``; ``check``: called while waiting, raises to stop
    (`sweep_signals.StopRequest.check`); ``say``: one line for the user per lost task."""
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
    done = as_completed()
    lost = 0

    def submit(w: Work) -> None:
        suffix = f"-{w.bicycles[0]}-alone" if w.alone else ""
        f = client.submit(task, spec, w.bicycles, limit, pure=False,
                          key=f"sweep-{h}-{w.chunk:06d}{suffix}")
        flight[f] = w
        done.add(f)

    refill()
    while pending or alone or flight:
        while pending and len(flight) < window:
            submit(pending.popleft())
            refill()
        if not flight:                         # every other task finished: one suspect alone
            submit(alone.popleft())
        for fut in _finished(done, check):
            w = flight.pop(fut)
            try:
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


def _finished(done, check, poll: float = POLL):
    """The futures finished so far (at least one), waiting in steps of ``poll`` seconds and
    calling ``check()`` between them (it raises to stop: `sweep_signals`)."""
    while True:
        check()
        batch = done.next_batch(block=False)
        if batch:
            return batch
        time.sleep(poll)
