"""Whole commands, timed as a user runs them: ``bicycle-xval run --quick`` and the full
``bicycle-xval run`` (what ``make report`` runs after its install step), each in a fresh
process writing into a temporary folder, warm code cache. The issue's targets: 8 s and 25 s.

Each command is run ``repeat`` times and the best wall time is kept (the host is shared: the
best is the one least disturbed); the stage CPU seconds come from the report's
``timings.json`` of the same run.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.common import ROOT, TARGETS, Row

COMMANDS = {   # key -> (arguments of `bicycle-xval`, what the row says)
    "cmd_run_quick": (["run", "--quick"], "bicycle-xval run --quick (whole command, warm cache)"),
    "cmd_run_full": (["run"], "bicycle-xval run, every section = make report (warm cache)"),
}


def _once(args: list[str], out: Path) -> tuple[float, float]:
    """(wall seconds, stage CPU seconds) of one run of ``bicycle-xval ARGS --out OUT``."""
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "comparisons.cli", *args, "--out", str(out)],
                          cwd=ROOT, capture_output=True, text=True)   # CSVs and HTML as make report
    wall = time.perf_counter() - t0
    if proc.returncode not in (0, 1):   # 1: a check did not hold, still a complete run
        raise RuntimeError(f"bicycle-xval {' '.join(args)} exited {proc.returncode}: "
                           f"{proc.stderr.strip().splitlines()[-1:]}")
    stages = json.loads((out / "timings.json").read_text())["stages"]
    return wall, float(sum(stages.values()))


def bench_commands(repeat: int, progress=lambda s: None) -> list[Row]:
    rows = []
    with tempfile.TemporaryDirectory(prefix="bicycle-xval-bench-run-") as tmp:
        for key, (args, what) in COMMANDS.items():
            runs = []
            for i in range(repeat):
                progress(f"{what}: run {i + 1} of {repeat}")
                runs.append(_once(args, Path(tmp) / f"{key}-{i}"))
            wall, cpu = min(runs)
            rows.append(Row(key, what, wall, target=TARGETS.get(key),
                            measured_text=f"{wall:.1f} s (max {max(r[0] for r in runs):.1f} s)",
                            vs_crba=False,
                            details={"walls_s": [r[0] for r in runs],
                                     "stage_cpu_s": [r[1] for r in runs]}))
    return rows
