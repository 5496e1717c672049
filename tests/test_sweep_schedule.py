"""The sweep's scheduling on Dask (comparisons/stages/sweep_schedule.py) in process, against a
fake client: no cluster, no worker, no real time.

The contract is the module's docstring and docs/sweep.md ("Resuming, failures, determinism"):
at most two tasks per worker in flight and a few futures held, not one per chunk; a lost task's
bicycles run again one at a time, alone, after every other task, the one lost again a "failed"
row (``task lost when run alone: ...``), one line for each; a task past its deadline (twice its
bicycles' limits, plus 30 s of grace) cancelled and its worker restarted through its nanny.

`FakeClient` stands for Dask's client with its documented behaviour (``scheduler_info`` lists
at most 5 workers unless asked for all with ``n_workers=-1``, ``restart_workers`` takes a list
of worker addresses, ``as_completed.next_batch(block=False)`` returns the finished futures
without waiting, a cancelled future counts as finished); a task's outcome is chosen by its
bicycles (one that kills its worker, one that freezes it). Time is a fake clock advanced by
the module's own sleeps, so a deadline is checked to the poll. The task itself is a stand-in
returning one row per bicycle with the limit it was given. Each test names the planted bugs
(mutmut's survivors of the module's first measurement) it fails on. The file takes ~0.1 s
after the reference model's import.
"""

from __future__ import annotations

import math
import sys
import types
import weakref

import pytest

from comparisons.stages import sweep_schedule as sched
from comparisons.stages.sweep_schedule import GRACE, PER_WORKER, POLL, TaskOverdue, compute, deadline
from comparisons.stages.sweep_spec import make_spec, spec_hash
from reference_model import load_model

FROZE = "its worker froze (no reply by its deadline: an engine holding the interpreter lock?)"


class KilledWorker(Exception):
    """Dask's error for a task whose worker died (its name is what the sweep's lines show)."""


class Clock:
    """Monotonic time that only the module's sleeps advance; a wait of more than ``limit``
    simulated seconds is a hang."""

    def __init__(self, start: float = 1000.0, limit: float = 2000.0):
        self.t, self.start, self.limit = start, start, limit
        self.sleeps: list[float] = []

    def monotonic(self) -> float:
        return self.t

    def sleep(self, dt: float) -> None:
        self.sleeps.append(dt)
        self.t += dt
        if self.t - self.start > self.limit:
            raise RuntimeError("the scheduler waits forever")


class FakeFuture:
    def __init__(self, key: str, outcome, frozen: bool):
        self.key = key
        self.status = "pending" if frozen else ("error" if isinstance(outcome, BaseException)
                                                else "finished")
        self._outcome = outcome
        self.released = False

    def done(self) -> bool:
        return self.status != "pending"

    def result(self):
        if self.status == "cancelled":
            raise RuntimeError(f"{self.key} cancelled")
        if self.status == "pending":
            raise AssertionError("result() of a task still running would block")
        if isinstance(self._outcome, BaseException):
            raise self._outcome
        return self._outcome

    def release(self) -> None:
        self.released = True


class FakeAsCompleted:
    """Dask's ``as_completed``: futures added, handed back once each when finished."""

    def __init__(self):
        self.futures: list[FakeFuture] = []

    def add(self, f: FakeFuture) -> None:
        self.futures.append(f)

    def next_batch(self, block: bool = True) -> list:
        batch = [f for f in self.futures if f.done()]
        if block and not batch:
            raise AssertionError("next_batch(block=True) waits until a task ends: a frozen "
                                 "worker's never does")
        self.futures = [f for f in self.futures if not f.done()]
        return batch


class FakeClient:
    """A client of ``workers`` workers; a task holding a bicycle of ``kills`` raises
    KilledWorker, one holding a bicycle of ``freezes`` never ends."""

    def __init__(self, clock: Clock | None = None, workers: int = 1, kills=(), freezes=(),
                 restart_error: Exception | None = None):
        self.clock = clock or Clock()
        self.workers = [f"tcp://w{i}" for i in range(workers)]
        self.kills, self.freezes, self.restart_error = set(kills), set(freezes), restart_error
        self.live: weakref.WeakSet = weakref.WeakSet()
        self.submitted: list[dict] = []       # key, bicycles, time, tasks in flight
        self.cancelled: list[tuple[str, float]] = []
        self.restarts: list[tuple[list, object]] = []

    def scheduler_info(self, n_workers: int = 5) -> dict:
        shown = self.workers if n_workers == -1 else self.workers[:n_workers]
        return {"workers": {w: {} for w in shown}}

    def submit(self, fn, *args, key=None, pure=True):
        spec, bicycles, limit = args
        assert key is not None, "a sweep task without its name"
        in_flight = 1 + sum(not f.released for f in self.live)      # this one included
        self.submitted.append({"key": key, "bicycles": tuple(bicycles), "at": self.clock.t,
                               "in_flight": in_flight})
        if self.freezes & set(bicycles):
            f = FakeFuture(key, None, frozen=True)
        elif self.kills & set(bicycles):
            f = FakeFuture(key, KilledWorker(f"worker {self.workers[0]} died"), frozen=False)
        else:
            f = FakeFuture(key, fn(spec, bicycles, limit), frozen=False)
        self.live.add(f)
        return f

    def processing(self) -> dict:
        return {w: [f.key for f in self.live if not f.done()] if i == 0 else []
                for i, w in enumerate(self.workers)}

    def cancel(self, f: FakeFuture) -> None:
        f.status = "cancelled"
        self.cancelled.append((f.key, self.clock.t))

    def restart_workers(self, workers, timeout=None, raise_for_error=True):
        if not isinstance(workers, list) or not set(workers) <= set(self.workers):
            raise ValueError(f"not workers of this cluster: {workers!r}")
        self.restarts.append((workers, timeout))
        if self.restart_error is not None:
            raise self.restart_error


def rows_task(spec, bicycles, limit):
    """The stand-in task: one row per bicycle, with the limit it was given."""
    return [{"bicycle": k, "status": "agree", "limit": limit} for k in bicycles]


@pytest.fixture(scope="module")
def spec():
    """Six bicycles: rider mass m3 = 80, 84, ..., 100 kg (the grid's points by definition)."""
    return make_spec(load_model("benchmark").params, varies=["m3=80:100:6"],
                     engines=("pinocchio",), checks=("eigen",))


@pytest.fixture
def clock(monkeypatch):
    c = Clock()
    monkeypatch.setattr(sched, "time", c)
    return c


@pytest.fixture(autouse=True)
def fake_dask(monkeypatch):
    fake = types.ModuleType("distributed")
    fake.as_completed = FakeAsCompleted
    monkeypatch.setitem(sys.modules, "distributed", fake)


def _run(client, spec, todo, limit=3.0, **kw):
    """compute() with every callback recorded: (lost, chunks, bicycle counts, lines)."""
    chunks, counts, lines = {}, [], []

    def on_chunk(i, rows):
        assert i not in chunks, f"chunk {i} reported twice"
        chunks[i] = sorted(rows, key=lambda r: r["bicycle"])

    lost = compute(client, spec, todo, limit, on_chunk, counts.append, task=rows_task,
                   say=lines.append, **kw)
    return lost, chunks, counts, lines


# --- the deadline ---------------------------------------------------------------------------------

def test_a_tasks_deadline_is_its_bicycles_limits_behind_the_tasks_ahead_plus_grace():
    """docs/sweep.md: a task's deadline is twice its bicycles' limits plus 30 s (two tasks per
    worker: one running, one waiting behind it); `deadline` counts ``depth`` tasks of
    ``n_bicycles`` bicycles at ``limit`` each, plus ``grace``. Planted: grace subtracted,
    the limit divided instead of multiplied, the depth divided by the bicycles."""
    assert GRACE == 30.0 and PER_WORKER == 2
    assert deadline(3, 2.0, PER_WORKER) == 2 * (3 * 2.0) + 30.0
    assert deadline(1, 5.0, 1, grace=3.0) == 8.0
    assert deadline(4, 0.5, 3, grace=0.0) == 6.0


# --- the window -----------------------------------------------------------------------------------

@pytest.mark.parametrize("workers, window", [(1, 2), (3, 6), (7, 14), (0, 2)])
def test_at_most_two_tasks_per_worker_are_in_flight(spec, workers, window):
    """docs/sweep.md: at most two tasks per worker in flight, every worker of the cluster
    counted (Dask describes 5 unless asked for all), a cluster reporting none counted as
    one; each chunk reported once with all its rows (the limit given reached the task), the
    progress told the rows of each task as they arrive. Planted: the window divided by the
    workers, at least two workers counted, one task more than the window, the limit not
    passed to the task, the progress told None."""
    client = FakeClient(workers=workers)
    todo = [(i, range(i, i + 1)) for i in range(20)]
    lost, chunks, counts, lines = _run(client, spec, todo, limit=7.5)
    assert max(s["in_flight"] for s in client.submitted) == window
    assert lost == 0 and lines == [] and counts == [1] * 20
    assert sorted(chunks) == list(range(20))
    assert all(chunks[i] == [{"bicycle": i, "status": "agree", "limit": 7.5}] for i in chunks)


def test_a_large_sweep_holds_a_few_futures_not_one_per_chunk(spec):
    """docs/sweep.md: "a large sweep keeps a few futures, not one per chunk": while the last of
    40 chunks is reported, at most the window's futures are still alive (weak references to
    the fake's futures). Planted: the finished future's deadline never forgotten (every
    future kept alive in the deadlines' table)."""
    client = FakeClient(workers=1)
    alive = []
    todo = [(i, range(i, i + 1)) for i in range(40)]
    compute(client, spec, todo, 1.0, lambda i, rows: alive.append(len(client.live)),
            task=rows_task)
    assert len(alive) == 40 and max(alive) <= PER_WORKER


def test_the_tasks_are_named_after_the_sweep_and_the_chunk(spec):
    """Each task's Dask key names the sweep (its spec hash) and the chunk (six digits, as the
    chunk files), a lone task also its bicycle: ``sweep-<hash>-000002`` and
    ``sweep-<hash>-000002-5-alone`` (distinct keys: Dask would hand back the running future
    of a key already submitted). Planted: the hash not computed (None), a suffix on every
    chunk's key, no key given (Dask's own random name)."""
    client = FakeClient(workers=1, kills={5})
    _run(client, spec, [(1, range(0, 4)), (2, range(4, 6))])
    h = spec_hash(spec)
    assert [s["key"] for s in client.submitted] == [
        f"sweep-{h}-000001", f"sweep-{h}-000002", f"sweep-{h}-000002-4-alone",
        f"sweep-{h}-000002-5-alone"]


# --- lost tasks -----------------------------------------------------------------------------------

def test_a_lost_task_is_narrowed_down_to_the_bicycle_that_loses_it(spec):
    """Bicycles 1, 3 and 5 kill their worker (KilledWorker). Chunks (0, 1, 2), (3,) and (4, 5)
    are lost; each of their bicycles runs again alone, with nothing else in flight, after
    every chunk task; those that lose their task again are "failed" rows ("task lost when run
    alone: KilledWorker: ...", the grid's m3 kept), the others keep their results; one line
    per lost task, the bicycles counted in words ("1 bicycle", "2 bicycles"); six tasks
    lost. Planted: either line dropped or altered (the error's type as NoneType, the plural
    always, never, or from one or from three bicycles on), the progress told None."""
    client = FakeClient(workers=1, kills={1, 3, 5})
    lost, chunks, counts, lines = _run(client, spec, [(0, range(0, 3)), (1, range(3, 4)),
                                                      (2, range(4, 6))])
    assert lost == 6
    again = "one at a time, alone, to find the one that loses it"
    assert lines == [
        f"sweep: a task of chunk 0 was lost (KilledWorker); its 3 bicycles run again {again}",
        f"sweep: a task of chunk 1 was lost (KilledWorker); its 1 bicycle run again {again}",
        f"sweep: a task of chunk 2 was lost (KilledWorker); its 2 bicycles run again {again}",
        "sweep: bicycle 1 loses its task even alone (KilledWorker): a failed row",
        "sweep: bicycle 3 loses its task even alone (KilledWorker): a failed row",
        "sweep: bicycle 5 loses its task even alone (KilledWorker): a failed row",
    ]
    alone = [s for s in client.submitted if s["key"].endswith("-alone")]
    assert [s["bicycles"] for s in client.submitted[:3]] == [(0, 1, 2), (3,), (4, 5)]
    assert [s["bicycles"] for s in alone] == [(k,) for k in range(6)]
    assert all(s["in_flight"] == 1 for s in alone)
    assert counts == [1] * 6
    rows = [r for i in sorted(chunks) for r in chunks[i]]
    assert [r["bicycle"] for r in rows] == list(range(6))
    for r in rows:
        if r["bicycle"] % 2 == 0:
            assert r == {"bicycle": r["bicycle"], "status": "agree", "limit": 3.0}
        else:
            assert r["status"] == "failed" and math.isnan(r["task_seconds"])
            assert r["failures"] == "task lost when run alone: KilledWorker: worker tcp://w0 died"
            assert r["vary.m3"] == 80.0 + 4.0 * r["bicycle"]


def test_a_frozen_worker_is_given_up_at_its_deadline_and_restarted(spec, clock):
    """Bicycle 1 freezes its worker (its task never ends). Chunk (0, 1), limit 3 s, grace 7 s,
    is given up once past 2 x 2 x 3 + 7 = 19 s (within one poll, 50 ms), cancelled, its
    worker restarted and the chunk narrowed down; bicycle 0 alone completes (in the same
    batch as the cancelled future, handed back by Dask once more) and bicycle 1 alone is given
    up past 1 x 1 x 3 + 7 = 10 s, a failed row naming the freeze; chunk (2,) completes at
    once. Planted: any argument of the deadline dropped or swapped (grace left at 30 s, the
    bicycles' count, the limit, the depth), the lone task's depth 2 or the chunks' 1, a
    task never seen as late (late None, or only the finished ones), the frozen task's
    client, future or line not handed to its abandonment, the batch abandoned at the
    cancelled future (break for continue), next_batch waiting for a task to end."""
    client = FakeClient(clock, workers=1, freezes={1})
    lost, chunks, counts, lines = _run(client, spec, [(0, range(0, 2)), (1, range(2, 3))],
                                       limit=3.0, grace=7.0)
    h = spec_hash(spec)
    restarted = f"{FROZE}; the worker process was restarted"
    assert lost == 2
    assert lines == [
        f"sweep: task sweep-{h}-000000 {restarted}",
        "sweep: a task of chunk 0 was lost (TaskOverdue); its 2 bicycles run again one at a "
        "time, alone, to find the one that loses it",
        f"sweep: task sweep-{h}-000000-1-alone {restarted}",
        "sweep: bicycle 1 loses its task even alone (TaskOverdue): a failed row",
    ]
    at = {s["key"]: s["at"] for s in client.submitted}
    assert [k for k, _ in client.cancelled] == [f"sweep-{h}-000000", f"sweep-{h}-000000-1-alone"]
    for (key, when), limit in zip(client.cancelled, (19.0, 10.0)):
        assert limit < when - at[key] <= limit + POLL + 1e-9, key
    assert client.restarts[0][0] == ["tcp://w0"] and len(client.restarts) == 2
    assert set(clock.sleeps) == {POLL}
    assert chunks[1] == [{"bicycle": 2, "status": "agree", "limit": 3.0}]
    assert chunks[0][0] == {"bicycle": 0, "status": "agree", "limit": 3.0}
    assert chunks[0][1]["failures"] == f"task lost when run alone: TaskOverdue: {restarted}"
    assert counts == [1, 1, 1]


def test_a_task_is_late_only_once_strictly_past_its_deadline(clock):
    """`_finished` looks every ``poll`` seconds, calling ``check`` each time; a task due at
    t = 1 s is not late at t = 1 s exactly ("past their deadline"), only at the next look
    (1.25 s), and comes back with its `TaskOverdue`; a finished one comes back with None.
    Planted: late at the deadline itself (>=)."""
    clock.t = clock.start = 0.0
    client = FakeClient(clock, workers=1, freezes={0})
    f = client.submit(rows_task, None, (0,), 1.0, key="sweep-x-000000")
    done, checks, lines = FakeAsCompleted(), [], []
    done.add(f)
    got = sched._finished(done, lambda: checks.append(clock.t), {f: 1.0}, client, lines.append,
                          poll=0.25)
    assert clock.t == 1.25 and checks == [0.0, 0.25, 0.5, 0.75, 1.0, 1.25]
    assert [(g, type(o)) for g, o in got] == [(f, TaskOverdue)]
    ok = client.submit(rows_task, None, (1,), 1.0, key="sweep-x-000001")
    done = FakeAsCompleted()
    done.add(ok)
    assert sched._finished(done, lambda: None, {ok: 0.0}, client, lines.append) == [(ok, None)]


# --- giving a frozen task up ------------------------------------------------------------------

def test_a_frozen_task_is_cancelled_and_its_worker_alone_restarted(clock):
    """`_abandon`: the future is cancelled, the worker processing its key (and only that one)
    restarted with a bounded wait (a number of seconds, at least the 10 s a worker process
    takes to start: the module's GRACE note, at most a few minutes); the line and the
    `TaskOverdue` say so. Planted: the workers not processing it restarted, no worker list or
    None given, no timeout or None (Dask's default or forever), the cancel of None, the
    reason None or altered, replaced instead of extended, the line dropped, the overdue
    error without its reason."""
    client = FakeClient(clock, workers=3, freezes={0})
    f = client.submit(rows_task, None, (0,), 1.0, key="sweep-x-000004")
    client.processing = lambda: {"tcp://w0": ["sweep-x-000001"], "tcp://w1": [f.key, "b"],
                                 "tcp://w2": []}
    lines = []
    overdue = sched._abandon(client, f, lines.append)
    why = f"{FROZE}; the worker process was restarted"
    assert isinstance(overdue, TaskOverdue) and str(overdue) == why
    assert lines == [f"sweep: task sweep-x-000004 {why}"]
    assert client.cancelled == [(f.key, clock.t)] and f.status == "cancelled"
    (workers, timeout), = client.restarts
    assert workers == ["tcp://w1"]
    assert isinstance(timeout, (int, float)) and 10 <= timeout <= 300


def test_a_worker_that_cannot_be_restarted_is_said_not_hidden(clock):
    """A worker without a nanny cannot be restarted: the reason says so with Dask's error on
    one line; a task no worker is processing is cancelled with no restart. Planted: the
    reason replaced by the failure alone, the error shown as None."""
    client = FakeClient(clock, workers=1, freezes={0},
                        restart_error=RuntimeError("worker tcp://w0\n  has no nanny"))
    f = client.submit(rows_task, None, (0,), 1.0, key="sweep-x-000000")
    lines = []
    overdue = sched._abandon(client, f, lines.append)
    why = f"{FROZE}; its worker could not be restarted (RuntimeError: worker tcp://w0 has no nanny)"
    assert str(overdue) == why and lines == [f"sweep: task sweep-x-000000 {why}"]
    client = FakeClient(clock, workers=1, freezes={0})
    f = client.submit(rows_task, None, (0,), 1.0, key="sweep-x-000000")
    client.processing = lambda: {"tcp://w0": []}
    lines = []
    assert str(sched._abandon(client, f, lines.append)) == FROZE
    assert client.restarts == [] and lines == [f"sweep: task sweep-x-000000 {FROZE}"]
