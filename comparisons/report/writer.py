"""Write a `ComparisonResult` as a report folder: report.md, report.html, summary.json,
figures/*.png, data/<scenario>_<engine>.csv, timings.json.

The folder is assembled beside ``out`` and swapped in whole (`files.ReportFolder`): an
interrupted run leaves the previous report as it was, and files the harness did not write are
never touched. Everything but timings.json is a function of the inputs only, so two runs give
byte-identical reports.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

import numpy as np

from . import figures, frames, markdown
from .files import ReportFolder, write_csv, write_text
from .html import write_html


def _json_default(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.bool_):
        return bool(x)
    return str(x)


def write_report(result, out: Path, data: bool = True, html: bool = True,
                 progress: Callable[[str], None] = lambda s: None) -> Path:
    """Write the report of ``result`` into ``out`` (a folder); returns the path of report.md."""
    with ReportFolder(out) as folder:
        root = folder.path
        n_fig = 0
        for sec in result.sections:
            for fig in sec.figures:
                figures.save_figure(fig.kind, fig.data, root / "figures" / fig.name)
                n_fig += 1
        progress(f"  {n_fig} figures drawn")
        if data:
            for (label, name), run in sorted(result.runs.items()):
                if run.t.size:
                    write_csv(frames.run_frame(run), root / "data" / f"{name}_{label}.csv")
        write_text(root / "summary.json",
                   json.dumps(result.summary, indent=1, default=_json_default) + "\n")
        write_text(root / "report.md", markdown.render(result))
        if html:
            write_html(root / "report.md")
        write_text(root / "timings.json", json.dumps(result.timings, indent=1) + "\n")
    return Path(out) / "report.md"
