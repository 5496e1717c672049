"""A sweep on Dask: chunks of bicycles as tasks, one stamped file per chunk, resumable.

    result = run_sweep(spec, out_dir, workers=2)                  # a LocalCluster
    result = run_sweep(spec, out_dir, scheduler="tcp://host:8786")   # a running cluster

Layout of ``out_dir``::

    spec.json                        the spec and its hash (what the chunks belong to)
    chunks/<hash>/chunk-000000.parquet   one per chunk, rows sorted by bicycle (.csv without pyarrow)
    results.parquet                  every row of the sweep, sorted by bicycle (when complete)

* **Chunks**: consecutive bicycle indices, sized so a task takes about ``TARGET_SECONDS``
  (1-10 s, from `COST`: per-bicycle seconds measured on the 2-core development machine), a
  pure function of the spec: the chunking is part of what the hash fixes.
* **Atomic, stamped and resumable**: each chunk file is written to a temporary name and
  renamed when complete (`files.atomic_path`), with its stamp: the spec hash and its bicycles
  (`sweep_chunks`). A rerun with the same spec computes the chunks whose file is missing, and
  those whose file does not read or is not the chunk the plan expects (cut, copied over
  another, of another spec, with other columns), one line each saying so (an interrupted
  sweep loses the chunks in flight, nothing else).
* **Estimate and limits**: before the first task, one line gives the bicycles, the chunks,
  what is left and the expected time (`sweep_budget`); each bicycle runs under a time limit
  (`sweep_deadline`: past it, a "failed" row "timed out after N s").
* **Failures are rows**: an engine that raises on a bicycle is caught in the task
  (`sweep_task.bicycle_row`); a task that never returns (its worker died, or any other
  exception) is narrowed down to the bicycle that loses it, each of its bicycles run again
  alone (`sweep_schedule`): only that bicycle becomes a "failed" row naming the exception.
  Delete that chunk's file to compute it again.
* **Interrupts**: Ctrl-C and SIGTERM are noted while Dask runs and acted on between two
  futures (`sweep_signals`); the local workers are killed and the finished chunks stay.
* **Deterministic**: bicycle k's parameters and states come from ``SeedSequence([seed, k])``,
  rows are sorted by index: the same spec gives the same rows (``task_seconds`` aside),
  whatever the number of workers or the order they finish in.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from .files import write_text
from .sweep_budget import Estimate, bicycle_limit, estimate_line
from .sweep_chunks import (WRITERS, ChunkMismatch, ChunkStamp, default_writer, read_chunk,
                           write_chunk, write_table)
from .sweep_deadline import limited_chunk_rows
from .sweep_schedule import compute
from .sweep_signals import deferred_signals
from .sweep_spec import SweepSpec, spec_hash
from .sweep_task import columns

TARGET_SECONDS = 3.0
#: rough seconds per bicycle (2-core machine, measured: benchmarks/sweep_timings.py)
COST = {"terms": 0.01, "terms_engine": 0.02, "eigen": 0.06, "runs": 12.0}
MAX_CHUNK = 200


@dataclass
class SweepResult:
    """What a sweep did: where, under which hash, how many chunks computed and skipped."""

    out: Path
    hash: str
    n_bicycles: int
    chunks: int
    computed: int = 0
    skipped: int = 0
    failed_tasks: int = 0
    seconds: float = 0.0
    results: Path | None = None
    timings: dict = field(default_factory=dict)


def bicycle_cost(spec: SweepSpec) -> float:
    """Estimated seconds for one bicycle (`COST`)."""
    c = 0.0
    if "terms" in spec.checks:
        c += COST["terms"] + COST["terms_engine"] * len(spec.engines) * spec.n_states / 8
    if "eigen" in spec.checks:
        c += COST["eigen"]
    if "runs" in spec.checks:
        c += COST["runs"] * (1 + len(spec.engines)) / 3
    return c


def chunk_size(spec: SweepSpec) -> int:
    return max(1, min(MAX_CHUNK, int(TARGET_SECONDS / max(bicycle_cost(spec), 1e-6))))


def plan(spec: SweepSpec) -> list[range]:
    """The chunks: consecutive bicycle indices (ranges: a large sweep's plan stays small)."""
    n, size = spec.n_bicycles, chunk_size(spec)
    return [range(s, min(s + size, n)) for s in range(0, n, size)]


def chunk_name(i: int, writer: str = "parquet") -> str:
    return f"chunk-{i:06d}{WRITERS[writer]}"


def chunk_path(out: Path, h: str, i: int, writer: str = "parquet") -> Path:
    return Path(out) / "chunks" / h / chunk_name(i, writer)


def stamp_of(h: str, bicycles) -> ChunkStamp:
    """The stamp of the chunk of consecutive ``bicycles`` under spec hash ``h``."""
    return ChunkStamp(h, bicycles[0], bicycles[-1] + 1)


def rows_frame(spec: SweepSpec, rows, cols: list[str] | None = None):
    """The rows (dicts, or a frame) as a DataFrame with fixed columns and dtypes (identical
    files for identical rows), sorted by bicycle; ``cols``: `columns(spec)` when known (it asks
    the engine registry: ~30 ms)."""
    import pandas as pd
    cols = cols or columns(spec)
    frame = pd.DataFrame(rows, columns=cols).sort_values("bicycle", kind="stable")
    for c in cols:
        if c in ("bicycle", "seed"):
            frame[c] = frame[c].astype("uint64" if c == "seed" else "int64")
        elif c in ("terms_passed", "runs_confirmed"):
            frame[c] = frame[c].astype("boolean")
        elif c.startswith(("entry.", "run.")) or c in ("status", "failures", "localization"):
            # object first: a column with no text in it (all NaN) is float64, and pandas
            # refuses to put "" into a float column in place (Pandas4Warning, an error to come)
            frame[c] = frame[c].astype(object).fillna("").astype(str)
        else:
            frame[c] = frame[c].astype("float64")
    return frame.reset_index(drop=True)


def _client(scheduler: str | None, workers: int | None, processes: bool):
    """A Dask client: to ``scheduler``, or to a new LocalCluster of ``workers`` single-threaded
    workers (default: the machine's cores)."""
    from distributed import Client, LocalCluster
    if scheduler:
        return Client(scheduler, timeout="20s"), None
    n = workers or os.cpu_count() or 1
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")     # one BLAS thread per worker: the matrices are small
    import signal
    import threading
    main = threading.current_thread() is threading.main_thread()
    signals = (signal.SIGINT, signal.SIGTERM)
    previous = {s: signal.signal(s, signal.SIG_IGN) for s in signals} if main else {}
    import dask
    try:   # the worker processes start with Ctrl-C and SIGTERM ignored (inherited): the client
        # stops them (at an interrupt: kills them, `_close`), and a group's SIGTERM cannot start
        # their nannies restarting them while the sweep closes
        # a worker's death fails its tasks at once: `sweep_schedule` narrows them down itself
        # (Dask's retries would blame a healthy task queued beside the one that kills)
        with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=processes,
                                   dashboard_address=None, silence_logs=50,
                                   # its HTTP server on a free port: no "Port 8787 is already
                                   # in use" warning when another cluster holds it
                                   scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler if handler is not None else signal.SIG_DFL)
    return Client(cluster), cluster


def _progress_bar(total: int, enabled: bool):
    from tqdm import tqdm
    tty = sys.stderr.isatty()
    return tqdm(total=total, unit="bicycle", file=sys.stderr, disable=not enabled,
                mininterval=0.5 if tty else 15.0, dynamic_ncols=tty,
                desc="sweep")


def run_sweep(spec: SweepSpec, out: Path, *, scheduler: str | None = None,
              workers: int | None = None, processes: bool = True,
              progress: bool = True, client=None, writer: str | None = None,
              bicycle_timeout: float | None = None, notify=None) -> SweepResult:
    """Compute every missing or unbelievable chunk of ``spec`` on Dask, then merge all rows
    into ``results.parquet`` (module docstring). ``client``: an existing Dask client to use
    (and leave open) instead of connecting to ``scheduler`` or starting a local cluster;
    ``writer``: "parquet" or "csv" (`sweep_chunks`; default parquet where pyarrow is
    installed); ``bicycle_timeout``: seconds a bicycle may take (default
    `sweep_budget.bicycle_limit`); ``notify``: called with each line for the user (the
    estimate, a chunk computed again and why)."""
    t0 = time.perf_counter()
    out = Path(out)
    writer = writer or default_writer()
    say = notify or (lambda line: None)
    h = spec_hash(spec)
    chunks = plan(spec)
    write_text(out / "spec.json", json.dumps({"hash": h, "chunk_size": chunk_size(spec),
                                              "spec": spec.as_json()}, indent=1) + "\n")
    frames, todo = believed_chunks(spec, out, h, chunks, writer, say)
    result = SweepResult(out, h, spec.n_bicycles, len(chunks), skipped=len(chunks) - len(todo))
    task_seconds = 0.0
    if todo:
        with deferred_signals() as stop:
            task_seconds = _compute(spec, out, h, chunks, todo, frames, result, writer, say,
                                    stop, client=client, scheduler=scheduler,
                                    workers=workers, processes=processes, progress=progress,
                                    bicycle_timeout=bicycle_timeout)
        stop.check()        # a signal that arrived while the client and cluster were closing
    result.timings["task_seconds"] = task_seconds
    result.results = merge(spec, out, [frames[i] for i in range(len(chunks))], writer)
    result.seconds = time.perf_counter() - t0
    return result


def _compute(spec, out, h, chunks, todo, frames, result, writer, say, stop, *, client,
             scheduler, workers, processes, progress, bicycle_timeout) -> float:
    """The chunks of ``todo`` on Dask, each written as it completes and kept in ``frames``;
    returns the tasks' own seconds. Stops (the client and an own cluster closed) when a signal
    reaches ``stop`` (a `sweep_signals.StopRequest`)."""
    check = stop.check
    task_seconds = 0.0
    own = client is None
    cluster = None
    try:
        if own:
            client, cluster = _client(scheduler, workers, processes)
        check()
        n_workers = len(client.scheduler_info(n_workers=-1)["workers"])
        result.timings["workers"] = n_workers
        estimate = _estimate(spec, frames, chunks, todo, n_workers, bicycle_timeout)
        say(estimate_line(estimate))
        t_submit = time.perf_counter()
        cols = columns(spec)
        with _progress_bar(sum(len(c) for _, c in todo), progress) as bar:
            def finished(i: int, rows: list[dict]) -> None:
                nonlocal task_seconds
                frame = rows_frame(spec, rows, cols)
                write_chunk(frame, chunk_path(out, h, i, writer), stamp_of(h, chunks[i]), writer)
                frames[i] = frame
                task_seconds += sum(r["task_seconds"] for r in rows
                                    if math.isfinite(r["task_seconds"]))
                result.computed += 1
            result.failed_tasks = compute(client, spec, todo, estimate.limit, finished,
                                          bar.update, task=limited_chunk_rows, check=check,
                                          say=say)
        result.timings["compute_seconds"] = time.perf_counter() - t_submit
    finally:
        if own and client is not None:
            _close(client, cluster, at_once=stop.signum is not None)
    return task_seconds


def believed_chunks(spec: SweepSpec, out: Path, h: str, chunks, writer: str, say):
    """The frames of the chunk files that read and are what the plan expects
    (`sweep_chunks.read_chunk`), and the chunks left to compute; one line through ``say`` for
    each file found but not believed."""
    cols = columns(spec)
    frames: dict = {}
    todo = []
    folder = chunk_path(out, h, 0, writer).parent
    present = set(os.listdir(folder)) if folder.is_dir() else set()   # one listing, not a
    for i, c in enumerate(chunks):                                    # path and stat per chunk
        if chunk_name(i, writer) not in present:
            todo.append((i, c))
            continue
        path = folder / chunk_name(i, writer)
        try:
            frames[i] = rows_frame(spec, read_chunk(path, stamp_of(h, c), cols), cols)
        except ChunkMismatch as why:
            say(f"sweep: {path} is not chunk {i} of this sweep ({why}); computing it again")
            todo.append((i, c))
    return frames, todo


def _estimate(spec, frames, chunks, todo, workers, override) -> Estimate:
    """The `Estimate` before the tasks start: the cost measured on the rows already computed
    under this spec, else `bicycle_cost`."""
    measured = [t for f in frames.values() for t in f["task_seconds"] if math.isfinite(t)]
    cost = sum(measured) / len(measured) if measured else bicycle_cost(spec)
    return Estimate(spec.n_bicycles, len(chunks), len(todo), sum(len(c) for _, c in todo),
                    cost, len(measured), workers, bicycle_limit(bicycle_cost(spec), override))


def _close(client, cluster, at_once: bool = False) -> None:
    """Close the client and the local cluster, quietly (at an interrupt Dask's connections are
    torn down while it still logs about them). ``at_once``: the local workers are killed
    first, instead of each being given 5 s to finish the bicycle it is on (the chunks in
    flight are lost either way)."""
    import logging
    quiet = [logging.getLogger(n) for n in ("distributed", "tornado", "asyncio")]
    levels = [q.level for q in quiet]
    for q in quiet:
        q.setLevel(logging.CRITICAL + 1)
    try:
        if at_once and cluster is not None:
            _kill_workers(cluster)
        client.close()
        if cluster is not None:
            cluster.close()
    finally:
        for q, level in zip(quiet, levels):
            q.setLevel(level)


def _kill_workers(cluster) -> None:
    """SIGKILL to the worker processes of a local cluster, their nannies told not to restart
    them (a cluster of threads has none)."""
    import signal
    for nanny in list(getattr(cluster, "workers", {}).values()):
        process = getattr(getattr(nanny, "process", None), "process", None)
        pid = getattr(process, "pid", None)
        if not pid:
            continue
        nanny.auto_restart = False
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def merge(spec: SweepSpec, out: Path, frames, writer: str = "parquet") -> Path:
    """Every chunk's rows in one ``results.parquet`` (or ``results.csv``), sorted by
    bicycle."""
    import pandas as pd
    frame = rows_frame(spec, pd.concat(frames, ignore_index=True))
    return write_table(frame, out / f"results{WRITERS[writer]}", writer)
