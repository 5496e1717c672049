"""Write a `ComparisonResult` as a report folder: report.md, report.html, summary.json,
figures/*.png, data/<scenario>_<engine>.csv, timings.json.

The folder is assembled beside ``out`` and swapped in whole (`files.ReportFolder`): an
interrupted run leaves the previous report as it was, and files the harness did not write are
never touched. Everything but timings.json is a function of the inputs only, so two runs give
byte-identical reports, with one stated exception: the soft-contact study's cost of each
engine's settings (run time per simulated second, measured; in its section, its ranking and
summary.json's ``soft_contact_ranking``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

import numpy as np

from ..judgments.rows import Comparison
from . import figures, frames, markdown
from .figure_cache import FigureCache
from .matrix import claims_matrix, term_matrix
from ..stages.files import ReportFolder, write_bytes, write_csv, write_text
from .html import write_html


def _json_default(x):
    """summary.json's values that json does not know: a comparison row (`Comparison`, turned
    into its dict here, at the writer), numpy scalars."""
    if isinstance(x, Comparison):
        return x.as_dict()
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.bool_):
        return bool(x)
    return str(x)


def with_matrices(summary: dict) -> dict:
    """``summary`` with its two matrices added under keys of their own (``claims_matrix``,
    ``term_matrix``: rows, columns, cells; `matrix.Matrix.as_dict`): the rows they are built
    from stay as they were, under their own keys."""
    return {**summary, "claims_matrix": claims_matrix(summary["claims"]).as_dict(),
            "term_matrix": term_matrix(summary["comparisons"], summary["engines"]).as_dict()}


def draw_figures(result, workers: int | None = None, cache: FigureCache | None = None,
                 progress: Callable[[str], None] = lambda s: None) -> tuple[dict[str, bytes], int]:
    """Every figure of ``result`` as PNG bytes, and how many were drawn: those ``cache`` holds
    (`figure_cache`: same drawing code, same data) are read back, the others drawn in worker
    processes (matplotlib draws on one core; the figures are independent) and stored."""
    from ..stages.pool import Task, run_tasks
    figs = [f for sec in result.sections for f in sec.figures]
    held: dict[str, bytes] = {}
    keys: dict[str, str] = {}
    if cache is not None:
        try:
            held, keys = cache.read_back(figs)
        except OSError as exc:
            progress(f"  the figure cache {cache.root} cannot be read ({exc}): every figure is "
                     "drawn")
            cache = None
    todo = [f for f in figs if f.name not in held]
    tasks = [Task(f.name, figures.draw_png, (f.kind, f.data), 1.0, f"figure {f.name}") for f in todo]
    done = run_tasks(tasks, workers, warm=("matplotlib.pyplot",)) if tasks else {}
    failed = [f"{k}: {r.error}" for k, r in done.items() if r.error]
    if failed:
        raise RuntimeError(f"drawing a figure failed: {failed[0]}")
    drawn = {f.name: done[f.name].value for f in todo}
    if cache is not None and drawn:
        try:
            cache.store(keys, drawn)
        except OSError as exc:
            progress(f"  the figure cache {cache.root} cannot be written ({exc}): figures are "
                     "drawn every run")
    pngs = {**held, **drawn}
    return {f.name: pngs[f.name] for f in figs}, len(todo)


def write_report(result, out: Path, data: bool = True, html: bool = True,
                 progress: Callable[[str], None] = lambda s: None, force: bool = False,
                 figure_cache: FigureCache | None = None) -> Path:
    """Write the report of ``result`` into ``out`` (a folder); returns the path of report.md.
    A non-empty ``out`` without an earlier report is refused unless ``force``
    (`files.ReportFolder`). ``figure_cache``: where drawn figures are kept between runs (None:
    every figure is drawn, nothing stored)."""
    pngs, drawn = draw_figures(result, result.options.workers, figure_cache, progress)
    policy = result.summary.get("figures", "all")
    kept = len(pngs) - drawn
    progress(f"  {len(pngs)} figure(s): {drawn} drawn"
             + (f", {kept} unchanged since an earlier run (figure cache {figure_cache.root})"
                if kept else "")
             + ("" if policy == "all" else f" (--figures {policy})"))
    with ReportFolder(out, force) as folder:
        root = folder.path
        for name, png in pngs.items():
            write_bytes(root / "figures" / name, png)
        if data:
            for (label, name), run in sorted(result.runs.items()):
                if run.t.size:
                    write_csv(frames.run_frame(run), root / "data" / f"{name}_{label}.csv")
        write_text(root / "summary.json",
                   json.dumps(with_matrices(result.summary), indent=1, default=_json_default)
                   + "\n")
        write_text(root / "report.md", markdown.render(result))
        if html:
            write_html(root / "report.md")
        write_text(root / "timings.json", json.dumps(result.timings, indent=1) + "\n")
    return Path(out) / "report.md"
