"""What every benchmark section shares: result rows and their formatting, the machine's facts
(CPU, package versions, the competition from other processes), the timing helpers and the
seeded states near the constraint manifold."""

from __future__ import annotations

import math
import os
import platform
import subprocess
import sys
import time
import timeit
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent   # the repository
SEED = 20240611
N_SINGLE = 256          # distinct states cycled through in the single-state timings
N_BATCH = 10_000

# targets from the issues, in seconds (None: informative only); "pin_rhs_ratio" is a ratio
TARGETS = {
    "cold_start": 15.0,
    "warm_load": 1.0,
    "fwd_acc_single": 20e-6,
    "fwd_acc_batch": 2e-6,
    "zigzag_id": 0.5,
    "forward_2pi": 2.0,
    "pin_rhs_ratio": 5.0,
    "cmd_run_quick": 8.0,
    "cmd_run_full": 25.0,
}


# -- result rows ------------------------------------------------------------------------

@dataclass
class Row:
    key: str
    quantity: str
    value: float | None            # seconds; a count (unit "count") or a ratio (unit "x")
    unit: str = "s"
    target: float | None = None    # seconds
    measured_text: str | None = None   # overrides the formatted value (e.g. "min / max")
    judged: float | None = None    # the value compared with the target (default: value)
    details: dict = field(default_factory=dict)
    vs_crba: bool = True           # a ratio to crba means something (not for whole commands)

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


def timed_import(name: str):
    """(module, seconds, whether it was already imported)."""
    already = name in sys.modules
    t0 = time.perf_counter()
    mod = __import__(name)
    return mod, time.perf_counter() - t0, already


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


