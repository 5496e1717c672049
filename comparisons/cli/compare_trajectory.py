"""``bicycle-xval compare-trajectory``: a run made in any tool, judged like a built-in engine's.

    bicycle-xval compare-trajectory --scenario stability-psid5 --csv theirs.csv [--label mine]
                                    [--json OUT]

The CSV has the documented columns (README, "Command line"): ``t`` [s], the eight coordinates
``xc, yc, phi, theta, psi, beta, gamma, eps`` [m, rad] and their rates ``d_<name>``; for an
inverse scenario also ``Mdir, Mped, Mvue`` [N m] (and ``lambda_1..lambda_5`` if known).
Accelerations and other columns are ignored. The verdicts are the built-in engines': error of
all eight coordinates against time up to the meaningful horizon with the coordinate that
diverges first, the constraint residual measured by the reference model, the torques of an
inverse scenario, and the thesis's claims that depend on this scenario alone.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from engines.runs import Run
from reference_model import COORDINATES, TORQUE_NAMES

from ..stages.files import write_text
from .errors import EXIT_FAIL, EXIT_OK, UsageError

STATE_COLUMNS = ("t",) + COORDINATES + tuple(f"d_{c}" for c in COORDINATES)


def add_compare_trajectory_parser(sub) -> None:
    s = sub.add_parser("compare-trajectory",
                       help="judge a scenario run made in any tool (a CSV) like a built-in engine")
    s.add_argument("--scenario", required=True, help="the scenario the CSV ran (see 'scenarios')")
    s.add_argument("--csv", required=True, type=Path, help="the run: documented columns")
    s.add_argument("--label", default=None, help="the engine's name in the output [file stem]")
    s.add_argument("--json", type=Path, default=None, help="also write the verdicts as JSON")
    from .tolerance_option import add_tolerances_argument
    add_tolerances_argument(s)
    s.set_defaults(func=cmd_compare_trajectory)


def _unique_columns(path: Path) -> None:
    """A column named twice is refused (pandas would read the first and rename the second)."""
    import csv
    with open(path, newline="", encoding="utf-8-sig", errors="replace") as f:
        header = next(csv.reader(f), [])
    names = [h.strip() for h in header]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise UsageError(f"--csv {path}: column(s) {', '.join(twice)} appear more than once in "
                         "the header; keep one of each")


def _numbers(frame, need: list[str], path: Path) -> np.ndarray:
    """The columns ``need`` as floats, or a `UsageError` naming the first cell that is not a
    number (its column, its row in the file, its text)."""
    import pandas as pd
    for c in need:
        values = pd.to_numeric(frame[c], errors="coerce")
        bad = np.flatnonzero(values.isna().to_numpy() & frame[c].notna().to_numpy())
        if bad.size:
            k = int(bad[0])
            raise UsageError(f"--csv {path}: column {c}, row {k + 2}: {str(frame[c].iloc[k])!r} "
                             "is not a number (write numbers with a decimal point, no "
                             "thousands separators)")
        frame[c] = values
    return frame[need].to_numpy(dtype=float)


def read_run(path: Path, scenario, label: str) -> Run:
    """The CSV as a `Run`, or a `UsageError` naming the problem and the fix (one line)."""
    import pandas as pd
    if not path.is_file():
        raise UsageError(f"--csv: no file {str(path)!r}")
    try:
        frame = pd.read_csv(path)
    except (ValueError, UnicodeDecodeError, pd.errors.ParserError) as exc:
        raise UsageError(f"--csv {path}: not a readable CSV ({' '.join(str(exc).split())})") from None
    _unique_columns(path)
    need = list(STATE_COLUMNS) + (list(TORQUE_NAMES) if scenario.kind == "inverse" else [])
    missing = [c for c in need if c not in frame.columns]
    if missing:
        raise UsageError(f"--csv {path}: missing column(s) {', '.join(missing[:6])}"
                         f"{' ...' if len(missing) > 6 else ''}; the columns are t, the eight "
                         "coordinates, d_<coordinate> (and Mdir, Mped, Mvue for an inverse scenario)")
    data = _numbers(frame, need, path)
    if len(data) < 2:
        raise UsageError(f"--csv {path}: {len(data)} row(s); a run needs at least two samples")
    nan_rows, nan_cols = np.nonzero(~np.isfinite(data))
    if nan_rows.size:
        raise UsageError(f"--csv {path}: NaN or infinite value in column {need[nan_cols[0]]} at "
                         f"row {nan_rows[0] + 2} (t = {data[nan_rows[0], 0]:g}); write only finite "
                         "samples (end the file where the run ended)")
    t = data[:, 0]
    if np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise UsageError(f"--csv {path}: t is not increasing at row {k + 3} ({t[k]:g} then "
                         f"{t[k + 1]:g} s); sort the samples by time, no repeats")
    if t[-1] > 50 * max(scenario.duration, 1e-9):
        raise UsageError(f"--csv {path}: t ends at {t[-1]:g} but {scenario.name} lasts "
                         f"{scenario.duration:.3g} s: is t in milliseconds? write t in seconds")
    if abs(t[0] - scenario.t[0]) > 1e-9 + 1e-6 * scenario.duration:
        raise UsageError(f"--csv {path}: t starts at {t[0]:g} s but {scenario.name} starts at "
                         f"{scenario.t[0]:g} s")
    q, dq = data[:, 1:9], data[:, 9:17]
    T = data[:, 17:20] if scenario.kind == "inverse" else None
    lam = None
    if scenario.kind == "inverse" and all(f"lambda_{k}" in frame.columns for k in range(1, 6)):
        lam = frame[[f"lambda_{k}" for k in range(1, 6)]].to_numpy(dtype=float)
    status, how = run_status(scenario, t, q)
    return Run(label, scenario.name, scenario.model, scenario.kind, status,
               f"read from {path.name} ({len(t)} samples to {t[-1]:g} s{how})", 0.0, t, q, dq,
               T, lam)


#: the status of a CSV that ends before its scenario without a fall: its run did not cover the
#: span the verdicts judge, so what depends on that span is 'not assessed' (as the claims treat
#: a run that failed), never a fall
ENDED_EARLY = "failed"


def run_status(scenario, t, q) -> tuple[str, str]:
    """(status, what it means) of a run read from a file: 'completed' when it reaches the
    scenario's end, 'fell' when it ends with |theta| at the fall limit (the solvers' default,
    `reference_model.solvers.DEFAULT_FALL_LIMIT`, to 1e-3 relative), else `ENDED_EARLY`."""
    from reference_model.solvers import DEFAULT_FALL_LIMIT
    if t[-1] >= scenario.t[-1] - 1e-9:
        return "completed", ""
    lean = abs(float(q[-1, 3]))
    if lean >= DEFAULT_FALL_LIMIT * (1 - 1e-3):
        return "fell", f"; |theta| = {lean:.3g} rad at its end: a fall"
    return ENDED_EARLY, (f"; it ends before the scenario's {scenario.t[-1]:g} s with |theta| = "
                         f"{lean:.3g} rad, below the fall limit {DEFAULT_FALL_LIMIT:g} rad: not a "
                         "fall, and what needs the rest of the run is not assessed")


def _not_assessed_beyond(comps: list, run: Run, horizon: float) -> None:
    """A trajectory comparison of a run that ends early, before the meaningful horizon, and did
    not fall: not assessed (it compared only the start). Rows are frozen: replaced in place."""
    if run.status != ENDED_EARLY or run.t_end >= horizon - 1e-9:
        return
    for i, c in enumerate(comps):
        if c["quantity"] == "trajectory":
            comps[i] = c.replace(passed=None, verdict="not assessed",
                                 why=f"the run ends at {run.t_end:g} s, before the meaningful "
                                     f"horizon {horizon:.2f} s, without a fall")


def cmd_compare_trajectory(args) -> int:
    from reference_model import load_model
    from reference_model.scenarios import get_scenario

    from ..judgments.claims import CLAIMS, judge_claims
    from ..judgments.convergence import reference_horizon
    from ..judgments.scenario_compare import compare_constraints, compare_forward, compare_inverse
    from ..stages.runs import run_one, setup_of
    from .tolerance_option import tolerances_from

    sc = get_scenario(args.scenario)
    label = args.label or args.csv.stem
    theirs = read_run(args.csv, sc, label)
    model = load_model(sc.model)
    tols = tolerances_from(args)
    ref = run_one(setup_of("reference"), sc.name)
    comps = []
    if sc.kind == "inverse":
        if theirs.lam is None:
            theirs.lam = np.full_like(ref.lam, np.nan)
        n = min(len(ref.t), len(theirs.t))
        if len(ref.t) != len(theirs.t) or np.abs(ref.t[:n] - theirs.t[:n]).max() > 1e-9:
            raise UsageError(f"--csv {args.csv}: an inverse scenario is compared sample by sample; "
                             f"write its {len(ref.t)} samples on the scenario's grid")
        comps += [c for c in compare_inverse(ref, theirs, tols)
                  if not (c["quantity"] == "multipliers" and np.isnan(theirs.lam).all())]
    else:
        hor = reference_horizon(model, sc)
        comps += compare_forward(model, ref, theirs, hor, tols, judged_by="trajectory_conformance")[0]
        _not_assessed_beyond(comps, theirs, hor.t)
        comps.append(compare_constraints(model, theirs, tols))
    runs = {("reference", sc.name): ref, (label, sc.name): theirs}
    if sc.name == "replay":
        runs[("reference", "zigzag")] = run_one(setup_of("reference"), "zigzag")
    own = {c.id for c in CLAIMS if set(c.scenarios) <= {sc.name, "zigzag"}}
    claims = [c for c in judge_claims(runs, [label], load_model("thesis"), [sc.name])
              if c["verdict"] != "not assessed" or c["claim_id"] in own]   # not: needing others
    print(f"{label} on {sc.name} ({theirs.message}) against the reference ({model.name}):")
    for c in comps:
        verdict = c.get("verdict") or ("reported" if c["passed"] is None else
                                       ("pass" if c["passed"] else "FAIL"))
        tol = "-" if c.get("tolerance") is None else f"{c['tolerance']:.0e}"
        err = "-" if c.get("max_error") is None else f"{c['max_error']:.2e}"
        print(f"  {c['quantity']:20s} {err:>9s} (tolerance {tol}) {verdict:8s} "
              f"{c.get('localized_to', '')}" + (f"; {c['why']}" if c.get("why") else ""))
    for c in claims:
        print(f"  claim {c['claim_id']}: {c['verdict']}: {c['evidence']}")
    if args.json is not None:
        write_text(args.json, json.dumps({"scenario": sc.name, "engine": label,
                                          "comparisons": [dict(c) for c in comps],
                                          "claims": claims},
                                         indent=1, default=float) + "\n")
    return EXIT_FAIL if any(c["passed"] is False for c in comps) else EXIT_OK
