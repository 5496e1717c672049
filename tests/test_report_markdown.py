"""report.md's writer (comparisons/report/markdown.py): harness text reaches the markdown
escaped, the writer's own formatting still renders, and the verdict block names the bicycles.

Expectations come from the planted strings themselves (what the harness said must be what
the reader sees, character for character) and from CommonMark's rules as the project's own
renderer applies them (comparisons/report/html.py, markdown-it-py), never from the writer's
output. No report run: a hand-made summary (milliseconds), and the session's quick report.
"""

import html as htmllib
import re
from pathlib import Path
from types import SimpleNamespace

from comparisons.report import markdown
from comparisons.report.html import markdown_to_html
from comparisons.stages.results import Section

EXAMPLE = Path(__file__).resolve().parents[1] / "reports" / "example" / "report.md"

# harness text a run could produce: emphasis, code, link, autolink, entity, heading and list
# openers, a pipe in a table cell
EVIDENCE = "fit I2xx = 1.82 kg*m^2 (model 0.216 kg*m^2), a*b*c, x_1_ and _y_"
PLANTED = {
    "evidence": EVIDENCE,
    "reason": "engine `weird` failed: see [log](http://x) or <http://y> &amp; <b>bold</b>",
    "engine": "my_engine_",
    "cell": "max |C| = 2 | *not a column*",
    "heading": "Stability of __init__ (my*bike.toml)",
    "line": "# not a heading; 1. not a list",
}


def _summary() -> dict:
    p = PLANTED
    return {
        "passed": False, "engines": ["reference", p["engine"]],
        "dropped_engines": [{"engine": "bad`name", "reason": p["reason"]}],
        "comparisons": [{"quantity": "mass_matrix", "scenario": "s", "engines": ["reference",
                         p["engine"]], "max_error": 1.0, "tolerance": 1e-12, "passed": False,
                         "localized_to": p["cell"]}],
        "claims": [{"claim": "c", "engine": p["engine"], "verdict": "partly",
                    "evidence": p["evidence"]}],
        "faults": [{"fault": "f", "engine": p["engine"], "verdict": "missed",
                    "evidence": p["evidence"]}],
        "checks": [{"check": "k", "passed": False, "evidence": p["evidence"]}],
        "summary_table": [], "scenarios": [], "engine_runs": [], "initial_corrections": {},
        "expected_differences": [],
        "environment": {"machine": {"cpu": "cpu", "cores": 2, "platform": "x"},
                        "packages": {}, "solvers": {}, "steps": {}},
        "provenance": {"version": "0.1.0", "commit": "0123456789abcdef", "dirty": True,
                       "bicycles": [{"name": "thesis", "source": "reference_model/params_x/t.toml",
                                     "contact": "thesis", "comparisons": 3, "variants": []}]},
    }


def _rendered() -> tuple[str, str]:
    sec = Section(PLANTED["heading"])
    sec.heading(PLANTED["heading"])
    sec.table(("engine", "evidence"), [(PLANTED["engine"], PLANTED["cell"])])
    result = SimpleNamespace(summary=_summary(), sections=[sec],
                             localization=[("M", PLANTED["line"] + "\n" + PLANTED["evidence"])])
    text = markdown.render(result)
    return text, markdown_to_html(text, Path("."))


def _visible(fragment: str) -> str:
    """What a reader sees of an HTML fragment: tags dropped, entities resolved."""
    return htmllib.unescape(re.sub(r"<[^>]+>", "", fragment))


def _cells(page: str, tag: str = "td") -> list[str]:
    return [_visible(c) for c in re.findall(rf"<{tag}[^>]*>(.*?)</{tag}>", page, flags=re.S)]


def test_planted_harness_text_renders_literally():
    """Planted: ``cell`` back to escaping pipes only (as before) renders ``kg*m^2 (...)
    kg*m^2`` as italics and this fails; so does a ``_blocks`` that writes headings raw."""
    _, page = _rendered()
    cells = _cells(page)
    # the claim's evidence: the details of its matrix cell (after the verdict and "evidence")
    assert any(c.endswith(f"c / {PLANTED['engine']}: {EVIDENCE}") for c in cells), cells
    assert PLANTED["cell"] in cells                            # pipe and asterisks, one cell
    assert PLANTED["engine"] in _cells(page, "th")             # the claims matrix's column
    visible = _visible(page)
    for text in (PLANTED["evidence"], PLANTED["reason"], PLANTED["heading"], PLANTED["line"]):
        assert text in visible, text
    # nothing the harness said became markup: no emphasis at all (the writer writes none
    # here), no link or image, a heading only where the writer writes one
    assert "<em>" not in page and "<a href=\"http" not in page and "<img" not in page
    assert "<b>" not in page                                   # raw HTML stays text
    assert not re.search(r"<h\d[^>]*>[^<]*not a heading", page)
    assert re.findall(r"<ol[^>]*>", page) == ['<ol class="footnotes-list">']  # the cells' notes


def test_the_writers_own_formatting_still_renders():
    """The bold verdict and the code spans the writer means survive the escaping (planted:
    `inline` escaping a `Markdown` value too turns them into literal asterisks/backticks)."""
    text, page = _rendered()
    assert "<strong>Something is out of tolerance: 1 comparison(s) failed.</strong>" in page
    assert "<strong>Dropped</strong>" in page
    assert "<code>bad`name</code>" in page                     # a code span of a name with a `
    assert "<code>reference_model/params_x/t.toml</code>" in page
    assert "**" not in page and "\\*" not in _visible(page)


def test_every_table_row_keeps_its_columns():
    """A pipe in a cell is that cell's text, not a column boundary: every row of the
    rendered tables has as many cells as its header."""
    _, page = _rendered()
    for table in re.findall(r"<table>(.*?)</table>", page, flags=re.S):
        n = len(re.findall(r"<th[ >]", table))
        for row in re.findall(r"<tr>(.*?)</tr>", table, flags=re.S)[1:]:
            assert len(re.findall(r"<td[ >]", row)) == n


def test_no_emphasis_inside_the_example_reports_tables():
    """The committed example report: its table cells are harness text, none is emphasised
    (before the escaping, 12 fault-evidence cells were: ``kg*m^2 ... kg*m^2``)."""
    page = markdown_to_html(EXAMPLE.read_text(encoding="utf-8"), EXAMPLE.parent)
    cells = re.findall(r"<td[^>]*>(.*?)</td>", page, flags=re.S)
    assert cells and not [c for c in cells if "<em>" in c or "<strong>" in c]
    assert "kg*m^2" in _visible(page)


def test_the_verdict_block_names_every_bicycle_compared(quick_report):
    """The thesis run's verdict block (before the first section) names each built-in bicycle
    its comparisons ran on, with its parameter file and contact; the set and the counts are
    read here from summary.json's comparisons and reference_model.NAMED_MODELS. summary.json
    records the code's version (that of the installed distribution)."""
    import importlib.metadata
    from reference_model import NAMED_MODELS
    out, _, summary = quick_report
    verdict = (out / "report.md").read_text(encoding="utf-8").split("\n## ")[0]
    counts: dict[str, int] = {}
    for c in summary["comparisons"]:
        base = c["model"].split(" (")[0]
        counts[base] = counts.get(base, 0) + 1
    assert {"thesis", "thesis-disc", "benchmark"} <= set(counts)
    for name, n in counts.items():
        path, contact = NAMED_MODELS[name]
        line = next(ln for ln in verdict.splitlines() if ln.startswith(f"  - {name}: "))
        assert f"`reference_model/parameters/{Path(path).name}`" in line
        assert f"{contact} contact ({n} comparisons" in line
    assert summary["provenance"]["version"] == importlib.metadata.version("bicycle-xval")
    assert "bicycle-xval --version" in verdict
