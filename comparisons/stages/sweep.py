"""A sweep on Dask: chunks of bicycles as tasks, one Parquet file per chunk, resumable.

    result = run_sweep(spec, out_dir, workers=2)                  # a LocalCluster
    result = run_sweep(spec, out_dir, scheduler="tcp://host:8786")   # a running cluster

Layout of ``out_dir``::

    spec.json                        the spec and its hash (what the chunks belong to)
    chunks/<hash>/chunk-000000.parquet   one per chunk, rows sorted by bicycle
    results.parquet                  every row of the sweep, sorted by bicycle (when complete)

* **Chunks**: consecutive bicycle indices, sized so a task takes about ``TARGET_SECONDS``
  (1-10 s, from `COST`: per-bicycle seconds measured on the 2-core development machine), a
  pure function of the spec: the chunking is part of what the hash fixes.
* **Atomic and resumable**: each chunk file is written to a temporary name and renamed when
  complete (`files.atomic_path`); a rerun with the same spec finds the files under the
  same hash and computes only the missing chunks (an interrupted sweep loses the chunks in
  flight, nothing else).
* **Failures are rows**: an engine that raises on a bicycle is caught in the task
  (`sweep_task.bicycle_row`); a task that never returns (its worker died more often than
  Dask's ``distributed.scheduler.allowed-failures`` retries, or any other exception) is split
  into one task per bicycle, and a bicycle whose own task is lost again becomes a "failed" row
  naming the exception (the chunk's other bicycles keep their results). Delete that chunk's
  file to compute it again.
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

from .files import atomic_path, write_text
from .sweep_spec import SweepSpec, spec_hash
from .sweep_task import chunk_rows, columns, failed_row

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


def plan(spec: SweepSpec) -> list[tuple[int, ...]]:
    """The chunks: consecutive bicycle indices."""
    n, size = spec.n_bicycles, chunk_size(spec)
    return [tuple(range(s, min(s + size, n))) for s in range(0, n, size)]


def chunk_path(out: Path, h: str, i: int) -> Path:
    return Path(out) / "chunks" / h / f"chunk-{i:06d}.parquet"


def rows_frame(spec: SweepSpec, rows: list[dict]):
    """The rows as a DataFrame with fixed columns and dtypes (identical files for identical
    rows), sorted by bicycle."""
    import pandas as pd
    cols = columns(spec)
    frame = pd.DataFrame(rows, columns=cols).sort_values("bicycle", kind="stable")
    for c in cols:
        if c in ("bicycle", "seed"):
            frame[c] = frame[c].astype("uint64" if c == "seed" else "int64")
        elif c in ("terms_passed", "runs_confirmed"):
            frame[c] = frame[c].astype("boolean")
        elif c.startswith(("entry.", "run.")) or c in ("status", "failures", "localization"):
            frame[c] = frame[c].fillna("").astype(str)
        else:
            frame[c] = frame[c].astype("float64")
    return frame.reset_index(drop=True)


def write_parquet(frame, path: Path) -> Path:
    """One Parquet file, written atomically (a temporary name renamed when complete)."""
    with atomic_path(path, suffix=".parquet") as tmp:
        frame.to_parquet(tmp, index=False, engine="pyarrow", compression="zstd")
    return Path(path)


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
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:   # the worker processes start with Ctrl-C ignored (inherited): the client stops them
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=processes,
                               dashboard_address=None, silence_logs=40)
    finally:
        if main:
            signal.signal(signal.SIGINT, previous)
    return Client(cluster), cluster


def _progress_bar(total: int, enabled: bool):
    from tqdm import tqdm
    tty = sys.stderr.isatty()
    return tqdm(total=total, unit="bicycle", file=sys.stderr, disable=not enabled,
                mininterval=0.5 if tty else 15.0, dynamic_ncols=tty,
                desc="sweep")


def run_sweep(spec: SweepSpec, out: Path, *, scheduler: str | None = None,
              workers: int | None = None, processes: bool = True,
              progress: bool = True, client=None) -> SweepResult:
    """Compute every missing chunk of ``spec`` on Dask, then merge all rows into
    ``results.parquet`` (module docstring). ``client``: an existing Dask client to use (and
    leave open) instead of connecting to ``scheduler`` or starting a local cluster."""
    t0 = time.perf_counter()
    out = Path(out)
    h = spec_hash(spec)
    chunks = plan(spec)
    write_text(out / "spec.json", json.dumps({"hash": h, "chunk_size": chunk_size(spec),
                                              "spec": spec.as_json()}, indent=1) + "\n")
    todo = [(i, c) for i, c in enumerate(chunks) if not chunk_path(out, h, i).exists()]
    result = SweepResult(out, h, spec.n_bicycles, len(chunks), skipped=len(chunks) - len(todo))
    task_seconds = 0.0
    if todo:
        from distributed import as_completed
        own = client is None
        if own:
            client, cluster = _client(scheduler, workers, processes)
        try:
            result.timings["workers"] = len(client.scheduler_info(n_workers=-1)["workers"])
            t_submit = time.perf_counter()
            futures = {client.submit(chunk_rows, spec, c, key=f"sweep-{h}-{i:06d}", pure=False): (i, c)
                       for i, c in todo}
            done: dict[int, list[dict]] = {i: [] for i, _ in todo}    # rows so far per chunk
            left = {i: 1 for i, _ in todo}                            # tasks outstanding
            with _progress_bar(sum(len(c) for _, c in todo), progress) as bar:
                ac = as_completed(futures)
                for fut in ac:
                    i, c = futures.pop(fut)
                    left[i] -= 1
                    try:
                        done[i] += fut.result()
                    except Exception as exc:     # noqa: BLE001 -- a lost task is a row per bicycle
                        result.failed_tasks += 1
                        if len(c) > 1:           # isolate the bicycle(s) that lose the task
                            for k in c:
                                f = client.submit(chunk_rows, spec, (k,), pure=False,
                                                  key=f"sweep-{h}-{i:06d}-{k}")
                                futures[f] = (i, (k,))
                                ac.add(f)
                            left[i] += len(c)
                        else:
                            msg = f"task lost: {type(exc).__name__}: {' '.join(str(exc).split())}"
                            done[i] += [failed_row(spec, k, msg[:500]) for k in c]
                    fut.release()
                    if left[i] == 0:
                        rows = done.pop(i)
                        write_parquet(rows_frame(spec, rows), chunk_path(out, h, i))
                        task_seconds += sum(r["task_seconds"] for r in rows
                                            if math.isfinite(r["task_seconds"]))
                        result.computed += 1
                        bar.update(len(rows))
            result.timings["compute_seconds"] = time.perf_counter() - t_submit
        finally:
            if own:
                client.close()
                if cluster is not None:
                    cluster.close()
    result.timings["task_seconds"] = task_seconds
    result.results = merge(spec, out, h, len(chunks))
    result.seconds = time.perf_counter() - t0
    return result


def merge(spec: SweepSpec, out: Path, h: str, n_chunks: int) -> Path:
    """Every chunk's rows in one ``results.parquet``, sorted by bicycle."""
    import pandas as pd
    frames = [pd.read_parquet(chunk_path(out, h, i)) for i in range(n_chunks)]
    frame = rows_frame(spec, pd.concat(frames, ignore_index=True).to_dict("records"))
    return write_parquet(frame, out / "results.parquet")
