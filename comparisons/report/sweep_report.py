"""The summary of a sweep (`bicycle-xval sweep`): ``report.md`` and two maps beside the Parquet.

* **Agreement map** (``agreement.png``): each bicycle's largest normalised term error (all
  engines, all compared quantities; `stages.sweep_task`) against each varied parameter, log
  scale, with the tolerance band's upper edge (the largest tolerance in
  `judgments/tolerances.toml`) drawn; bicycles that failed are marked at the top.
* **Stability map** (``stability.png``): weave and capsize speeds against each varied
  parameter, as the bicycle literature draws them; a bicycle whose nonlinear runs confirmed
  both predictions is a filled marker, one whose runs contradicted the linear prediction a
  red cross, no runs an open marker.
* **Disagreeing bicycles**: every bicycle not "agree" with its parameters, its failures and
  its localization (worst entries and the diagnose module's best explanation).

For a random sample the maps' axes are the derived benchmark quantities (trail, head angle,
wheelbase) where the base has them, else the first three varied parameters.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .figures import _plt, png_bytes
from .markdown import cell, inline
from ..stages.files import write_bytes, write_text

MAX_LISTED = 200      # disagreeing bicycles listed in report.md (all are in the results file)


def _axes(spec, frame) -> list[tuple[str, str]]:
    """(column, label) of the maps' x axes."""
    if spec.grids:
        return [(f"vary.{g.name}", g.name) for g in spec.grids][:3]
    derived = [(n, n) for n in ("trail", "head_angle", "wheelbase")
               if n in frame and frame[n].notna().any()]
    return derived or [(f"vary.{n}", n) for n in spec.varied[:3]]


def agreement_figure(frame, axes, tolerance: float):
    plt = _plt()
    fig, panels = plt.subplots(1, len(axes), figsize=(4.2 * len(axes), 3.4), squeeze=False)
    err = frame["max_error"].to_numpy(dtype=float)
    bad = frame["status"].isin(["failed", "invalid"]).to_numpy()
    top = max(np.nanmax(np.r_[err[np.isfinite(err)], tolerance]) * 10, tolerance * 10)
    for ax, (col, label) in zip(panels[0], axes):
        x = frame[col].to_numpy(dtype=float)
        ok = np.isfinite(err) & ~bad
        ax.semilogy(x[ok], np.maximum(err[ok], 1e-18), "o", ms=3, color="tab:blue",
                    label="max normalised error")
        if bad.any():
            ax.semilogy(x[bad], np.full(bad.sum(), top), "x", color="tab:red", label="failed")
        ax.axhline(tolerance, color="k", lw=0.8, ls="--", label="largest tolerance")
        ax.set_xlabel(label)
        ax.set_ylabel("max error (all engines, terms)")
    panels[0][0].legend(fontsize=7)
    fig.suptitle("agreement of the engines with the reference across the sweep", fontsize=9)
    return fig


def stability_figure(frame, axes):
    plt = _plt()
    fig, panels = plt.subplots(1, len(axes), figsize=(4.2 * len(axes), 3.4), squeeze=False)
    conf = frame["runs_confirmed"] if "runs_confirmed" in frame else None
    for ax, (col, label) in zip(panels[0], axes):
        x = frame[col].to_numpy(dtype=float)
        for mode, color in (("weave", "tab:blue"), ("capsize", "tab:orange")):
            y = frame[f"{mode}_speed"].to_numpy(dtype=float)
            if conf is None:
                ax.plot(x, y, "o", ms=3, mfc="none", color=color, label=f"{mode} speed")
                continue
            c = conf.to_numpy(dtype=object)
            yes = np.array([v is True for v in c])
            no = np.array([v is False for v in c])
            none = ~(yes | no)
            ax.plot(x[yes], y[yes], "o", ms=3, color=color, label=f"{mode} (runs confirm)")
            ax.plot(x[none], y[none], "o", ms=3, mfc="none", color=color, label=f"{mode} (no runs)")
            if no.any():
                ax.plot(x[no], y[no], "x", ms=5, color="tab:red", label=f"{mode} (runs contradict)")
        ax.set_xlabel(label)
        ax.set_ylabel("critical speed [m/s]")
    panels[0][0].legend(fontsize=7)
    fig.suptitle("weave and capsize speeds across the sweep", fontsize=9)
    return fig


def summarize(frame) -> dict:
    counts = frame["status"].value_counts().to_dict()
    return {k: int(counts.get(k, 0)) for k in ("agree", "disagree", "failed", "invalid")}


def write_sweep_report(spec, result) -> dict:
    """Write report.md, agreement.png and stability.png into the sweep's folder; the counts
    by status and the report's path."""
    from ..stages.sweep import rows_frame
    from ..stages.sweep_chunks import read_table
    out = Path(result.out)
    frame = rows_frame(spec, read_table(result.results)[0])   # Parquet or CSV, same dtypes
    counts = summarize(frame)
    axes = _axes(spec, frame)
    lines = [f"# Sweep {result.hash}: {spec.n_bicycles} bicycles around "
             f"{inline(spec.base_name)}", ""]
    how = (", ".join(g.text() for g in spec.grids) if spec.grids else
           f"{spec.sample} random bicycles within +-{spec.spread:g} % (seed {spec.seed}; "
           "inertias congruence-scaled, physical by construction)")
    lines += [f"Bicycles: {inline(how)}. Contact {spec.contact}. Engines "
              f"{inline(', '.join(spec.engines))} against the reference; checks {', '.join(spec.checks)}; {spec.n_states} random "
              "states per bicycle for the terms, judged by the tolerances of "
              f"{inline(spec.tolerances.source or 'the packaged tolerances.toml')} (their "
              "values are in `spec.json` and the hash).", "",
              f"**{counts['agree']} agree, {counts['disagree']} disagree, {counts['failed']} "
              f"failed, {counts['invalid']} invalid.** Every row: `{Path(result.results).name}` (columns: "
              "`comparisons/stages/sweep_task.py`).", ""]
    times = frame["task_seconds"].to_numpy(dtype=float)
    if np.isfinite(times).any():
        lines += [f"Time per bicycle on its worker: median {np.nanmedian(times):.3f} s, max "
                  f"{np.nanmax(times):.3f} s; total {np.nansum(times):.1f} s of work.", ""]
    if "terms" in spec.checks and axes:
        tol = max(t.tolerance for t in spec.tolerances.values())
        write_bytes(out / "agreement.png", png_bytes(agreement_figure(frame, axes, tol)))
        lines += ["## Agreement map", "", "![agreement](agreement.png)", ""]
    if "eigen" in spec.checks and axes:
        write_bytes(out / "stability.png", png_bytes(stability_figure(frame, axes)))
        lines += ["## Stability map", "", "![stability](stability.png)", ""]
        if "runs_confirmed" in frame:
            rc = frame["runs_confirmed"]
            lines += [f"Nonlinear runs: {int((rc == True).sum())} bicycles confirm the linear "  # noqa: E712
                      f"prediction on every engine, {int((rc == False).sum())} contradict it.",  # noqa: E712
                      ""]
    bad = frame[frame["status"] != "agree"]
    lines += ["## Bicycles where something disagrees or failed", ""]
    if bad.empty:
        lines += ["None.", ""]
    else:
        cols = [c for c, _ in axes]
        lines += ["| bicycle | " + " | ".join(n for _, n in axes) + " | status | failures | "
                  "localization |", "|---" * (len(cols) + 4) + "|"]
        for _, r in bad.head(MAX_LISTED).iterrows():
            vals = " | ".join("" if not math.isfinite(float(r[c])) else f"{float(r[c]):.6g}"
                              for c in cols)
            loc = r["localization"] if "localization" in r else ""
            lines.append(f"| {cell(r['bicycle'])} | {vals} | {cell(r['status'])} | "
                         f"{cell(r['failures'] or '')} | {cell(loc or '')} |")
        if len(bad) > MAX_LISTED:
            lines += ["", f"... and {len(bad) - MAX_LISTED} more in {Path(result.results).name}."]
        lines.append("")
    path = write_text(out / "report.md", "\n".join(lines))
    return {**counts, "report": path}

