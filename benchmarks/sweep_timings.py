"""Timings of `bicycle-xval sweep` (issue 16): a script, not a timed test.

    PYTHONPATH=. .venv/bin/python benchmarks/sweep_timings.py [--n 200] [--n-large 1000]
                                                              [--no-runs] [--json FILE]

1. Cost per bicycle for each check set and engine, in this process (warm: the generated code
   loaded once), on seeded samples of the benchmark bicycle within +-20 %: terms (one engine
   at a time, 8 states), eigen (weave and capsize speeds), runs (4 forward runs of 5 s per
   engine: 0.9 and 1.1 x each critical speed).
2. Scaling: the same terms+eigen sweep of ``--n`` bicycles on a LocalCluster of 1 then 2
   worker processes (fresh output folders, cluster start-up excluded: the time from the first
   submission to the last chunk written); the speed-up, and the scheduler's overhead per task
   = (1-worker wall time - the tasks' own time) / tasks, against the mean task time.
3. ``--n-large`` bicycles (terms+eigen, +-20 % around the benchmark bicycle, 2 workers), the
   whole command's wall time (cluster start-up and the merge included).
4. The projection to 10^4 bicycles on 1, 16 and 256 cores from the measured per-bicycle cost
   (1 worker) and the measured 2-worker utilisation (the fraction of the wall time the workers
   spent in tasks), assuming dedicated cores (tasks that do not slow each other down).

The load average of the machine is printed with the numbers: the development machine is a
shared 2-core one, and another process's work lowers the 2-worker speed-up.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from comparisons.stages.sweep import plan, run_sweep  # noqa: E402
from comparisons.stages.sweep_spec import make_spec  # noqa: E402
from comparisons.stages.sweep_task import bicycle_row  # noqa: E402
from reference_model import load_model  # noqa: E402

SPREAD = 20.0
SEED = 16


def per_bicycle(base, runs: bool) -> dict:
    out = {}
    bicycle_row(make_spec(base, sample=1, spread=SPREAD, seed=SEED, engines=("pinocchio",),
                          checks=("terms", "eigen")), 0)        # warm-up: loads and imports
    for name, engines, checks, n in (("terms, pinocchio", ("pinocchio",), ("terms",), 20),
                                     ("terms, exudyn", ("exudyn",), ("terms",), 20),
                                     ("eigen", ("pinocchio",), ("eigen",), 20)):
        spec = make_spec(base, sample=n, spread=SPREAD, seed=SEED, engines=engines, checks=checks)
        t = time.perf_counter()
        for k in range(n):
            bicycle_row(spec, k)
        out[name] = (time.perf_counter() - t) / n
    if runs:
        from comparisons.judgments.eigenvalues import critical_speeds
        from comparisons.stages.runs import SETUPS
        from comparisons.stages.stability import SPEED_RANGE, judge_run, run_speeds
        from comparisons.stages.sweep_spec import sample_parameters
        from comparisons.stages.sweep_task import _scenario, _template
        from engines import load_engine
        spec = make_spec(base, sample=1, spread=SPREAD, seed=SEED, checks=("eigen", "runs"))
        model = _template("disc").with_params(sample_parameters(spec, 0))
        w, c = critical_speeds(model, np.array(SPEED_RANGE))
        for label in ("reference", "pinocchio", "exudyn-tree"):
            setup = SETUPS[label]
            t = time.perf_counter()
            for mode, _, v in run_speeds({"weave": w, "capsize": c}):
                traj = load_engine(setup.engine, model, **dict(setup.options)).simulate(
                    _scenario(model, v))
                judge_run(model, mode, v, traj)
            out[f"runs, {label} (4 runs of 5 s, judged)"] = time.perf_counter() - t
        out["all runs of one bicycle (3 engines)"] = sum(
            v for k, v in out.items() if k.startswith("runs,"))
    return out


def sweep_wall(base, n: int, workers: int) -> dict:
    spec = make_spec(base, sample=n, spread=SPREAD, seed=SEED, checks=("terms", "eigen"))
    with tempfile.TemporaryDirectory() as d:
        t = time.perf_counter()
        res = run_sweep(spec, Path(d), workers=workers, progress=False)
        total = time.perf_counter() - t
    tasks = len(plan(spec))
    return {"bicycles": n, "workers": workers, "tasks": tasks,
            "compute_seconds": res.timings["compute_seconds"],
            "task_seconds": res.timings["task_seconds"], "total_seconds": total,
            "failed_tasks": res.failed_tasks}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--n-large", type=int, default=1000)
    ap.add_argument("--no-runs", action="store_true")
    ap.add_argument("--json", type=Path, default=None)
    a = ap.parse_args(argv)
    base = load_model("benchmark").params
    rec = {"loadavg_start": os.getloadavg(), "cpus": os.cpu_count()}
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    rec["per_bicycle"] = per_bicycle(base, not a.no_runs)
    print("\n1. cost per bicycle (warm, one process)")
    for k, v in rec["per_bicycle"].items():
        print(f"   {k:52s} {v * 1e3:9.1f} ms")
    one, two = sweep_wall(base, a.n, 1), sweep_wall(base, a.n, 2)
    rec["scaling"] = [one, two]
    speedup = one["compute_seconds"] / two["compute_seconds"]
    overhead = (one["compute_seconds"] - one["task_seconds"]) / one["tasks"]
    mean_task = one["task_seconds"] / one["tasks"]
    rec.update(speedup=speedup, overhead_per_task=overhead, mean_task_seconds=mean_task)
    print(f"\n2. scaling, {a.n} bicycles terms+eigen in {one['tasks']} tasks "
          f"(load average now {os.getloadavg()[0]:.2f})")
    print(f"   1 worker  {one['compute_seconds']:7.2f} s (tasks' own time {one['task_seconds']:.2f} s)")
    print(f"   2 workers {two['compute_seconds']:7.2f} s (tasks' own time {two['task_seconds']:.2f} s)")
    util = two["task_seconds"] / (2 * two["compute_seconds"])
    rec["utilization_2"] = util
    print(f"   speed-up {speedup:.2f}x (target >= 1.8x); the 2 workers were busy {100 * util:.0f} % "
          "of the wall time (tasks' own time / (2 x wall)): a speed-up below that comes from "
          "the tasks running slower side by side (other processes, memory bandwidth)")
    print(f"   scheduler overhead per task {overhead * 1e3:.1f} ms = {100 * overhead / mean_task:.1f} % "
          f"of the mean task {mean_task:.2f} s (target < 5 %)")
    if a.n_large:
        big = sweep_wall(base, a.n_large, 2)
        rec["large"] = big
        print(f"\n3. {a.n_large} bicycles terms+eigen, 2 workers: {big['total_seconds']:.1f} s "
              f"whole command (target 600 s for 1000); load average {os.getloadavg()[0]:.2f}")
    c = one["task_seconds"] / a.n
    eff = util      # the scheduler's share; on dedicated cores the tasks do not slow each other
    rec["projection"] = {}
    print(f"\n4. projection, 10^4 bicycles (terms+eigen {c * 1e3:.0f} ms/bicycle"
          + (f"; with runs {rec['per_bicycle']['all runs of one bicycle (3 engines)']:.1f} s/bicycle"
             if not a.no_runs else "") + f"; worker utilisation {eff:.2f} as measured at 2; dedicated cores assumed)")
    for cores in (1, 16, 256):
        te = 1e4 * c / (cores * (1 if cores == 1 else eff))
        line = f"   {cores:4d} cores: terms+eigen {te / 60:8.1f} min"
        if not a.no_runs:
            r = rec["per_bicycle"]["all runs of one bicycle (3 engines)"] + c
            tr = 1e4 * r / (cores * (1 if cores == 1 else eff))
            line += f", +runs {tr / 3600:7.2f} h"
            rec["projection"][cores] = {"terms_eigen_s": te, "with_runs_s": tr}
        else:
            rec["projection"][cores] = {"terms_eigen_s": te}
        print(line)
    if a.json:
        from comparisons.stages.files import write_text
        write_text(a.json, json.dumps(rec, indent=1, default=float) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
