"""Speed benchmarks of the reference model against the issues' targets, beside Pinocchio's crba.

    .venv/bin/python benchmarks/run.py [--quick] [--json PATH]      (make bench)

Measures, in one run on one machine: cold start (derivation + code generation + gcc, in a
subprocess with a fresh temporary cache), warm load from that cache, the single-state and
batched model calls, the constrained right-hand side of a forward run on the reference and on
the Pinocchio adapter, the zig-zag inverse dynamics, 2*pi s forward runs at rtol 1e-10, and, as
the yardstick, Pinocchio's ``crba`` and ``rnea`` on the same thesis tree (checked against the
reference mass matrix first), and the whole commands ``bicycle-xval run --quick`` and ``run``
(`command_timings.py`; ``--no-commands`` skips them). Prints an aligned table and writes the same numbers as JSON.

The sections live beside this entry point: `common.py` (rows, machine facts, timing helpers,
states), `reference_timings.py` (the reference model's calls and runs), `engine_timings.py`
(Pinocchio and Exudyn), `output.py` (table, JSON).

Exit status: 0 when the run completed (targets missed are reported, not failures), 2 when
Pinocchio's mass matrix or RNEA disagrees with the reference model (the yardstick is then
suspect), 1 on an error.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # `python benchmarks/run.py` without PYTHONPATH (make bench)
    sys.path.insert(0, str(ROOT))

from benchmarks.command_timings import bench_commands  # noqa: E402
from benchmarks.common import (N_BATCH, N_SINGLE, SEED, TARGETS, CpuMonitor, Row,  # noqa: E402
                               busy_warning, machine_info, machine_line, random_states,
                               run_interleaved, timed_import)
from benchmarks.engine_timings import (bench_exudyn, bench_exudyn_scenarios,  # noqa: E402
                                       bench_pinocchio_forward, build_pinocchio, check_pinocchio,
                                       pinocchio_micros)
from benchmarks.output import mismatch_banner, table, to_json  # noqa: E402
from benchmarks.reference_timings import (bench_forward, bench_inprocess_load,  # noqa: E402
                                          bench_linearization, bench_load, bench_zigzag,
                                          model_micros)

DEFAULT_JSON = Path(__file__).resolve().parent / "results.json"


def rhs_rows(micros: dict, rounds: int) -> list[Row]:
    """The Pinocchio adapter's constrained right-hand side beside the reference's (same states,
    same interleaved rounds), with its ratios to the reference, to crba and to rnea."""
    pin_rhs, ref_rhs = micros["pin_adapter_rhs"].best, micros["rhs_single"].best
    crba, rnea = micros["pin_crba"].best, micros["pin_rnea"].best
    ratio = pin_rhs / ref_rhs
    return [
        Row("pin_adapter_rhs", f"Pinocchio adapter constrained RHS, 1 state ({ratio:.3g}x the "
            f"reference's RHS, {pin_rhs / rnea:.3g}x rnea)", pin_rhs,
            details={"samples": rounds, "reference_rhs_s": ref_rhs, "ratio_to_reference_rhs": ratio,
                     "ratio_to_crba": pin_rhs / crba, "ratio_to_rnea": pin_rhs / rnea}),
        Row("pin_rhs_ratio", "  Pinocchio adapter RHS / reference RHS (same run, same states)", ratio,
            unit="x", target=TARGETS["pin_rhs_ratio"]),
    ]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repetitions (about a third of the time)")
    ap.add_argument("--no-commands", action="store_true",
                    help="skip the whole-command timings of bicycle-xval run (about a minute)")
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

    progress("model calls, Pinocchio crba/rnea and the adapter's right-hand side...")
    q, dq, T = random_states(model, N_BATCH, rng)
    pin_micro = pinocchio_micros(pin, pm, pd, model, q, dq, T)
    model_micro = model_micros(model, q, dq, T)
    run_interleaved(pin_micro + model_micro, rounds, min_time)
    micros = {m.key: m for m in pin_micro + model_micro}
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
    rows += rhs_rows(micros, rounds)
    rows += [Row(m.key, m.quantity, m.best) for m in pin_micro if m.key != "pin_adapter_rhs"]
    rows.append(Row("import_pinocchio", "import pinocchio (in-process"
                    + (", already loaded)" if pin_already else ")"), t_pin_import))
    rows += bench_exudyn()
    progress("Exudyn forward runs against the reference (thesis-disc)...")
    rows += bench_exudyn_scenarios(args.quick)
    if not args.no_commands:
        progress("whole commands: bicycle-xval run --quick and run (fresh processes)...")
        rows += bench_commands(1 if args.quick else 2, progress)
    crba = micros["pin_crba"].best

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
    partial = args.json.with_name(args.json.name + ".partial")   # never a half-written file
    partial.write_text(json.dumps(out, indent=1) + "\n")
    os.replace(partial, args.json)
    print(f"\nwrote {args.json} (total {out['total_seconds']:.1f} s)")
    return 0 if check["ok"] else 2


if __name__ == "__main__":
    sys.exit(main())
