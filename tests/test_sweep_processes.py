"""Sweep integrity (issue 23), the cases where a process dies: a bicycle that kills its Dask
worker, and Ctrl-C / SIGTERM to a running sweep. Both run real worker processes (a LocalCluster
of processes, the sweep command in its own session), never this test process's threads.

Cost, measured on the 2-core machine shared with three other suites (load average 7-14): the
worker death 20-50 s (a cluster start, 2.2 s alone, and two worker restarts, 1.4-2.4 s each
alone, each a fresh interpreter loading the model), Ctrl-C 12-27 s (the command's start, its
cluster's, one chunk). Not measured on a quiet machine.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from comparisons.stages.sweep import chunk_path, run_sweep, stamp_of
from comparisons.stages.sweep_chunks import read_chunk, read_table
from comparisons.stages.sweep_spec import make_spec, spec_hash
from comparisons.stages.sweep_task import columns
from reference_model import load_model
from sweep_engines import hostile_engines

# signals and deaths in the harness's own process tree: make test-slow
pytestmark = pytest.mark.slow


ROOT = Path(__file__).resolve().parents[1]

@pytest.fixture
def hostile(tmp_path):
    return hostile_engines(tmp_path)


def test_a_bicycle_that_kills_its_worker_is_the_only_failed_row(tmp_path, hostile, monkeypatch):
    """Main: the killer's healthy neighbour was also "failed: KilledWorker" in 2 of 9 runs
    (Dask fails the task queued beside the one running on a worker that dies). Bicycle 0
    kills its worker; bicycle 1, in the same chunk, is computed again alone and agrees."""
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    spec = make_spec(load_model("benchmark").params, varies=["m3=80:90:2"],
                     engines=(f"{hostile}:Killer",), checks=("terms",), n_states=1)
    lines: list[str] = []
    res = run_sweep(spec, tmp_path, workers=1, progress=False, notify=lines.append)
    frame, _ = read_table(res.results)
    assert list(frame["status"]) == ["failed", "agree"], frame["failures"].tolist()
    assert frame["failures"][0].startswith("task lost when run alone: KilledWorker")
    assert list(frame["vary.m3"]) == [80.0, 90.0] and frame["p.m3"][1] == 90.0
    assert any("run again one at a time" in ln for ln in lines), lines
    assert any(ln.startswith("sweep: bicycle 0 loses its task even alone") for ln in lines), lines


def _group_alive(pgid: int) -> list[str]:
    out = subprocess.run(["ps", "-eo", "pgid=,stat=,args="], capture_output=True, text=True).stdout
    return [ln for ln in out.splitlines()
            if ln.split()[0] == str(pgid) and not ln.split()[1].startswith("Z")]


SCRIPT = """
import sys
from comparisons.stages import sweep
sweep.TARGET_SECONDS = 1e-6            # one bicycle a chunk
from comparisons.cli.main import main
sys.exit(main())                       # argv None: the command as the program runs it
"""


def test_ctrl_c_during_a_sweep_is_one_line_and_keeps_the_finished_chunks(tmp_path, hostile):
    """Main: Ctrl-C printed 7 Dask tracebacks (and, measured here, a KeyboardInterrupt "ignored"
    in a Dask callback let the sweep run on). SIGINT goes to the whole process group, as a
    terminal's Ctrl-C does, while bicycle 1 hangs in its engine:
    one line, the status, every process of the group gone within 2 s, and the finished chunk
    reads as this sweep's chunk 0 (a rerun resumes from it)."""
    out = tmp_path / "out"
    argv = ["sweep", "--vary", "m3=80:90:2", "--checks", "terms", "--states", "1", "--engines",
            f"{hostile}:Sleeper", "--workers", "1", "--no-progress", "--out", str(out)]
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    # SIGINT at its default, as a terminal's foreground job has it (a shell's background job,
    # such as a CI runner's, starts with it ignored, which the sweep leaves as it is)
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT, *argv], cwd=ROOT, env=env,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 60
        while not list(out.glob("chunks/*/chunk-000000.parquet")):
            assert proc.poll() is None and time.monotonic() < deadline, proc.stderr.read()
            time.sleep(0.05)
        time.sleep(0.3)                         # bicycle 1 is in its engine by now
        t = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)
        err = proc.communicate(timeout=20)[1]
        gone = time.monotonic() - t
        while _group_alive(proc.pid) and time.monotonic() - t < 2.0:
            time.sleep(0.05)
        assert not _group_alive(proc.pid), _group_alive(proc.pid)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    lines = err.strip().splitlines()
    assert proc.returncode == 130 and gone < 2.0, (proc.returncode, gone, err)
    assert "Traceback" not in err and len(lines) == 2, err      # the estimate, then the signal
    assert "rerun the same command to resume" in lines[1]
    spec = make_spec(load_model("benchmark").params, varies=["m3=80:90:2"], checks=("terms",),
                     engines=(f"{hostile}:Sleeper",), n_states=1)
    h = spec_hash(spec)
    assert str(out / "chunks" / h) in lines[1]
    frame = read_chunk(chunk_path(out, h, 0), stamp_of(h, (0,)), columns(spec))
    assert list(frame["status"]) == ["agree"] and not chunk_path(out, h, 1).exists()


def test_an_engine_that_freezes_its_worker_holding_the_gil_is_a_failed_row(tmp_path, hostile):
    """Main: an engine that holds the interpreter lock forever (here 600 s asleep in C through
    ctypes.PyDLL) froze the per-bicycle limit's thread with the rest of its worker, and the
    sweep hung. Seen from the client its task passes its deadline (2 x 2 bicycles x 2 s + 3 s
    of grace): it is cancelled, its worker process restarted by its nanny, the chunk narrowed
    down; bicycle 0 agrees, bicycle 1 freezes its worker again alone and is the failed row. The
    whole takes two deadlines and two worker restarts, far below the 600 s hang."""
    from distributed import Client, LocalCluster

    from comparisons.stages.sweep_schedule import compute
    spec = make_spec(load_model("benchmark").params, varies=["m3=80:90:2"],
                     engines=(f"{hostile}:Freezer",), checks=("terms",), n_states=1)
    lines: list[str] = []
    got: dict = {}
    t = time.perf_counter()
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=50) as cluster, Client(cluster) as client:
        lost = compute(client, spec, [(0, (0, 1))], 2.0, got.__setitem__, say=lines.append,
                       grace=3.0)
    took = time.perf_counter() - t
    rows = sorted(got[0], key=lambda r: r["bicycle"])
    assert [r["status"] for r in rows] == ["agree", "failed"], rows
    assert rows[1]["failures"].startswith("task lost when run alone: TaskOverdue: its worker "
                                          "froze"), rows[1]["failures"]
    assert "the worker process was restarted" in rows[1]["failures"], rows[1]["failures"]
    assert lost == 2 and took < 120, (lost, took, lines)
