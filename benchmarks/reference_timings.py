"""Timings of the reference model itself: cold start and warm load (in subprocesses), its
single-state and batched calls, the constrained right-hand side a forward run evaluates, the
zig-zag inverse dynamics, forward runs and the benchmark bicycle's linearisation."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.common import (N_BATCH, N_SINGLE, ROOT, SEED, TARGETS, Micro, Row, best_wall,
                               fmt_time)

CHILD_TIMEOUT = 600.0   # s, for one cold-start subprocess

_CHILD = r"""
import json, sys, time
t0 = time.perf_counter()
import reference_model
t1 = time.perf_counter()
model = reference_model.load_model("thesis")
t2 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "load_s": t2 - t1, "built_now": model.library.built_now,
                  "build_s": model.library.build_seconds, "library": str(model.library.path)}))
"""


# -- 1-2. cold start and warm load in subprocesses --------------------------------------------

def run_child(cache: Path) -> dict:
    env = dict(os.environ)
    env["BICYCLE_XVAL_CACHE"] = str(cache)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-c", _CHILD], env=env, cwd=ROOT, capture_output=True,
                         text=True, timeout=CHILD_TIMEOUT)
    wall = time.perf_counter() - t0
    if res.returncode != 0:
        raise RuntimeError(f"benchmark subprocess failed (exit {res.returncode}):\n{res.stderr[-3000:]}")
    out = json.loads(res.stdout.strip().splitlines()[-1])
    out["process_s"] = wall
    return out


def bench_load(tmp: Path, cold_runs: int) -> tuple[list[Row], Path]:
    """Cold starts (each with a fresh cache folder), then a warm subprocess on the last one."""
    colds = []
    for i in range(cold_runs):
        cache = tmp / f"cold-{i}"
        r = run_child(cache)
        if not r["built_now"]:
            raise RuntimeError(f"cold-start run {i} did not build (cache {cache} was not fresh?)")
        colds.append(r)
    warm = run_child(cache)
    if warm["built_now"]:
        raise RuntimeError("the warm subprocess rebuilt the library: the cache was not reused")
    loads = [r["load_s"] for r in colds]
    imports = [r["import_s"] for r in colds + [warm]]
    rows = [
        Row("import_reference_model", "import reference_model (subprocess, min)", min(imports),
            details={"runs_s": imports}),
        Row("cold_start", f"cold start load_model('thesis') (min / max of {cold_runs})", max(loads),
            target=TARGETS["cold_start"],
            measured_text=f"{fmt_time(min(loads))} / {fmt_time(max(loads))}",
            details={"runs_s": loads, "min_s": min(loads), "max_s": max(loads),
                     "build_s": [r["build_s"] for r in colds],
                     "process_s": [r["process_s"] for r in colds]}),
        Row("warm_load", "warm load_model('thesis') (subprocess)", warm["load_s"],
            target=TARGETS["warm_load"]),
        Row("warm_process", "warm process total (python start+import+load)", warm["process_s"]),
    ]
    return rows, cache


def bench_inprocess_load(cache: Path):
    """First in-process load (from the filled temporary cache) and a second, memoised one."""
    from reference_model import load_model
    old = os.environ.get("BICYCLE_XVAL_CACHE")
    os.environ["BICYCLE_XVAL_CACHE"] = str(cache)
    try:
        t0 = time.perf_counter()
        model = load_model("thesis")
        t1 = time.perf_counter()
        load_model("thesis")
        t2 = time.perf_counter()
    finally:
        if old is None:
            os.environ.pop("BICYCLE_XVAL_CACHE", None)
        else:
            os.environ["BICYCLE_XVAL_CACHE"] = old
    rows = [
        Row("inproc_first_load", "in-process load_model, first (warm cache)", t1 - t0,
            details={"built_now": model.library.built_now}),
        Row("inproc_second_load", "in-process load_model, again (memoised)", t2 - t1),
    ]
    return model, rows


# -- 3. model calls ------------------------------------------------------------------------

def _reference_inverse_dynamics(model):
    from engines.reference import ReferenceEngine
    return ReferenceEngine(model).inverse_dynamics


def rhs_args(q, dq, T) -> list[tuple]:
    """Single-state arguments of ``forward`` as a forward run passes them (Baumgarte as the
    thesis, the default of every forward scenario)."""
    from reference_model.solvers import THESIS_BAUMGARTE
    return [(q[i].copy(), dq[i].copy(), T[i].copy(), THESIS_BAUMGARTE) for i in range(N_SINGLE)]


def model_micros(model, q, dq, T) -> list[Micro]:
    k = N_SINGLE
    single3 = [(q[i].copy(), dq[i].copy(), T[i].copy()) for i in range(k)]
    single1 = [(q[i].copy(),) for i in range(k)]
    acc = np.random.default_rng(SEED + 1).uniform(-1, 1, (k, 8))  # same as the rnea timing's
    single_id = [(q[i].copy(), dq[i].copy(), acc[i]) for i in range(k)]
    Q, DQ, TT = (np.ascontiguousarray(a[:N_BATCH]) for a in (q, dq, T))
    return [
        Micro("fwd_acc_single", "forward_acceleration, 1 state", model.forward_acceleration, single3,
              target=TARGETS["fwd_acc_single"]),
        Micro("fwd_acc_batch", "forward_acceleration, batch 1e4 (per state)",
              model.forward_acceleration, [(Q, DQ, TT)], per=N_BATCH, target=TARGETS["fwd_acc_batch"]),
        Micro("rhs_single", "constrained RHS forward(q, dq, T, Baumgarte), 1 state", model.forward,
              rhs_args(q, dq, T)),
        Micro("mass_matrix_single", "mass_matrix, 1 state", model.mass_matrix, single1),
        Micro("mass_matrix_batch", "mass_matrix, batch 1e4 (per state)", model.mass_matrix, [(Q,)],
              per=N_BATCH),
        Micro("generalized_forces_single", "generalized_forces, 1 state", model.generalized_forces,
              single3),
        Micro("constraint_jacobian_single", "constraint_jacobian, 1 state", model.constraint_jacobian,
              single1),
        Micro("inverse_dynamics_single", "inverse dynamics M ddq - Qv - Qgrav, 1 state (vs rnea)",
              _reference_inverse_dynamics(model), single_id),
        Micro("harness_overhead", "(timing loop overhead per call, empty fn)", lambda *a: None, single3),
    ]


# -- 4. zig-zag inverse dynamics ----------------------------------------------------------

def bench_zigzag(model, repeat: int) -> list[Row]:
    from reference_model.scenarios import SCENARIOS, run_inverse
    from reference_model.solvers import inverse_dynamics, inverse_kinematics
    sc = SCENARIOS["zigzag"]
    total, ident = best_wall(lambda: run_inverse(model, sc), repeat)
    ik, motion = best_wall(lambda: inverse_kinematics(model, sc.motion, sc.t), repeat)
    solve, _ = best_wall(lambda: inverse_dynamics(model, motion), repeat)
    n = sc.t.size
    return [
        Row("zigzag_id", f"zig-zag inverse dynamics, {n} samples (run_inverse)", total,
            target=TARGETS["zigzag_id"], details={"samples": n, "ik_nfev": ident.motion.info["nfev"]}),
        Row("zigzag_ik", "  of which inverse kinematics (DOP853 1e-12)", ik,
            details={"nfev": motion.info["nfev"]}),
        Row("zigzag_solves", f"  of which {n} 13x13 solves", solve, details={"per_sample_s": solve / n}),
    ]


# -- 5. forward runs ------------------------------------------------------------------------

def _forward_rows(key: str, label: str, wall: float, traj, target=None, extra=None) -> list[Row]:
    nfev = traj.timing["nfev"]
    det = {"status": traj.status, "t_end": traj.t_end, "nfev": nfev,
           "simulate_wall_s": traj.timing["wall_seconds"], "constraints": traj.settings["constraints"],
           "max_abs_constraint_residual": float(np.max(np.abs(traj.C))), **(extra or {})}
    return [
        Row(key, f"{label}: wall ({traj.status} at t = {traj.t_end:.3f} s)", wall, target=target,
            details=det),
        Row(f"{key}_nfev", f"  {label}: RHS evaluations", float(nfev), unit="count"),
        Row(f"{key}_per_rhs", f"  {label}: wall per RHS evaluation", traj.timing["wall_seconds"] / nfev),
    ]


def bench_forward(model, repeat: int) -> list[Row]:
    from reference_model.scenarios import SCENARIOS, run_forward
    from reference_model.solvers import simulate
    t_eval = 0.01 * np.arange(629)
    q0 = np.zeros(8)
    dq0 = np.array([1.6, 0, 0, 0, 5.0, 0, 0, 5.0])      # straight rolling, R psi_dot = 1.6 m/s
    torques = np.array([0.0, 0.65536, 0.0])              # pedal torque cv v^2 R balancing the drag
    rows = []
    for constraints, key, label, target in (
            ("baumgarte", "forward_2pi", "2pi s straight rolling, Baumgarte", TARGETS["forward_2pi"]),
            ("none", "forward_2pi_exact", "2pi s straight rolling, exact acc.", None)):
        wall, traj = best_wall(lambda: simulate(model, q0, dq0, t_eval, torques, rtol=1e-10,
                                                constraints=constraints), repeat)
        rows += _forward_rows(key, label, wall, traj, target)
    sc = SCENARIOS["replay"]
    wall, traj = best_wall(lambda: run_forward(model, sc, rtol=1e-10), repeat)
    rows += _forward_rows("replay", "replay scenario (incl. zig-zag torque spline)", wall, traj,
                          extra={"scenario": "replay"})
    rows.append(Row("replay_simulate", "  replay: simulate only", traj.timing["wall_seconds"]))
    return rows


def bench_linearization(repeat: int) -> list[Row]:
    """The benchmark bicycle's eigenvalues over the CLI's default grid (1001 speeds) and its
    weave and capsize speeds, warm (the generated numpy code loaded once)."""
    from reference_model import load_model
    from reference_model.linearize import capsize_speed, eigenvalues, weave_speed
    bench = load_model("benchmark")
    speeds = 0.01 * np.arange(1001)
    eigenvalues(bench, 1.0)   # load the generated code
    wall, _ = best_wall(lambda: eigenvalues(bench, speeds), repeat)
    crit, _ = best_wall(lambda: (weave_speed(bench), capsize_speed(bench)), repeat)
    return [Row("eigenvalues_1001", "benchmark eigenvalues at 1001 speeds (0:10:0.01)", wall),
            Row("critical_speeds", "benchmark weave + capsize speeds (brentq)", crit)]


