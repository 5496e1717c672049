"""The sweep's driver (comparisons/stages/sweep.py) in process: every function against the module
docstring and docs/sweep.md, with no Dask cluster and no worker.

The contract: the layout of ``out_dir`` (``spec.json`` with the hash, the chunk size and the
spec; ``chunks/<hash>/chunk-000000.parquet``; ``results.parquet`` or ``.csv``, sorted by
bicycle); chunks of consecutive bicycles sized from the development machine's cost table
(docs/sweep.md's example: 10^7 bicycles at 0.11 s are 370371 chunks of 27, chunk 2 holding
bicycles 54-80); the estimate line before the first task; a missing chunk computed again, a
foreign one named on one line ("... is not chunk 0 of this sweep (...); computing it again");
a rerun computing nothing; the local cluster's workers single-threaded, one BLAS thread each,
started with Ctrl-C and SIGTERM ignored and Dask's ``allowed-failures`` 0; at an interrupt the
local workers killed and the finished chunks kept.

Stand-ins: ``compute`` (`sweep_schedule`, tested in tests/test_sweep_schedule.py) is replaced
by `FakeCompute`, which hands each chunk's rows to the sweep's callback synchronously; the
rows are hand-made (`_row`), except in one test that runs the real task on two bicycles.
Dask's ``Client``/``LocalCluster`` are fakes recording what they were given (a fake
``distributed`` module), the worker processes fake nannies with pids (``os.kill`` recorded),
the sweep's clock a fake advanced only by the fake compute. Each test names the bugs planted
in a copy of the module that it was seen failing on. The file takes about a second.
"""

from __future__ import annotations

import json
import logging
import math
import os
import shutil
import signal
import sys
import threading
import types
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace

import dask
import numpy as np
import pandas as pd
import pytest

from comparisons.stages import sweep
from comparisons.stages import sweep_deadline
from comparisons.stages.signals import Terminated
from comparisons.stages.sweep import (SweepResult, believed_chunks, bicycle_cost, chunk_name,
                                      chunk_path, chunk_size, merge, plan, rows_frame,
                                      run_sweep, stamp_of)
from comparisons.stages.sweep_budget import Estimate
from comparisons.stages.sweep_chunks import ChunkStamp, read_chunk, read_table, write_chunk
from comparisons.stages.sweep_signals import StopRequest
from comparisons.stages.sweep_spec import make_spec, spec_hash
from comparisons.stages.sweep_task import chunk_rows, columns
from reference_model import load_model

FAILURES_KEY = "distributed.scheduler.allowed-failures"
NAN, INF = math.nan, math.inf
#: each hand-made bicycle's measured seconds: a NaN (a lost task's row) and an inf among them,
#: neither of which is a measurement
SECONDS = {0: 30.0, 1: NAN, 2: 0.25, 3: INF, 4: 60.0}


@pytest.fixture(scope="module")
def spec():
    """Five bicycles, rider mass m3 = 80, 85, ..., 100 kg, their weave and capsize speeds
    (eigen: 0.06 s a bicycle in the cost table, chunks of int(3 / 0.06) = 50)."""
    return make_spec(load_model("benchmark").params, varies=["m3=80:100:5"],
                     engines=("reference",), checks=("eigen",))


@pytest.fixture
def two_per_chunk(monkeypatch):
    """TARGET_SECONDS 0.13: int(0.13 / 0.06) = 2 bicycles a chunk, the five in chunks
    (0, 1), (2, 3), (4,)."""
    monkeypatch.setattr(sweep, "TARGET_SECONDS", 0.13)


def _row(k: int) -> dict:
    """A hand-made row of bicycle k (the columns not given are missing)."""
    return {"bicycle": k, "seed": 2**63 + k, "status": "agree" if k != 3 else "failed",
            "failures": "" if k != 3 else "eigen: boom", "vary.m3": 80.0 + 5.0 * k,
            "weave_speed": 4.0 + k / 10, "task_seconds": SECONDS[k]}


def _cost_spec(checks, engines=("reference",), n_states=8, n_bicycles=1):
    """What `bicycle_cost`, `chunk_size` and `plan` read of a spec."""
    return SimpleNamespace(checks=tuple(checks), engines=tuple(engines), n_states=n_states,
                           n_bicycles=n_bicycles)


# --- fakes ----------------------------------------------------------------------------------------

class FakeClient:
    """A Dask client of ``workers`` workers: ``scheduler_info`` lists ``n_workers`` of them,
    all for -1 (Dask's documented argument); ``close`` is logged."""

    def __init__(self, workers: int = 7, log=None, on_close=None):
        self.workers = [f"tcp://w{i}" for i in range(workers)]
        self.log = [] if log is None else log
        self.on_close = on_close

    def scheduler_info(self, n_workers: int = 5) -> dict:
        shown = self.workers if n_workers == -1 else self.workers[:n_workers]
        return {"workers": {w: {} for w in shown}}

    def close(self) -> None:
        self.log.append("client.close")
        if self.on_close:
            self.on_close()


def _nanny(pid):
    """A local cluster's nanny: its worker process's pid (None: not started)."""
    return SimpleNamespace(process=SimpleNamespace(process=SimpleNamespace(pid=pid)),
                           auto_restart=True)


class FakeCluster:
    def __init__(self, log, pids=(101, 102)):
        self.log = log
        self.workers = {f"w{i}": _nanny(p) for i, p in enumerate(pids)}

    def close(self) -> None:
        self.log.append("cluster.close")


class FakeCompute:
    """`sweep_schedule.compute` on this side, synchronous: one line said, the clock advanced
    ``seconds``, then each chunk of ``todo`` (reversed when ``order`` says so: the last
    finishing first) handed to the sweep's callback with its rows (`_row`, or those of the
    task it is given when ``real_task``) and the progress told its bicycles; ``raises``
    raised before the second chunk; after ``stop_after`` chunks, ``stop_after_hook()`` (a
    signal arriving) then the sweep's ``check``. Returns ``failed`` lost tasks."""

    def __init__(self, lines=None, clock=None, seconds=4.0, failed=0, order=None,
                 real_task=False, raises=None, stop_after=None):
        self.calls: list[dict] = []
        self.lines, self.clock, self.seconds, self.failed = lines, clock, seconds, failed
        self.order, self.real_task, self.raises = order, real_task, raises
        self.stop_after, self.stop_after_hook = stop_after, None

    def __call__(self, client, spec, todo, limit, on_chunk, on_bicycles=None, *, task, check,
                 say):
        self.calls.append(dict(client=client, spec=spec, todo=list(todo), limit=limit, task=task,
                               check=check, said_before=list(self.lines or [])))
        say("sweep: a line from the scheduler")
        if self.clock is not None:
            self.clock.t += self.seconds
        work = list(todo)
        if self.order == "reversed":
            work.reverse()
        for n, (i, c) in enumerate(work):
            if self.raises is not None and n == 1:
                raise self.raises
            rows = task(spec, tuple(c), limit) if self.real_task else [_row(k) for k in c]
            on_chunk(i, rows)
            on_bicycles(len(c))
            if self.stop_after is not None and n + 1 == self.stop_after:
                self.stop_after_hook()
                check()
        return self.failed


class Clock:
    """The sweep's ``time``: ``perf_counter`` stands still unless the fake compute moves it."""

    def __init__(self):
        self.t = 1000.0

    def perf_counter(self) -> float:
        return self.t


@pytest.fixture
def clock(monkeypatch):
    c = Clock()
    monkeypatch.setattr(sweep, "time", c)
    return c


@pytest.fixture
def lines():
    return []


@pytest.fixture
def fake_compute(monkeypatch, clock, lines):
    fake = FakeCompute(lines=lines, clock=clock, failed=2, order="reversed")
    monkeypatch.setattr(sweep, "compute", fake)
    return fake


@pytest.fixture
def stop(monkeypatch):
    """The sweep's `StopRequest`, held by the test (`deferred_signals` replaced)."""
    request = StopRequest()

    @contextmanager
    def deferred():
        yield request
    monkeypatch.setattr(sweep, "deferred_signals", deferred)
    return request


@pytest.fixture
def kills(monkeypatch):
    """``os.kill`` recorded; pid 404 is a process already gone."""
    sent = []

    def kill(pid, sig):
        sent.append((pid, sig))
        if pid == 404:
            raise ProcessLookupError(pid)
    monkeypatch.setattr(sweep.os, "kill", kill)
    return sent


@pytest.fixture
def own_cluster(monkeypatch):
    """`_client` replaced: a fake client of 2 workers and a cluster of worker pids 101 and
    102, both logging; the arguments it was called with in ``calls``."""
    log, calls = [], []
    made = SimpleNamespace(log=log, calls=calls, client=FakeClient(2, log),
                           cluster=FakeCluster(log))

    def client(scheduler, workers, processes):
        calls.append((scheduler, workers, processes))
        if getattr(made, "on_start", None):
            made.on_start()
        return made.client, made.cluster
    monkeypatch.setattr(sweep, "_client", client)
    return made


def _sweep(spec, out, lines, **kw):
    kw.setdefault("client", FakeClient())
    return run_sweep(spec, out, progress=False, notify=lines.append, **kw)


# --- the cost, the chunks, the names --------------------------------------------------------------

def test_a_bicycles_cost_adds_the_cost_tables_rows_for_its_checks():
    """The development table (module docstring, benchmarks/sweep_timings.py): terms 0.01 s
    plus 0.02 s per engine at 8 states (in proportion to the states), eigen 0.06 s, runs 12 s
    for each three of the reference and the engines (4 runs each); a bicycle sums the rows of
    its checks. Planted: the states not divided by 8 (multiplied), the engines not counted, the
    eigen row added for terms only, the runs' reference not counted (1 - engines), the runs
    divided by 2, the table's eigen value 0.07."""
    assert bicycle_cost(_cost_spec(("terms",))) == pytest.approx(0.01 + 0.02)
    assert bicycle_cost(_cost_spec(("terms",), ("a", "b", "c"), 4)) == pytest.approx(
        0.01 + 3 * 0.02 * 4 / 8)
    assert bicycle_cost(_cost_spec(("eigen",))) == pytest.approx(0.06)
    assert bicycle_cost(_cost_spec(("eigen", "runs"), ("a", "b"))) == pytest.approx(
        0.06 + 12.0 * 3 / 3)
    assert bicycle_cost(_cost_spec(("runs",), ("a",))) == pytest.approx(12.0 * 2 / 3)
    assert bicycle_cost(_cost_spec(("terms", "eigen", "runs"), ("a",), 16)) == pytest.approx(
        0.01 + 0.02 * 2 + 0.06 + 8.0)
    assert bicycle_cost(_cost_spec(())) == 0.0


def test_the_docs_example_ten_million_bicycles_are_370371_chunks_of_27():
    """docs/sweep.md's estimate line: 10000000 bicycles of terms and eigen (two engines, the
    default 8 states) "in 370371 chunks ... at 0.11 s a bicycle", and its notice "(it holds
    bicycles 54-80, not 0-26)": chunks of 27 (about 3 s each), consecutive ranges (a plan of
    ranges stays small), the last one the bicycles left over. The plan is cut here for the
    cap's 100,000 bicycles (27 x 3703 = 99981: 3704 chunks, the last of 19) to stay fast.
    Planted: TARGET_SECONDS 4, the plan's step one more or one less than the chunk size, a
    chunk's end past the sweep (min with n + 1) or short of it (n - 1), the first chunk from
    1, the engines not counted."""
    big = _cost_spec(("terms", "eigen"), ("pinocchio", "exudyn"), 8, 10_000_000)
    assert bicycle_cost(big) == pytest.approx(0.11)
    assert chunk_size(big) == 27 and -(-10_000_000 // chunk_size(big)) == 370371
    big.n_bicycles = 100_000
    chunks = plan(big)
    assert len(chunks) == 3704
    assert chunks[0] == range(0, 27) and chunks[2] == range(54, 81)
    assert chunks[-1] == range(99_981, 100_000)
    assert all(type(c) is range for c in chunks)
    assert all(a.stop == b.start for a, b in zip(chunks, chunks[1:]))


@pytest.mark.parametrize("checks, engines, n_states, size", [
    (("eigen",), ("a",), 8, 50),                 # 3 / 0.06
    (("eigen", "runs"), ("a", "b"), 8, 1),       # 3 / 12.06 < 1: at least one bicycle
    (("terms",), ("a",), 1, 200),                # 3 / 0.0125 = 240: at most 200
    ((), ("a",), 8, 200),                        # no cost at all: still at most 200
])
def test_a_chunk_holds_at_least_one_and_at_most_200_bicycles(checks, engines, n_states, size):
    """A chunk takes about TARGET_SECONDS (3 s) at the table's cost, at least one bicycle, at
    most MAX_CHUNK = 200 (the cut is part of what the hash fixes: a changed cap would re-cut
    every sweep's chunks). Planted: the floor 0 or 2, the cap 201 or the cap ignored (max for
    min), a zero cost dividing by zero (the 1e-6 floor dropped)."""
    assert sweep.MAX_CHUNK == 200
    assert chunk_size(_cost_spec(checks, engines, n_states)) == size


@pytest.mark.parametrize("n, expected", [
    (120, [range(0, 50), range(50, 100), range(100, 120)]),
    (100, [range(0, 50), range(50, 100)]),
    (1, [range(0, 1)]),
    (0, []),
])
def test_the_plan_is_consecutive_chunks_covering_every_bicycle_once(n, expected):
    """Chunks of 50 (eigen) cover 0..n-1 in order, the last one short. Planted: the last
    chunk's end n + 1 or n - 1, the step size - 1, the start 1."""
    assert plan(_cost_spec(("eigen",), n_bicycles=n)) == expected


def test_chunk_files_are_named_by_their_six_digit_index_under_the_hash():
    """The layout: ``chunks/<hash>/chunk-000000.parquet`` (``.csv`` for the CSV writer), the
    index in six digits; a chunk's stamp is its hash and its bicycles start:stop (stop one past
    the last). Planted: five digits, the writer's suffix ignored, "chunk" as the folder, the
    stamp's stop the last bicycle, its start the second."""
    assert chunk_name(0) == "chunk-000000.parquet"
    assert chunk_name(12, "csv") == "chunk-000012.csv"
    assert chunk_path(Path("out"), "abc", 3) == Path("out/chunks/abc/chunk-000003.parquet")
    assert chunk_path("out", "abc", 1234567, "csv") == Path("out/chunks/abc/chunk-1234567.csv")
    assert stamp_of("abc", range(54, 81)) == ChunkStamp("abc", 54, 81)
    assert stamp_of("abc", (4,)) == ChunkStamp("abc", 4, 5)


def test_a_new_result_has_done_nothing_yet():
    """A `SweepResult` starts with nothing computed, skipped or failed, no results file and an
    empty timings table of its own. Planted: computed or failed_tasks starting at 1, the
    timings None."""
    a, b = SweepResult(Path("o"), "h", 5, 3), SweepResult(Path("o"), "h", 5, 3)
    assert (a.computed, a.skipped, a.failed_tasks, a.seconds, a.results) == (0, 0, 0, 0.0, None)
    a.timings["x"] = 1
    assert b.timings == {}


# --- rows_frame and merge -------------------------------------------------------------------------

def test_a_rows_frame_has_fixed_dtypes_sorted_by_bicycle():
    """`rows_frame`'s docstring: fixed columns and dtypes, sorted by bicycle, a fresh index:
    bicycle int64, seed uint64 (seeds use all 64 bits), the two flags nullable booleans, text
    columns (status, failures, localization, entry.*, run.*) str with "" for missing, every
    other column float64 (NaN for missing), whatever the rows held. Planted: seed int64 (or
    bicycle uint64), a flag float, status, localization, entry.* or run.* dropped from the
    text list (its "" missing as NaN, or its text refused as a float), "" filled as "nan",
    sorted by seed or descending, the old index kept as a column, the given columns replaced
    by the spec's."""
    cols = ["bicycle", "seed", "status", "failures", "vary.m3", "entry.E.mass_matrix",
            "max_error", "terms_passed", "localization", "run.weave.0.9.reference",
            "runs_confirmed", "task_seconds"]
    rows = [{"bicycle": 2, "seed": 2**64 - 1, "status": "failed", "failures": "E: boom",
             "vary.m3": 90, "terms_passed": False, "run.weave.0.9.reference": "confirmed",
             "runs_confirmed": True},
            {"bicycle": 0, "seed": 5, "status": "agree", "entry.E.mass_matrix": "M[x, y] @ state 0",
             "max_error": 1e-16, "localization": "trail", "terms_passed": True,
             "task_seconds": 0.5},
            {"bicycle": 1, "seed": 3, "status": "agree", "vary.m3": 85.5}]
    frame = rows_frame(None, rows, cols)
    assert list(frame.columns) == cols
    assert list(frame.index) == [0, 1, 2]
    assert frame["bicycle"].tolist() == [0, 1, 2] and frame["bicycle"].dtype == np.int64
    assert frame["seed"].dtype == np.uint64 and frame["seed"].tolist() == [5, 3, 2**64 - 1]
    for c in ("terms_passed", "runs_confirmed"):
        assert str(frame[c].dtype) == "boolean"
    assert frame["terms_passed"].tolist() == [True, pd.NA, False]
    assert frame["runs_confirmed"].tolist() == [pd.NA, pd.NA, True]
    text = {"status": ["agree", "agree", "failed"], "failures": ["", "", "E: boom"],
            "localization": ["trail", "", ""],
            "entry.E.mass_matrix": ["M[x, y] @ state 0", "", ""],
            "run.weave.0.9.reference": ["", "", "confirmed"]}
    for c, values in text.items():
        assert frame[c].tolist() == values, c
        assert all(type(v) is str for v in frame[c]), c
    for c in ("vary.m3", "max_error", "task_seconds"):
        assert frame[c].dtype == np.float64, c
    assert frame["vary.m3"].tolist()[1:] == [85.5, 90.0] and math.isnan(frame["vary.m3"][0])
    assert frame["max_error"][0] == 1e-16 and frame["max_error"][1:].isna().all()


def test_a_rows_frame_takes_the_specs_columns_unless_given(spec):
    """``cols``: `columns(spec)` when not given (sweep_task's list), the given ones otherwise
    (rows_frame(None, ..., cols) never asks a spec). Planted: ``cols and columns(spec)``
    (the spec asked even when the columns are given), the status column not text."""
    frame = rows_frame(spec, [_row(1), _row(0)])
    assert list(frame.columns) == columns(spec)
    assert frame["bicycle"].tolist() == [0, 1] and frame["vary.m3"].tolist() == [80.0, 85.0]
    assert list(rows_frame(None, [{"bicycle": 0}], ["bicycle", "status"]).columns) == \
        ["bicycle", "status"]


@pytest.mark.parametrize("writer, name", [("parquet", "results.parquet"), ("csv", "results.csv")])
def test_merge_writes_every_row_sorted_whatever_the_order_of_the_chunks(spec, tmp_path, writer,
                                                                       name):
    """`merge`: every chunk's rows in one results file of the writer, sorted by bicycle.
    Planted: always results.parquet, the frames concatenated without `rows_frame` (not
    sorted), sorted descending."""
    frames = [rows_frame(spec, [_row(k) for k in c]) for c in ((4,), (2, 3), (0, 1))]
    path = merge(spec, tmp_path, frames, writer)
    assert path == tmp_path / name
    got, _ = read_table(path)
    assert got["bicycle"].tolist() == [0, 1, 2, 3, 4]
    assert got["vary.m3"].tolist() == [80.0, 85.0, 90.0, 95.0, 100.0]
    assert merge(spec, tmp_path / "d", frames) == tmp_path / "d" / "results.parquet"


# --- believed chunks and the estimate ---------------------------------------------------------

def _write_chunks(spec, out, h, writer="parquet"):
    """Chunks (0, 1), (2, 3), (4,) of hand-made rows written as the sweep writes them."""
    chunks = [range(0, 2), range(2, 4), range(4, 5)]
    for i, c in enumerate(chunks):
        write_chunk(rows_frame(spec, [_row(k) for k in c]), chunk_path(out, h, i, writer),
                    ChunkStamp(h, c.start, c.stop), writer)
    return chunks


def test_nothing_written_yet_is_every_chunk_to_compute(spec, tmp_path):
    """No chunk folder: every chunk left, none believed, nothing said. Planted: a chunk not
    in the folder taken as present (``in`` for ``not in``)."""
    chunks = [range(0, 2), range(2, 4), range(4, 5)]
    said = []
    frames, todo = believed_chunks(spec, tmp_path, "h1", chunks, "parquet", said.append)
    assert frames == {} and todo == list(enumerate(chunks)) and said == []


@pytest.mark.parametrize("writer", ["parquet", "csv"])
def test_a_missing_chunk_is_left_and_a_foreign_one_named_on_one_line(spec, tmp_path, writer):
    """Chunk 1 deleted: left to compute, silently. Chunk 2's file copied over chunk 0: named
    on one line as docs/sweep.md shows it ("... is not chunk 0 of this sweep (it holds
    bicycles 4-4, not 0-1); computing it again"), and left. Chunk 2 believed: its rows read
    back. A chunk of the other writer in the folder does not count. Planted: the line
    dropped or its words changed, a believed chunk's frame not kept, a missing chunk skipped,
    the foreign one not left to compute, the chunks' parent folder listed (nothing believed),
    the chunk path's suffix not the writer's."""
    h = "h1"
    chunks = _write_chunks(spec, tmp_path, h, writer)
    chunk_path(tmp_path, h, 1, writer).unlink()
    path0 = chunk_path(tmp_path, h, 0, writer)
    shutil.copyfile(chunk_path(tmp_path, h, 2, writer), path0)
    other = "csv" if writer == "parquet" else "parquet"
    write_chunk(rows_frame(spec, [_row(2), _row(3)]), chunk_path(tmp_path, h, 1, other),
                ChunkStamp(h, 2, 4), other)
    said = []
    frames, todo = believed_chunks(spec, tmp_path, h, chunks, writer, said.append)
    assert said == [f"sweep: {path0} is not chunk 0 of this sweep (it holds bicycles 4-4, "
                    "not 0-1); computing it again"]
    assert todo == [(0, range(0, 2)), (1, range(2, 4))]
    assert list(frames) == [2]
    assert frames[2]["bicycle"].tolist() == [4] and frames[2]["weave_speed"].tolist() == [4.4]
    assert list(frames[2].columns) == columns(spec)


def test_a_chunk_of_another_spec_is_named_with_its_hash(spec, tmp_path):
    """A file written under another spec's hash in this hash's folder: "it belongs to spec
    'h0', not h1". Planted: the notice dropped or its words changed, the chunks' parent
    folder listed (the file never seen), the foreign file not left to compute."""
    _write_chunks(spec, tmp_path, "h0")
    (tmp_path / "chunks" / "h1").mkdir()
    shutil.copyfile(chunk_path(tmp_path, "h0", 2), chunk_path(tmp_path, "h1", 2))
    said = []
    _, todo = believed_chunks(spec, tmp_path, "h1", [range(0, 2), range(2, 4), range(4, 5)],
                              "parquet", said.append)
    assert [i for i, _ in todo] == [0, 1, 2]
    assert said == [f"sweep: {chunk_path(tmp_path, 'h1', 2)} is not chunk 2 of this sweep (it "
                    "belongs to spec 'h0', not h1); computing it again"]


def test_the_estimate_is_measured_on_the_rows_done_else_the_table(spec, tmp_path):
    """`_estimate`: the mean of the finite task_seconds of the chunks already done (30 and 60
    s: 45 s, on 2 bicycles; the NaN and the inf are no measurements), else the table's cost
    (0.06 s, measured on 0); the chunks, chunks left and bicycles left; a bicycle's limit
    20 x the table's cost, at least 120 s, or the one given. Planted: the mean over all rows
    (NaN), the sum instead of the mean, the bicycles left counted as chunks, the override
    ignored, the workers not passed, the chunks left counted as done, the runs' table row
    divided by 2."""
    chunks = [range(0, 2), range(2, 4), range(4, 5)]
    frames = {i: rows_frame(spec, [_row(k) for k in c]) for i, c in enumerate(chunks)}
    frames.pop(1)
    todo = [(1, range(2, 4))]
    assert sweep._estimate(spec, frames, chunks, todo, 4, None) == \
        Estimate(5, 3, 1, 2, 45.0, 2, 4, 120.0)
    assert sweep._estimate(spec, {}, chunks, list(enumerate(chunks)), 3, 7.5) == \
        Estimate(5, 3, 3, 5, pytest.approx(0.06), 0, 3, 7.5)
    runs = _cost_spec(("eigen", "runs"), ("reference",), n_bicycles=5)   # 0.06 + 12 x 2 / 3
    assert sweep._estimate(runs, {}, chunks, [], 1, None).limit == pytest.approx(20 * 8.06)


# --- run_sweep, with the scheduler's compute replaced ---------------------------------------------

def test_a_sweep_writes_its_spec_its_chunks_and_the_sorted_results(spec, tmp_path, two_per_chunk,
                                                                   fake_compute, clock, lines):
    """The layout of ``out``: spec.json (the hash, the chunk size, the spec), one stamped file
    per chunk under the hash, results.parquet with every row sorted by bicycle (the chunks
    finished last first). The result: the hash, 5 bicycles, 3 chunks all computed, the
    compute's lost tasks, the results path; the timings: the 7 workers (all of them, not
    Dask's first 5), the tasks' finite seconds summed (30 + 0.25 + 60: the NaN and the inf
    left out), and the compute's 4 s of the fake clock, the sweep's too. The compute is given
    the chunks left, the limit (120 s), the real task, the stop's check and the line sink;
    the passed-in client stays open. Planted: spec.json's keys or chunk size altered, a chunk
    stamped with its index's neighbour, the sum over the non-finite seconds (or replaced per
    chunk), n_workers not -1, computed not counted, failed_tasks dropped, the times added
    instead of subtracted, the task or the check not passed, skipped counted as todo."""
    client = FakeClient(7)
    res = _sweep(spec, tmp_path, lines, client=client)
    h = spec_hash(spec)
    saved = json.loads((tmp_path / "spec.json").read_text())
    assert saved == {"hash": h, "chunk_size": 2, "spec": json.loads(json.dumps(spec.as_json()))}
    assert (tmp_path / "spec.json").read_text().endswith("}\n")
    for i, (start, stop) in enumerate([(0, 2), (2, 4), (4, 5)]):
        path = tmp_path / "chunks" / h / f"chunk-{i:06d}.parquet"
        frame = read_chunk(path, ChunkStamp(h, start, stop), columns(spec))
        assert frame["bicycle"].tolist() == list(range(start, stop))
    results, _ = read_table(tmp_path / "results.parquet")
    assert results["bicycle"].tolist() == [0, 1, 2, 3, 4]
    assert results["vary.m3"].tolist() == [80.0, 85.0, 90.0, 95.0, 100.0]
    assert results["status"].tolist() == ["agree"] * 3 + ["failed", "agree"]
    assert (res.out, res.hash, res.n_bicycles, res.chunks) == (tmp_path, h, 5, 3)
    assert (res.computed, res.skipped, res.failed_tasks) == (3, 0, 2)
    assert res.results == tmp_path / "results.parquet"
    assert res.timings == {"workers": 7, "task_seconds": 90.25, "compute_seconds": 4.0}
    assert res.seconds == 4.0
    (call,) = fake_compute.calls
    assert call["client"] is client and call["spec"] is spec
    assert call["todo"] == [(0, range(0, 2)), (1, range(2, 4)), (2, range(4, 5))]
    assert call["limit"] == 120.0
    assert call["task"] is sweep_deadline.limited_chunk_rows
    assert isinstance(call["check"].__self__, StopRequest) and call["check"].__name__ == "check"
    assert client.log == []


def test_the_estimate_is_said_before_the_first_task(spec, tmp_path, two_per_chunk, fake_compute,
                                                    lines):
    """docs/sweep.md: one line before the first task: the bicycles, the chunks, how many are
    done, what is left and the expected time on the workers at hand (0.06 x 5 / 7 s: under a
    second) from the table, each bicycle's limit; then the compute's own lines. Planted: the
    line not said, the workers counted from Dask's first 5 (or None), the chunks left
    counted as done, the bicycles left counted as chunks."""
    _sweep(spec, tmp_path, lines, client=FakeClient(7))
    first = ("sweep: 5 bicycles in 3 chunks (0 already done); 5 to compute, under a second on "
             "7 workers at 0.06 s a bicycle (the development machine's measured cost); each "
             "bicycle given up after 120 s")
    assert fake_compute.calls[0]["said_before"] == [first]
    assert lines == [first, "sweep: a line from the scheduler"]


def test_a_bicycle_timeout_is_the_limit_given_to_the_tasks(spec, tmp_path, fake_compute, lines):
    """``bicycle_timeout``: the seconds a bicycle may take, in the line and in the tasks'
    arguments. Planted: the timeout not passed on to `_compute` or to the estimate (the
    default 120 s), the override ignored by the estimate."""
    _sweep(spec, tmp_path, lines, bicycle_timeout=7.5)
    assert fake_compute.calls[0]["limit"] == 7.5
    assert lines[0].endswith("each bicycle given up after 7.5 s")


def test_a_rerun_computes_nothing_and_merges_the_same_rows(spec, tmp_path, two_per_chunk,
                                                          fake_compute, monkeypatch, lines):
    """Docs: "rerunning the same command computes only the missing chunks": none here. No
    client is asked for, no compute called, no line said, no chunk file rewritten; every chunk
    skipped, the tasks' seconds 0, the results the same rows. Planted: the compute called
    with nothing to do (``if todo`` negated), the chunks believed nothing (a listing of the
    wrong folder), the task seconds starting at 1."""
    first = _sweep(spec, tmp_path, lines)
    before = {p: p.stat().st_mtime_ns for p in (tmp_path / "chunks").rglob("*.parquet")}
    rows = read_table(first.results)[0]
    monkeypatch.setattr(sweep, "compute", None)          # called: TypeError
    monkeypatch.setattr(sweep, "_client", None)
    again_lines = []
    again = _sweep(spec, tmp_path, again_lines, client=None)
    assert (again.computed, again.skipped, again.chunks, again.failed_tasks) == (0, 3, 3, 0)
    assert again.timings == {"task_seconds": 0.0} and again_lines == []
    assert {p: p.stat().st_mtime_ns for p in before} == before
    pd.testing.assert_frame_equal(read_table(again.results)[0], rows)


def test_a_resume_computes_the_missing_and_foreign_chunks_from_the_measured_cost(
        spec, tmp_path, two_per_chunk, fake_compute, lines):
    """Chunk 1 deleted and chunk 2 copied over chunk 0: the foreign file named first, then the
    estimate from the one believed bicycle (60 s: 60 x 4 / 7 = 34 s for the 4 left), the two
    chunks computed again, the results complete. Planted: the notice's words changed or
    dropped, the measured cost's test negated, the workers counted from Dask's first 5,
    skipped counted as the chunks left, a believed chunk's frame dropped, the non-finite
    seconds summed."""
    first = _sweep(spec, tmp_path, lines)
    h = first.hash
    chunk_path(tmp_path, h, 1).unlink()
    shutil.copyfile(chunk_path(tmp_path, h, 2), chunk_path(tmp_path, h, 0))
    fake_compute.order = None
    said = []
    again = _sweep(spec, tmp_path, said)
    assert said[:2] == [
        f"sweep: {chunk_path(tmp_path, h, 0)} is not chunk 0 of this sweep (it holds bicycles "
        "4-4, not 0-1); computing it again",
        "sweep: 5 bicycles in 3 chunks (1 already done); 4 to compute, about 34 s on 7 workers "
        "at 60 s a bicycle (measured on the 1 bicycles done); each bicycle given up after 120 s"]
    assert fake_compute.calls[1]["todo"] == [(0, range(0, 2)), (1, range(2, 4))]
    assert (again.computed, again.skipped) == (2, 1)
    assert again.timings["task_seconds"] == 30.25
    assert read_table(again.results)[0]["bicycle"].tolist() == [0, 1, 2, 3, 4]


def test_the_csv_writer_writes_csv_chunks_and_results(spec, tmp_path, fake_compute, lines):
    """``writer="csv"``: ``chunk-000000.csv`` and ``results.csv``; no writer given: Parquet
    (pyarrow is installed here). Planted: the writer given ignored for the chunks (or the
    results), the default writer csv."""
    res = _sweep(spec, tmp_path / "c", lines, writer="csv")
    h = res.hash
    assert res.results == tmp_path / "c" / "results.csv"
    assert sorted(p.name for p in (tmp_path / "c" / "chunks" / h).iterdir()) == ["chunk-000000.csv"]
    read_chunk(chunk_path(tmp_path / "c", h, 0, "csv"), ChunkStamp(h, 0, 5), columns(spec))
    assert read_table(res.results)[0]["bicycle"].tolist() == [0, 1, 2, 3, 4]
    res = _sweep(spec, tmp_path / "p", lines)
    assert res.results == tmp_path / "p" / "results.parquet"
    assert chunk_path(tmp_path / "p", h, 0).exists()


def test_the_real_task_on_two_bicycles_reaches_the_files(tmp_path, monkeypatch, lines):
    """The compute's stand-in runs the task it is given (the real one: each bicycle under its
    limit in a helper thread) on m3 = 80 and 90 kg, the reference's terms against itself at one
    state: the stored rows are those the task computes in this process (task_seconds aside),
    both agreeing. Planted: no task passed (None), the entry.* or localization columns not
    text, the rows sorted by seed."""
    fake = FakeCompute(lines=lines, real_task=True)
    monkeypatch.setattr(sweep, "compute", fake)
    spec = make_spec(load_model("benchmark").params, varies=["m3=80:90:2"],
                     engines=("reference",), checks=("terms",), n_states=1)
    res = _sweep(spec, tmp_path, lines)
    stored = read_table(res.results)[0].drop(columns="task_seconds")
    again = rows_frame(spec, chunk_rows(spec, (0, 1))).drop(columns="task_seconds")
    pd.testing.assert_frame_equal(stored, again)
    assert stored["status"].tolist() == ["agree", "agree"]
    assert stored["vary.m3"].tolist() == [80.0, 90.0]


def test_the_progress_bar_counts_the_bicycles_left(spec, tmp_path, two_per_chunk, fake_compute,
                                                   monkeypatch, lines):
    """The bar's total is the bicycles to compute (5, then 2 after chunk 1 is deleted), told
    each chunk's bicycles as they arrive; ``progress=False`` disables it. Planted: the total
    the chunks' count, the progress flag not passed (or negated), the updates not passed."""
    bars = []

    class Bar:
        def __init__(self, total, enabled):
            self.total, self.enabled, self.updates = total, enabled, []
            bars.append(self)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def update(self, n):
            self.updates.append(n)
    monkeypatch.setattr(sweep, "_progress_bar", Bar)
    res = run_sweep(spec, tmp_path, client=FakeClient(), notify=lines.append)
    chunk_path(tmp_path, res.hash, 1).unlink()
    run_sweep(spec, tmp_path, client=FakeClient(), progress=False)
    assert [(b.total, b.enabled) for b in bars] == [(5, True), (2, False)]
    assert bars[0].updates == [1, 2, 2] and bars[1].updates == [2]


def test_the_progress_bar_counts_bicycles_on_stderr(monkeypatch):
    """`_progress_bar`: a tqdm bar "sweep" of ``total`` bicycles on stderr, disabled when not
    enabled, refreshed more often on a terminal than in a log (and only there as wide as the
    terminal). Planted: the unit or the description altered, ``disable=enabled``, the total
    not passed, the refresh intervals swapped."""
    made = []

    def tqdm(**kw):
        made.append(kw)
        return kw
    monkeypatch.setattr("tqdm.tqdm", tqdm)
    log_file = SimpleNamespace(isatty=lambda: False)
    monkeypatch.setattr(sys, "stderr", log_file)
    sweep._progress_bar(12, True)
    terminal = SimpleNamespace(isatty=lambda: True)
    monkeypatch.setattr(sys, "stderr", terminal)
    sweep._progress_bar(3, False)
    log, tty = made
    assert (log["total"], log["unit"], log["desc"], log["disable"]) == \
        (12, "bicycle", "sweep", False)
    assert (tty["total"], tty["unit"], tty["desc"], tty["disable"]) == (3, "bicycle", "sweep", True)
    assert log["file"] is log_file and tty["file"] is terminal
    assert tty["mininterval"] < log["mininterval"]
    assert (tty["dynamic_ncols"], log["dynamic_ncols"]) == (True, False)


# --- the sweep's own client, closing and interrupts ---------------------------------------------

def test_an_own_client_is_started_with_the_options_and_closed_after(spec, tmp_path, fake_compute,
                                                                    own_cluster, kills, lines):
    """No client given: one from `_client` with the scheduler, workers and processes asked
    for, used for the tasks, then closed: the client, then the cluster; no worker killed.
    Planted: an own client left open, the cluster closed first, the workers killed on a normal
    end, the workers or the processes flag not passed on."""
    res = _sweep(spec, tmp_path, lines, client=None, scheduler="tcp://h:1", workers=3,
                 processes=False)
    assert own_cluster.calls == [("tcp://h:1", 3, False)]
    assert fake_compute.calls[0]["client"] is own_cluster.client
    assert res.timings["workers"] == 2
    assert own_cluster.log == ["client.close", "cluster.close"] and kills == []


def test_an_own_client_is_closed_when_the_compute_raises(spec, tmp_path, two_per_chunk, monkeypatch,
                                                        own_cluster, kills, lines):
    """The compute raising (after chunk 0's file): the error goes up, the own client and
    cluster are closed (not killed: no signal), chunk 0 stays, no results file. A passed-in
    client is left open then too. Planted: the close outside ``finally``, the passed-in
    client closed."""
    monkeypatch.setattr(sweep, "compute", FakeCompute(raises=RuntimeError("scheduler gone")))
    with pytest.raises(RuntimeError, match="scheduler gone"):
        _sweep(spec, tmp_path, lines, client=None)
    assert own_cluster.log == ["client.close", "cluster.close"] and kills == []
    assert chunk_path(tmp_path, spec_hash(spec), 0).exists()
    assert not chunk_path(tmp_path, spec_hash(spec), 1).exists()
    assert not (tmp_path / "results.parquet").exists()
    mine = FakeClient()
    with pytest.raises(RuntimeError):
        _sweep(spec, tmp_path, lines, client=mine)
    assert mine.log == []


def test_a_signal_during_the_tasks_kills_the_local_workers_and_keeps_the_finished_chunks(
        spec, tmp_path, two_per_chunk, monkeypatch, own_cluster, stop, kills, lines):
    """SIGTERM after chunk 0 (its check raises `Terminated`): the local workers are killed
    (SIGKILL, their nannies told not to restart them) before the client and the cluster are
    closed; chunk 0's file stays, nothing more is written. Planted: at_once from ``signum is
    None``, the nannies left restarting, SIGTERM for SIGKILL, the close outside ``finally``,
    the check not passed to the compute (None)."""
    fake = FakeCompute(stop_after=1)
    fake.stop_after_hook = lambda: setattr(stop, "signum", signal.SIGTERM)
    monkeypatch.setattr(sweep, "compute", fake)
    with pytest.raises(Terminated):
        _sweep(spec, tmp_path, lines, client=None)
    assert kills == [(101, signal.SIGKILL), (102, signal.SIGKILL)]
    assert [n.auto_restart for n in own_cluster.cluster.workers.values()] == [False, False]
    assert own_cluster.log == ["client.close", "cluster.close"]
    h = spec_hash(spec)
    assert chunk_path(tmp_path, h, 0).exists() and not chunk_path(tmp_path, h, 1).exists()
    assert not (tmp_path / "results.parquet").exists()


def test_a_signal_while_the_cluster_starts_stops_before_any_task(spec, tmp_path, fake_compute,
                                                                 own_cluster, stop, kills, lines):
    """Ctrl-C while the local cluster starts: raised as soon as it is up, before the estimate
    and any task; its workers killed, it and the client closed. Planted: the check after the
    cluster's start dropped (the sweep goes on)."""
    own_cluster.on_start = lambda: setattr(stop, "signum", signal.SIGINT)
    with pytest.raises(KeyboardInterrupt):
        _sweep(spec, tmp_path, lines, client=None)
    assert fake_compute.calls == [] and lines == []
    assert kills == [(101, signal.SIGKILL), (102, signal.SIGKILL)]
    assert own_cluster.log == ["client.close", "cluster.close"]


def test_a_signal_while_the_sweep_closes_is_raised_after_the_close(spec, tmp_path, fake_compute,
                                                                   own_cluster, stop, kills,
                                                                   lines):
    """A Ctrl-C noted while the client closes (every chunk done): the close goes on normally
    (no worker killed: the tasks had ended), then the sweep raises it, the chunks kept.
    Planted: the check after the block dropped."""
    own_cluster.client.on_close = lambda: setattr(stop, "signum", signal.SIGINT)
    with pytest.raises(KeyboardInterrupt):
        _sweep(spec, tmp_path, lines, client=None)
    assert kills == [] and own_cluster.log == ["client.close", "cluster.close"]
    assert chunk_path(tmp_path, spec_hash(spec), 0).exists()


def _loggers():
    return [logging.getLogger(n) for n in ("distributed", "tornado", "asyncio")]


@pytest.fixture
def levels():
    """The three loggers at known levels, given back after the test."""
    loggers = _loggers()
    saved = [q.level for q in loggers]
    for q, level in zip(loggers, (logging.INFO, logging.WARNING, logging.NOTSET)):
        q.setLevel(level)
    yield [logging.INFO, logging.WARNING, logging.NOTSET]
    for q, level in zip(loggers, saved):
        q.setLevel(level)


def test_close_is_quiet_then_gives_the_loggers_back(levels, kills):
    """`_close`: while the client and then the cluster close, Dask's, tornado's and asyncio's
    loggers say nothing (above CRITICAL); afterwards each has its own level back; no worker
    is killed unless ``at_once``; without a cluster only the client closes. Planted: a logger
    left out, the level CRITICAL (still shown), the levels not given back (or all given the
    first one's), the cluster closed before the client."""
    seen = []

    class Client(FakeClient):
        def close(self):
            seen.append([q.level for q in _loggers()])
            super().close()
    log = []
    sweep._close(Client(1, log), FakeCluster(log))
    assert log == ["client.close", "cluster.close"] and kills == []
    assert all(level > logging.CRITICAL for level in seen[0])
    assert [q.level for q in _loggers()] == levels
    sweep._close(Client(1, log), None, at_once=True)
    assert log[2:] == ["client.close"] and kills == []


def test_close_gives_the_loggers_back_when_closing_fails(levels):
    """A client whose close raises: the error goes up, the levels are back. Planted: the
    levels given back outside ``finally``, not at all."""
    class Broken(FakeClient):
        def close(self):
            raise OSError("connection reset")
    with pytest.raises(OSError):
        sweep._close(Broken(), None)
    assert [q.level for q in _loggers()] == levels


def test_at_once_the_workers_are_killed_first_each_nanny_told_not_to_restart(kills):
    """`_kill_workers`: SIGKILL to each worker process with a pid, its nanny's auto_restart
    off first; a nanny with no process (pid None, or no process at all) left alone; a process
    already gone no error; a cluster of threads (no ``workers``) nothing. Planted: SIGTERM
    sent, the nanny left restarting, a pid-less nanny touched (os.kill(None)), the
    ProcessLookupError let through, the loop stopped at the first nanny without a pid."""
    log = []
    cluster = FakeCluster(log, pids=(None, 101, 404, 103))
    cluster.workers["bare"] = SimpleNamespace(auto_restart=True)
    sweep._close(FakeClient(1, log), cluster, at_once=True)
    assert kills == [(101, signal.SIGKILL), (404, signal.SIGKILL), (103, signal.SIGKILL)]
    assert [n.auto_restart for n in cluster.workers.values()] == [True, False, False, False, True]
    assert log == ["client.close", "cluster.close"]
    sweep._kill_workers(SimpleNamespace())
    assert len(kills) == 3


# --- _client, with a fake `distributed` ---------------------------------------------------------

@pytest.fixture
def fake_distributed(monkeypatch):
    """``distributed`` replaced: its Client and LocalCluster record what they are given, the
    cluster also what it sees while it starts (the signal handlers, Dask's allowed-failures,
    the BLAS variables); ``fail``: the cluster's start raises."""
    made = SimpleNamespace(clients=[], clusters=[], fail=None)

    class Client:
        def __init__(self, *args, **kwargs):
            self.args, self.kwargs = args, kwargs
            made.clients.append(self)

    class LocalCluster:
        def __init__(self, **kwargs):
            self.kwargs = kwargs
            self.seen = {
                "handlers": (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)),
                "allowed_failures": dask.config.get(FAILURES_KEY, None),
                "env": {v: os.environ.get(v) for v in
                        ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")},
            }
            made.clusters.append(self)
            if made.fail:
                raise made.fail
    fake = types.ModuleType("distributed")
    fake.Client, fake.LocalCluster = Client, LocalCluster
    monkeypatch.setitem(sys.modules, "distributed", fake)
    for v in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.delenv(v, raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", "4")
    return made


@pytest.fixture
def handlers():
    """SIGINT and SIGTERM set to handlers of the test's own, given back after."""
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    mine = {signal.SIGINT: lambda s, f: None, signal.SIGTERM: lambda s, f: None}
    for s, h in mine.items():
        signal.signal(s, h)
    yield mine
    for s, h in saved.items():
        signal.signal(s, h)


def test_a_scheduler_address_is_connected_to_and_no_cluster_started(fake_distributed):
    """``scheduler``: a client to it with a 20 s connection timeout, no local cluster, the
    BLAS variables untouched (they are the local workers'). Planted: the timeout dropped or
    altered, the address not passed, a cluster started anyway."""
    client, cluster = sweep._client("tcp://host:8786", 3, True)
    assert cluster is None and fake_distributed.clusters == []
    assert (client.args, client.kwargs) == (("tcp://host:8786",), {"timeout": "20s"})
    assert os.environ.get("MKL_NUM_THREADS") is None


@pytest.mark.parametrize("workers, cpus, n, processes", [
    (3, 8, 3, True), (None, 6, 6, False), (None, None, 1, True)])
def test_a_local_cluster_has_the_workers_asked_for_single_threaded(fake_distributed, monkeypatch,
                                                                   handlers, workers, cpus, n,
                                                                   processes):
    """No scheduler: a LocalCluster of ``workers`` single-threaded workers (default: the
    machine's cores, 1 if unknown), processes or threads as asked, no dashboard (its
    scheduler's HTTP server on a free loopback port), its logs silenced; the client is to it.
    Planted: one thread more per worker, the processes flag not passed (or negated), the
    cores ignored, 2 for unknown cores, a dashboard port, the logs not silenced, the
    scheduler's HTTP port not the free one, the client not to the cluster."""
    monkeypatch.setattr(os, "cpu_count", lambda: cpus)
    client, cluster = sweep._client(None, workers, processes)
    assert fake_distributed.clusters == [cluster]
    assert cluster.kwargs == {"n_workers": n, "threads_per_worker": 1, "processes": processes,
                              "dashboard_address": None, "silence_logs": logging.CRITICAL,
                              "scheduler_kwargs": {"dashboard_address": "127.0.0.1:0"}}
    assert (client.args, client.kwargs) == ((cluster,), {})


def test_the_cluster_starts_with_signals_ignored_one_blas_thread_and_no_retries(
        fake_distributed, handlers):
    """While the LocalCluster starts (its worker processes inherit it): SIGINT and SIGTERM
    ignored, Dask's allowed-failures 0 (the sweep narrows a lost task down itself), one BLAS
    thread for each library whose variable is unset (OMP_NUM_THREADS=4 kept); afterwards the
    test's own handlers and Dask's setting are back. Planted: SIGTERM not ignored, the
    handlers not given back (or SIG_DFL given back), allowed-failures 1, a BLAS variable
    overwritten or not set (MKL's), the main-thread test negated."""
    before = dask.config.get(FAILURES_KEY, None)
    _, cluster = sweep._client(None, 2, True)
    assert cluster.seen["handlers"] == (signal.SIG_IGN, signal.SIG_IGN)
    assert cluster.seen["allowed_failures"] == 0
    assert cluster.seen["env"] == {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "4",
                                   "MKL_NUM_THREADS": "1"}
    assert signal.getsignal(signal.SIGINT) is handlers[signal.SIGINT]
    assert signal.getsignal(signal.SIGTERM) is handlers[signal.SIGTERM]
    assert dask.config.get(FAILURES_KEY, None) == before


def test_a_cluster_that_fails_to_start_gives_the_handlers_back(fake_distributed, handlers):
    """The LocalCluster raising: the error goes up, the handlers are the test's again.
    Planted: the restore outside ``finally``."""
    fake_distributed.fail = OSError("no free port")
    with pytest.raises(OSError, match="no free port"):
        sweep._client(None, 1, True)
    assert signal.getsignal(signal.SIGINT) is handlers[signal.SIGINT]
    assert signal.getsignal(signal.SIGTERM) is handlers[signal.SIGTERM]


def test_outside_the_main_thread_no_handler_is_touched(fake_distributed, handlers):
    """From another thread (where Python refuses to set a handler) the cluster starts with
    the handlers as they are. Planted: the main-thread test negated (ValueError here)."""
    got = {}

    def start():
        try:
            got["cluster"] = sweep._client(None, 1, True)[1]
        except BaseException as exc:     # noqa: BLE001 -- reported by the test
            got["error"] = exc
    t = threading.Thread(target=start)
    t.start()
    t.join()
    assert "error" not in got, got.get("error")
    assert got["cluster"].seen["handlers"] == (handlers[signal.SIGINT], handlers[signal.SIGTERM])


def test_each_unset_blas_variable_is_set_to_one_thread(fake_distributed, handlers, monkeypatch):
    """The three libraries' variables each get "1" when unset and keep a value the user set:
    OMP unset here (the other test keeps OMP_NUM_THREADS=4), OPENBLAS set to 3.
    Planted: the OpenMP variable's name changed (OMP_NUM_THREADS left unset)."""
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "3")
    _, cluster = sweep._client(None, 1, True)
    assert cluster.seen["env"] == {"OPENBLAS_NUM_THREADS": "3", "OMP_NUM_THREADS": "1",
                                   "MKL_NUM_THREADS": "1"}


def test_a_handler_installed_outside_python_is_given_back_as_the_default(fake_distributed,
                                                                         monkeypatch):
    """signal.signal returns None for a handler not installed from Python (the Python docs):
    such a handler cannot be set back, so the default action is restored, not None (which
    signal.signal refuses with a TypeError). Planted: the None test always true."""
    calls = []

    def fake_signal(signum, handler):
        calls.append((signum, handler))
        if handler is None:
            raise TypeError("signal handler must be signal.SIG_IGN, signal.SIG_DFL, or a callable object")
        return None
    monkeypatch.setattr(signal, "signal", fake_signal)
    sweep._client(None, 1, True)
    assert calls == [(signal.SIGINT, signal.SIG_IGN), (signal.SIGTERM, signal.SIG_IGN),
                     (signal.SIGINT, signal.SIG_DFL), (signal.SIGTERM, signal.SIG_DFL)]


def test_a_local_cluster_is_of_processes_by_default(spec, tmp_path, own_cluster, fake_compute,
                                                    lines):
    """run_sweep without ``processes`` starts its own cluster of worker processes: docs/sweep.md
    counts on them (a frozen engine's worker process is restarted through its nanny, which a
    cluster of threads has not). Planted: processes=False as the default."""
    run_sweep(spec, tmp_path, progress=False, notify=lines.append)
    assert own_cluster.calls == [(None, None, True)]
