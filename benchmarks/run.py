"""Speed benchmarks of the reference model against the issue's targets, beside Pinocchio's crba.

    PYTHONPATH=. .venv/bin/python benchmarks/run.py [--quick] [--json PATH]

Measures, in one run on one machine: cold start (derivation + code generation + gcc, in a
subprocess with a fresh temporary cache), warm load from that cache, the single-state and
batched model calls, the zig-zag inverse dynamics, 2*pi s forward runs at rtol 1e-10, and, as
the yardstick, Pinocchio's ``crba`` and ``rnea`` on the same thesis tree (checked against the
reference mass matrix first). Prints an aligned table and writes the same numbers as JSON.

Exit status: 0 when the run completed (targets missed are reported, not failures), 2 when
Pinocchio's mass matrix or RNEA disagrees with the reference model (the yardstick is then
suspect), 1 on an error.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import platform
import signal
import subprocess
import sys
import tempfile
import threading
import time
import timeit
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # `python benchmarks/run.py` without PYTHONPATH (make bench)
    sys.path.insert(0, str(ROOT))

DEFAULT_JSON = Path(__file__).resolve().parent / "results.json"
SEED = 20240611
N_SINGLE = 256          # distinct states cycled through in the single-state timings
N_BATCH = 10_000
PIN_CHECK_STATES = 8
PIN_CHECK_RTOL = 1e-12
CHILD_TIMEOUT = 600.0   # s, for one cold-start subprocess

# targets from the issue, in seconds (None: informative only)
TARGETS = {
    "cold_start": 15.0,
    "warm_load": 1.0,
    "fwd_acc_single": 20e-6,
    "fwd_acc_batch": 2e-6,
    "zigzag_id": 0.5,
    "forward_2pi": 2.0,
}

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


# -- result rows ------------------------------------------------------------------------

@dataclass
class Row:
    key: str
    quantity: str
    value: float | None            # seconds, or a count when unit != "s"
    unit: str = "s"
    target: float | None = None    # seconds
    measured_text: str | None = None   # overrides the formatted value (e.g. "min / max")
    judged: float | None = None    # the value compared with the target (default: value)
    details: dict = field(default_factory=dict)

    @property
    def within(self) -> bool | None:
        if self.target is None:
            return None
        v = self.value if self.judged is None else self.judged
        return bool(v is not None and v <= self.target)


def fmt_time(s: float | None) -> str:
    if s is None or not math.isfinite(s):
        return "n/a"
    if s < 1e-3:
        return f"{s * 1e6:.3g} µs"
    if s < 1.0:
        return f"{s * 1e3:.3g} ms"
    return f"{s:.3g} s"


def fmt_ratio(r: float | None) -> str:
    if r is None:
        return "-"
    if r < 1000:
        return f"{r:.3g}x"
    return f"{r:.2e}x"


# -- environment ------------------------------------------------------------------------

def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown CPU"


def gcc_version() -> str:
    cc = os.environ.get("CC", "gcc")
    try:
        out = subprocess.run([cc, "-dumpfullversion"], capture_output=True, text=True, timeout=10)
        return f"{cc} {out.stdout.strip()}" if out.returncode == 0 else f"{cc} (version unknown)"
    except (OSError, subprocess.SubprocessError):
        return f"{cc} (not found)"


def machine_info() -> dict:
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    versions = {"python": sys.version.split()[0]}
    for pkg in ("numpy", "scipy", "sympy", "pin", "exudyn"):
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = "not installed"
    versions["cc"] = gcc_version()
    try:
        load = list(os.getloadavg())
    except (AttributeError, OSError):
        load = None
    return {"cpu": cpu_model(), "processor": platform.processor(), "cores": os.cpu_count(),
            "usable_cores": usable, "load_average_1_5_15min_at_start": load,
            "platform": platform.platform(terse=True), "versions": versions}


def machine_line(info: dict) -> str:
    v = info["versions"]
    pk = ", ".join(f"{k} {v[k]}" for k in ("numpy", "scipy", "sympy", "pin", "exudyn"))
    return (f"machine: {info['cpu']}, {info['cores']} cores ({info['usable_cores']} usable), "
            f"{info['platform']}; Python {v['python']}; {pk}; {v['cc']}")


class CpuMonitor:
    """CPU time the *other* processes of the machine used while this run was going on.

    /proc/stat gives the machine's busy time (steal listed apart: time the hypervisor gave to
    other guests); subtracting this process's and its children's own CPU time leaves the
    competition. Linux only; elsewhere `report()` returns None.
    """

    def __init__(self):
        self.start = self._sample()

    @staticmethod
    def _sample():
        try:
            fields = Path("/proc/stat").read_text().splitlines()[0].split()[1:]
        except (OSError, IndexError):
            return None
        j = [int(x) for x in fields[:8]]   # user nice system idle iowait irq softirq steal
        t = os.times()
        own = t.user + t.system + t.children_user + t.children_system
        return time.monotonic(), j[0] + j[1] + j[2] + j[5] + j[6], j[7], own

    def report(self) -> dict | None:
        end = self._sample()
        if self.start is None or end is None:
            return None
        hz = os.sysconf("SC_CLK_TCK")
        wall = end[0] - self.start[0]
        busy = (end[1] - self.start[1]) / hz
        steal = (end[2] - self.start[2]) / hz
        own = end[3] - self.start[3]
        return {"wall_s": wall, "own_cpu_s": own,
                "other_processes_cores": max(0.0, busy - own) / wall, "steal_cores": steal / wall}


def busy_warning(cpu: dict | None) -> str | None:
    """A warning when other processes (or other guests) took CPU during the run."""
    if cpu is None:
        return None
    if cpu["other_processes_cores"] > 0.25 or cpu["steal_cores"] > 0.1:
        return (f"WARNING: other processes used {cpu['other_processes_cores']:.2f} core(s) on "
                f"average during this run (hypervisor steal {cpu['steal_cores']:.2f}): the timings "
                "read high; rerun on a quiet machine.")
    return None


# -- timing helpers -----------------------------------------------------------------------

@dataclass
class Micro:
    """One micro-benchmark: fn(*args) for each args in args_list, `per` calls counted per args."""

    key: str
    quantity: str
    fn: object
    args_list: list
    per: int = 1
    target: float | None = None
    number: int = 1
    best: float = math.inf
    timer: timeit.Timer | None = None


def run_interleaved(micros: list[Micro], rounds: int, min_time: float) -> dict[str, float]:
    """Seconds per call of each micro-benchmark: the best of `rounds` samples of >= min_time
    each, the benchmarks interleaved round by round. On a shared machine the CPU comes and goes
    in phases of a second or so; interleaving gives every benchmark (and the crba yardstick)
    samples from the same quiet moments, and the minimum picks them."""
    for m in micros:
        def loop(fn=m.fn, args_list=m.args_list):
            for a in args_list:
                fn(*a)
        m.timer = timeit.Timer(loop)
        one = min(m.timer.repeat(repeat=3, number=1))  # warm-up and calibration
        m.number = max(1, math.ceil(min_time / max(one, 1e-9)))
    for _ in range(rounds):
        for m in micros:
            t = m.timer.timeit(m.number) / (m.number * len(m.args_list) * m.per)
            m.best = min(m.best, t)
    return {m.key: m.best for m in micros}


def best_wall(fn, repeat: int):
    """(best seconds, that call's result) of `repeat` calls of fn()."""
    best, out = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = fn()
        dt = time.perf_counter() - t0
        if dt < best:
            best, out = dt, res
    return best, out


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


# -- states ------------------------------------------------------------------------------

def random_states(model, n: int, rng: np.random.Generator):
    """n states near the constraint manifold: random theta, psi, gamma, position, yaw, eps and
    independent rates; beta from [rD]_z = 0 (batched Newton), dependent rates from D dq = 0."""
    from reference_model.model import DEP, IND
    q = np.zeros((n, 8))
    q[:, 0:2] = rng.uniform(-5.0, 5.0, (n, 2))                 # xc, yc
    q[:, 2] = rng.uniform(-np.pi, np.pi, n)                    # phi
    q[:, 3] = rng.uniform(-0.4, 0.4, n)                        # theta
    q[:, 4] = rng.uniform(-np.pi, np.pi, n)                    # psi
    q[:, 6] = rng.uniform(-0.6, 0.6, n)                        # gamma
    q[:, 7] = rng.uniform(-np.pi, np.pi, n)                    # eps
    zero = np.zeros_like(q)
    for _ in range(30):
        h = model.constraint_residual(q, zero)[:, 0]
        if np.max(np.abs(h)) < 1e-13:
            break
        q[:, 5] -= h / model.constraint_jacobian(q)[:, 0, 5]
    dq_ind = np.column_stack([rng.uniform(-1, 1, n), rng.uniform(1, 10, n), rng.uniform(-1, 1, n)])
    D = model.constraint_jacobian(q)
    dq = np.empty_like(q)
    dq[:, IND] = dq_ind
    rhs = -np.einsum("nij,nj->ni", D[:, :, IND], dq_ind)
    dq[:, DEP] = np.linalg.solve(D[:, :, DEP], rhs[:, :, None])[:, :, 0]
    T = rng.uniform(-1.0, 1.0, (n, 3))
    return q, dq, T


# -- 3. model calls ------------------------------------------------------------------------

def _reference_inverse_dynamics(model):
    from engines.reference import ReferenceEngine
    return ReferenceEngine(model).inverse_dynamics


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


def bench_pinocchio_forward(model, repeat: int) -> list[Row]:
    """stability-psid10 through the same solver on Pinocchio's terms (the adapter) and on the
    reference's generated code: what `bicycle-xval run` pays per engine run."""
    from engines import load_engine
    from reference_model.scenarios import SCENARIOS, run_forward
    sc = SCENARIOS["stability-psid10"]
    pin = load_engine("pinocchio", model)
    w_pin, t_pin = best_wall(lambda: pin.simulate(sc), repeat)
    w_ref, t_ref = best_wall(lambda: run_forward(model, sc), repeat)
    return [Row("psid10_reference", f"stability-psid10 forward run, reference ({t_ref.timing['nfev']} RHS)", w_ref),
            Row("psid10_pinocchio", f"stability-psid10 forward run, Pinocchio adapter ({t_pin.timing['nfev']} RHS)", w_pin)]


# -- 6. Pinocchio ----------------------------------------------------------------------------

def build_pinocchio(model):
    """The Pinocchio tree of the engines' adapter (engines/pinocchio.py; its joint order is
    asserted there and its terms are checked by tests/test_engine_conformance.py)."""
    from engines.pinocchio import build_pinocchio_model
    pm = build_pinocchio_model(model)
    return pm, pm.createData()


def check_pinocchio(pin, pm, pd, model, rng) -> dict:
    """Max relative errors of crba (symmetrised) and rnea against the reference model."""
    err_m = err_r = 0.0
    for _ in range(PIN_CHECK_STATES):
        q = rng.uniform(-np.pi, np.pi, 8)
        v = rng.uniform(-3, 3, 8)
        a = rng.uniform(-3, 3, 8)
        Mp = np.array(pin.crba(pm, pd, q))
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        Mr = model.mass_matrix(q)
        err_m = max(err_m, float(np.max(np.abs(Mp - Mr)) / np.max(np.abs(Mr))))
        tau_p = np.array(pin.rnea(pm, pd, q, v, a))
        tau_r = Mr @ a - model.Qv(q, v) - model.Qgrav(q)
        err_r = max(err_r, float(np.max(np.abs(tau_p - tau_r)) / np.max(np.abs(tau_r))))
    return {"states": PIN_CHECK_STATES, "rtol": PIN_CHECK_RTOL, "mass_matrix_max_rel_err": err_m,
            "rnea_max_rel_err": err_r, "ok": err_m <= PIN_CHECK_RTOL and err_r <= PIN_CHECK_RTOL}


def pinocchio_micros(pin, pm, pd, q, dq) -> list[Micro]:
    k = N_SINGLE
    acc = np.random.default_rng(SEED + 1).uniform(-1, 1, (k, 8))
    return [
        Micro("pin_crba", "Pinocchio crba, 1 state", pin.crba, [(pm, pd, q[i].copy()) for i in range(k)]),
        Micro("pin_rnea", "Pinocchio rnea, 1 state", pin.rnea,
              [(pm, pd, q[i].copy(), dq[i].copy(), acc[i]) for i in range(k)]),
    ]


# -- 7. imports ----------------------------------------------------------------------------

def timed_import(name: str):
    already = name in sys.modules
    t0 = time.perf_counter()
    mod = __import__(name)
    return mod, time.perf_counter() - t0, already


def bench_exudyn() -> list[Row]:
    exu, t_imp, already = timed_import("exudyn")
    t0 = time.perf_counter()
    sc = exu.SystemContainer()
    sc.AddSystem()
    t_sc = time.perf_counter() - t0
    return [Row("import_exudyn", "import exudyn (in-process" + (", already loaded)" if already else ")"),
                t_imp),
            Row("exudyn_system", "exu.SystemContainer() + AddSystem()", t_sc)]


# -- 8. Exudyn forward runs against the reference ---------------------------------------------

def bench_exudyn_scenarios(quick: bool) -> list[Row]:
    """Wall time of each forward scenario on thesis-disc (the contact both Exudyn builds
    realise): the reference (`run_forward`, default settings: Baumgarte, DOP853 rtol 1e-10)
    and Exudyn's tree and redundant builds at h = 1e-3, one run each, in the same process.
    Each wall time covers the whole call (initial projection, the replay's torque spline,
    building the Exudyn system, the run). The thesis-disc library is compiled into a fresh
    temporary cache (timed as a row), so the user's cache is not touched."""
    from engines import load_engine
    from reference_model import load_model
    from reference_model.scenarios import SCENARIOS, run_forward

    step = 1e-3
    names = ("stability-psid10",) if quick else (
        "replay", "stability-psid0", "stability-psid1", "stability-psid5", "stability-psid10")
    old = os.environ.get("BICYCLE_XVAL_CACHE")
    with tempfile.TemporaryDirectory(prefix="bicycle-xval-bench-disc-") as tmp:
        os.environ["BICYCLE_XVAL_CACHE"] = tmp
        try:
            t0 = time.perf_counter()
            disc = load_model("thesis-disc")
            t_load = time.perf_counter() - t0
        finally:
            if old is None:
                os.environ.pop("BICYCLE_XVAL_CACHE", None)
            else:
                os.environ["BICYCLE_XVAL_CACHE"] = old
    rows = [Row("exudyn_disc_load", "load_model('thesis-disc'), fresh temporary cache"
                + (" (compiled)" if disc.library.built_now else ""), t_load)]
    engines = {b: load_engine("exudyn", disc, build=b, step=step)
               for b in ("tree", "redundant")}
    for eng in engines.values():   # first-call costs (imports, symbolic machinery) not timed
        eng.simulate(SCENARIOS["stability-psid0"], t_end=0.05)
    for name in names:
        sc = SCENARIOS[name]
        t0 = time.perf_counter()
        ref = run_forward(disc, sc)
        t_ref = time.perf_counter() - t0
        rows.append(Row(f"exudyn_{name}_reference",
                        f"{name}, reference thesis-disc ({ref.status} at {ref.t_end:.2f} s)", t_ref,
                        details={"status": ref.status, "t_end": ref.t_end,
                                 "wall_per_simulated_s": t_ref / ref.t_end,
                                 "settings": {k: ref.settings[k] for k in
                                              ("integrator", "rtol", "atol", "constraints")},
                                 "nfev": ref.timing["nfev"]}))
        for build, eng in engines.items():
            t0 = time.perf_counter()
            tr = eng.simulate(sc)
            wall = time.perf_counter() - t0
            ratio = wall / t_ref
            # the runs may end at different times (a fall): also per simulated second
            ratio_sim = (wall / tr.t_end) / (t_ref / ref.t_end)
            rows.append(Row(
                f"exudyn_{name}_{build}",
                f"  Exudyn {build}, h = {step:g} ({tr.status} at {tr.t_end:.2f} s): "
                f"{ratio:.3g}x ref, {ratio_sim:.3g}x per simulated s", wall,
                details={"status": tr.status, "t_end": tr.t_end, "ratio_to_reference": ratio,
                         "wall_per_simulated_s": wall / tr.t_end,
                         "ratio_to_reference_per_simulated_s": ratio_sim,
                         "steps": tr.timing["steps"],
                         "newton_iterations": tr.timing.get("newton_iterations"),
                         "solve_s": tr.timing["solve_seconds"],
                         "build_s": tr.timing["build_seconds"],
                         "solver": tr.settings["solver_type"],
                         "spectral_radius": tr.settings["spectral_radius"]}))
    return rows


# -- output ------------------------------------------------------------------------------------

def table(rows: list[Row], crba: float) -> str:
    head = ("quantity", "measured", "target", "within target", "ratio to crba")
    body = []
    for r in rows:
        if r.unit == "s":
            measured = r.measured_text or fmt_time(r.value)
            ratio = fmt_ratio(r.value / crba) if r.value is not None else "-"
        else:
            measured, ratio = f"{r.value:.0f}", "-"
        target = f"<= {fmt_time(r.target)}" if r.target is not None else "-"
        within = {None: "-", True: "yes", False: "NO"}[r.within]
        body.append((r.quantity, measured, target, within, ratio))
    widths = [max(len(x[i]) for x in [head, *body]) for i in range(len(head))]

    def line(cells):
        return "  ".join([cells[0].ljust(widths[0]), *(c.rjust(w) for c, w in zip(cells[1:], widths[1:]))])
    sep = "  ".join("-" * w for w in widths)
    return "\n".join([line(head), sep, *(line(b) for b in body)])


def to_json(rows, crba, info, check, args) -> dict:
    return {
        "schema": "bicycle-xval-benchmarks/1",
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "quick": args.quick,
        "seed": SEED,
        "machine": info,
        "pinocchio_check": check,
        "crba_seconds": crba,
        "results": [{"key": r.key, "quantity": r.quantity.strip(), "value": r.value, "unit": r.unit,
                     "target": r.target, "within_target": r.within,
                     "ratio_to_crba": (r.value / crba) if r.unit == "s" and r.value is not None else None,
                     "details": r.details} for r in rows],
    }


def mismatch_banner(check: dict) -> str:
    return ("!" * 78 + "\n!!! PINOCCHIO DOES NOT MATCH THE REFERENCE MODEL: crba max rel. error "
            f"{check['mass_matrix_max_rel_err']:.3e}, rnea {check['rnea_max_rel_err']:.3e} "
            f"(tolerance {check['rtol']:.0e}).\n!!! The crba ratios below use a suspect yardstick; "
            "report this to the lead.\n" + "!" * 78)


# -- main ----------------------------------------------------------------------------------------

def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repetitions (about a third of the time)")
    ap.add_argument("--json", type=Path, default=DEFAULT_JSON, help=f"JSON output (default {DEFAULT_JSON})")
    args = ap.parse_args(argv)
    if threading.current_thread() is threading.main_thread():
        # `kill` unwinds like Ctrl-C, so the temporary caches are removed and the child killed
        signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    rounds, min_time, cold_runs, wall_repeat = (8, 0.02, 1, 2) if args.quick else (20, 0.02, 2, 3)
    t_start = time.perf_counter()
    info = machine_info()
    print(machine_line(info), flush=True)
    monitor = CpuMonitor()

    def progress(msg):
        print(f"[{time.perf_counter() - t_start:5.1f} s] {msg}", file=sys.stderr, flush=True)

    progress(f"cold start x{cold_runs} and warm load in subprocesses (temporary caches)...")
    with tempfile.TemporaryDirectory(prefix="bicycle-xval-bench-") as tmp:
        rows, cache = bench_load(Path(tmp), cold_runs)
        model, load_rows = bench_inprocess_load(cache)
    rows += load_rows

    pin, t_pin_import, pin_already = timed_import("pinocchio")
    pm, pd = build_pinocchio(model)
    rng = np.random.default_rng(SEED)
    check = check_pinocchio(pin, pm, pd, model, rng)
    if not check["ok"]:
        print(mismatch_banner(check), flush=True)
        print(mismatch_banner(check), file=sys.stderr, flush=True)

    progress("model calls and Pinocchio crba/rnea...")
    q, dq, T = random_states(model, N_BATCH, rng)
    pin_micro = pinocchio_micros(pin, pm, pd, q, dq)
    model_micro = model_micros(model, q, dq, T)
    run_interleaved(pin_micro + model_micro, rounds, min_time)
    rows += [Row(m.key, m.quantity, m.best, target=m.target,
                 details={"samples": rounds, "calls_per_sample": m.number * len(m.args_list) * m.per})
             for m in model_micro]
    progress("zig-zag inverse dynamics...")
    rows += bench_zigzag(model, wall_repeat)
    progress("forward runs...")
    rows += bench_forward(model, wall_repeat)
    progress("linearization of the benchmark bicycle; Pinocchio-adapter forward run...")
    rows += bench_linearization(wall_repeat)
    rows += bench_pinocchio_forward(model, wall_repeat)
    rows += [Row(m.key, m.quantity, m.best) for m in pin_micro]
    rows.append(Row("import_pinocchio", "import pinocchio (in-process"
                    + (", already loaded)" if pin_already else ")"), t_pin_import))
    rows += bench_exudyn()
    progress("Exudyn forward runs against the reference (thesis-disc)...")
    rows += bench_exudyn_scenarios(args.quick)
    crba = pin_micro[0].best

    print()
    print(table(rows, crba))
    print(f"\nPinocchio check ({check['states']} random states): crba (symmetrised) vs mass_matrix "
          f"max rel. error {check['mass_matrix_max_rel_err']:.2e}, rnea vs M a - Qv - Qgrav "
          f"{check['rnea_max_rel_err']:.2e} -> {'OK' if check['ok'] else 'MISMATCH'} "
          f"(tolerance {check['rtol']:.0e})")
    print(f"Notes: call timings: best of {rounds} interleaved samples of >= {min_time * 1e3:.0f} ms "
          f"each; single-state calls cycle over {N_SINGLE} seeded\n       random states near the "
          "constraint manifold.\n"
          "       'per RHS' = simulate's wall time / nfev (DOP853 steps and the dense output at the "
          "629 samples included).\n"
          "       Cold start: derivation + code generation + gcc in a fresh temporary cache; "
          "'within' is judged on the max.")
    info["cpu_competition"] = cpu = monitor.report()
    if cpu is not None:
        print(f"Other processes used {cpu['other_processes_cores']:.2f} core(s) on average during "
              f"the run (steal {cpu['steal_cores']:.2f}).")
    busy = busy_warning(cpu)
    if busy:
        print(busy)
    if not check["ok"]:
        print(mismatch_banner(check))
    out = to_json(rows, crba, info, check, args)
    out["total_seconds"] = time.perf_counter() - t_start
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(out, indent=1) + "\n")
    print(f"\nwrote {args.json} (total {out['total_seconds']:.1f} s)")
    return 0 if check["ok"] else 2


if __name__ == "__main__":
    sys.exit(main())
