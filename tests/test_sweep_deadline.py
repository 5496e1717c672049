"""The sweep's per-bicycle time limit (`comparisons.stages.sweep_deadline`), called directly in
this process: no Dask, and a bicycle function written in the test (slow, raising, or quick), so
the late and the raising bicycle are seen without the worker processes that `make test-slow`
starts.

Expected values come from the module's contract (its docstring and docs/sweep.md): a bicycle
past its limit is a "failed" row "timed out after N s" and the chunk goes on with the next
bicycle; what a bicycle raises past `bicycle_row` (SystemExit, KeyboardInterrupt) is its failed
row "raised Type: message"; every row of a grid sweep carries its grid point, read here from
the --vary text itself (m3 = 85 then 95 kg).
"""

from __future__ import annotations

import threading
import time

import pytest

from comparisons.stages import sweep_deadline
from comparisons.stages.sweep_deadline import limited_chunk_rows, one_line
from comparisons.stages.sweep_spec import make_spec
from reference_model import load_model

# the limit a slow bicycle overruns: short, so the suite waits little, yet 0.2 s is far past
# the start of a thread and a queue's hand-over on a loaded 2-core machine (a quick bicycle
# must never time out); the slow bicycle sleeps five times as long
LIMIT = 0.2
SLOW = 1.0
HELPER = "bicycle-xval-bicycle"


@pytest.fixture(scope="module")
def spec():
    """Two bicycles: the benchmark with its rider at 85 and at 95 kg."""
    return make_spec(load_model("benchmark").params, varies=["m3=85:95:2"], engines=("reference",),
                     checks=("terms",), n_states=2)


def _bicycles(monkeypatch, behaviour):
    """Replace the bicycle computation by ``behaviour[k]``: 'ok' returns a row naming k,
    'slow' sleeps past the limit first, anything else is raised."""
    def row(spec, k):
        what = behaviour[k]
        if what == "slow":
            time.sleep(SLOW)
            return {"bicycle": k, "status": "late"}
        if what == "ok":
            return {"bicycle": k, "status": "ok"}
        raise what
    monkeypatch.setattr(sweep_deadline, "bicycle_row", row)


def test_a_late_bicycle_is_a_failed_row_and_the_chunk_goes_on(spec, monkeypatch):
    """The first bicycle sleeps past the limit: its row is failed, 'timed out after 0.2 s',
    with its grid point (m3 = 85, the --vary's first value); the second is still computed, by
    a fresh helper (the late one is busy). Fails when the wait has no limit (the late row comes
    back as computed), when the loop stops after a late bicycle (`break`), when the failed row
    loses its spec, index or message, or when the helper is not replaced after a timeout."""
    _bicycles(monkeypatch, {0: "slow", 1: "ok"})
    t0 = time.perf_counter()
    rows = limited_chunk_rows(spec, [0, 1], LIMIT)
    assert time.perf_counter() - t0 < SLOW, "the chunk waited for the late bicycle"
    assert len(rows) == 2
    late, ok = rows
    assert late["status"] == "failed"
    assert late["failures"] == "timed out after 0.2 s"
    assert late["bicycle"] == 0
    assert late["vary.m3"] == 85.0
    assert ok == {"bicycle": 1, "status": "ok"}


def test_the_last_bicycle_late_ends_the_chunk_cleanly(spec, monkeypatch):
    """The chunk's last bicycle is late: its row is failed (m3 = 95, the grid's second value)
    and the call returns rows rather than raising while it tidies up (the helper it dropped is
    not stopped twice)."""
    _bicycles(monkeypatch, {0: "ok", 1: "slow"})
    rows = limited_chunk_rows(spec, [0, 1], LIMIT)
    assert [r["status"] for r in rows] == ["ok", "failed"]
    assert rows[1]["vary.m3"] == 95.0
    assert rows[1]["failures"] == "timed out after 0.2 s"


@pytest.mark.parametrize("exc, text", [
    (SystemExit("engine called exit(3)"), "raised SystemExit: engine called exit(3)"),
    (KeyboardInterrupt(), "raised KeyboardInterrupt: "),
    (RuntimeError("bad\n  pivot   at row 4"), "raised RuntimeError: bad pivot at row 4"),
])
def test_what_a_bicycle_raises_is_its_failed_row(spec, monkeypatch, exc, text):
    """A bicycle raising what `bicycle_row` lets through is a failed row naming the exception
    on one line, and the next bicycle is computed by the same helper. Fails when the raise is
    reported as a result, or lost (the helper's loop putting nothing usable back)."""
    _bicycles(monkeypatch, {0: exc, 1: "ok"})
    rows = limited_chunk_rows(spec, [0, 1], LIMIT * 5)
    assert rows[0]["status"] == "failed"
    assert rows[0]["failures"] == text
    assert rows[0]["bicycle"] == 0 and rows[0]["vary.m3"] == 85.0
    assert rows[1] == {"bicycle": 1, "status": "ok"}


def _spy_helpers(monkeypatch):
    """The threads each new helper starts, in order."""
    started = []
    real = sweep_deadline._Helper.__init__

    def spy(self):
        old = set(threading.enumerate())
        real(self)
        started.extend(t for t in threading.enumerate() if t not in old)
    monkeypatch.setattr(sweep_deadline._Helper, "__init__", spy)
    return started


def test_no_helper_thread_outlives_its_chunk(spec, monkeypatch):
    """The helper thread ends when the chunk is done (stopped in the `finally`); it is a named
    daemon, so a late bicycle cannot keep the worker process from exiting, and a late helper
    ends once its bicycle returns. An empty chunk starts none and returns no rows."""
    started = _spy_helpers(monkeypatch)
    _bicycles(monkeypatch, {0: "ok", 1: "ok"})
    assert limited_chunk_rows(spec, [], LIMIT) == []
    assert started == []
    assert len(limited_chunk_rows(spec, [0, 1], LIMIT)) == 2
    assert len(started) == 1, "one helper computes a chunk without a late bicycle"
    started[0].join(5.0)
    assert not started[0].is_alive(), "the helper thread was not stopped after its chunk"

    started.clear()
    _bicycles(monkeypatch, {0: "slow", 1: "ok"})
    limited_chunk_rows(spec, [0, 1], LIMIT)
    assert len(started) == 2, "a late bicycle's helper is replaced"
    assert all(t.daemon and t.name == HELPER for t in started)
    for t in started:
        t.join(SLOW + 5.0)
        assert not t.is_alive(), "a helper thread outlived its chunk"


def test_one_line_folds_whitespace_and_keeps_500_characters():
    """`one_line`: 'Type: message' with every run of whitespace one space, cut at 500
    characters exactly (the sweep's failures column)."""
    assert one_line(ValueError("a\n\tb   c ")) == "ValueError: a b c"
    long = one_line(ValueError("x" * 1000))
    assert len(long) == 500 and long.startswith("ValueError: xxx")
