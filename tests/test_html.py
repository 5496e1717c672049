"""The report's HTML renderer (comparisons/report/html.py).

Expectations come from the markdown itself (GitHub's rules: `\\|` in a table cell is a pipe,
`**x**` is bold) and from the bytes of the image files the tests write, never from the
renderer's own output.
"""

import base64
import re
import struct
import zlib
from pathlib import Path

import pytest

from comparisons.report import html as report_html
from comparisons.report.html import markdown_to_html, write_html

EXAMPLE = Path(__file__).resolve().parents[1] / "reports" / "example" / "report.md"


def _png(path: Path) -> bytes:
    """A valid 1x1 PNG, built by hand (signature, IHDR, IDAT, IEND), written to ``path``."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    raw = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 1, 1, 8, 2, 0, 0, 0)) \
        + chunk(b"IDAT", zlib.compress(b"\x00\xff\x00\x00")) + chunk(b"IEND", b"")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(raw)
    return raw


REPORT = """# bicycle-xval report

**All judged comparisons within tolerance.** Engines: reference, pinocchio.

## The thesis's claims, engine by engine

| claim | engine | verdict | evidence |
|---|---|---|---|
| replay: the constraint error stays below 2e-3 | reference | reproduced | max \\|C\\| = 5.4e-10 (bound 2e-03) |
| stability: psi_dot(0) = 10 stabilises | pinocchio | not reproduced | \\|theta\\| never below 0.05 rad; `a \\| b` |

## Summary: quantity x engine pair

| quantity | engines | verdict |
|---|---|---|
| mass_matrix | reference vs pinocchio | pass |
| trajectory | reference vs exudyn-tree | reported |
| torques | reference vs pinocchio | FAIL (2 of 5) |

- stability-psid0: max \\|velocity constraint\\| 3.2e-01 -> 5.6e-17 m/s

### Terms

![mass matrix error](figures/m.png)

## Benchmark

### Terms

<script>alert(1)</script>
"""


def _ids(page: str) -> list[str]:
    return re.findall(r'<h[1-6][^>]*\bid="([^"]+)"', page)


def _toc_links(page: str) -> list[str]:
    nav = re.search(r'<nav class="toc".*?</nav>', page, re.S)
    assert nav, "no table of contents"
    return re.findall(r'href="#([^"]+)"', nav.group(0))


@pytest.fixture
def rendered(tmp_path):
    png = _png(tmp_path / "figures" / "m.png")
    return markdown_to_html(REPORT, tmp_path), png


def test_escaped_pipes_and_bold_leave_no_markdown_in_the_html(rendered):
    page, _ = rendered
    assert "\\|" not in page and "**" not in page
    assert "<strong>All judged comparisons within tolerance.</strong>" in page
    assert "max |C| = 5.4e-10" in page                 # table cell: escaped pipes are pipes
    assert "<code>a | b</code>" in page                 # also inside a code span in a cell
    assert "max |velocity constraint| 3.2e-01" in page  # and in a list item


def test_tables_are_real_tables_in_a_scrolling_wrapper(rendered):
    page, _ = rendered
    assert page.count('<div class="table-wrap">') == page.count("<table>") == 2
    assert "<th>claim</th>" in page and "<td>reference vs pinocchio</td>" in page
    assert "|---|" not in page


def test_verdict_cells_are_classed(rendered):
    page, _ = rendered
    assert '<td class="pass">pass</td>' in page
    assert '<td class="pass">reproduced</td>' in page
    assert '<td class="fail">not reproduced</td>' in page
    assert '<td class="fail">FAIL (2 of 5)</td>' in page
    assert '<td class="info">reported</td>' in page


def test_every_heading_has_an_anchor_and_the_toc_links_to_them(rendered):
    page, _ = rendered
    ids = _ids(page)
    headings = re.findall(r"<h[1-6]", page)
    assert len(ids) == len(headings) == 6, "an anchor on every heading"
    assert len(set(ids)) == len(ids), "two '### Terms' headings need distinct anchors"
    links = _toc_links(page)
    # h2 and h3 only (3 h2 + 2 h3 here), in document order, each pointing at an existing id
    assert links == [i for i in ids if i not in ids[:1]]
    assert set(links) <= set(ids)
    nav = re.search(r'<nav class="toc".*?</nav>', page, re.S).group(0)
    assert "The thesis&#x27;s claims, engine by engine" in nav and "#</a>" not in nav


def test_image_is_embedded_as_a_data_uri(rendered):
    page, png = rendered
    assert f'src="data:image/png;base64,{base64.b64encode(png).decode()}"' in page
    assert 'src="figures/' not in page and "missing-figure\"" not in page
    assert re.search(r'img \{[^}]*width: 100%', report_html.CSS), "figures at full width"


def test_image_name_with_space_and_accent_is_found(tmp_path):
    png = _png(tmp_path / "figures" / "ángulo de dirección.png")
    page = markdown_to_html("![steer](<figures/ángulo de dirección.png>)\n", tmp_path)
    assert base64.b64encode(png).decode() in page and "missing-figure\"" not in page


def test_missing_image_gives_a_visible_note_not_a_crash(tmp_path):
    page = markdown_to_html("# r\n\n![gone](figures/gone.png)\n\n![odd](notes.txt)\n", tmp_path)
    assert '<span class="missing-figure">missing figure figures/gone.png (file not found)' in page
    assert "unknown image type .txt" in page
    assert "<img" not in page


def test_raw_html_is_escaped(rendered):
    page, _ = rendered
    assert "<script>" not in page and "&lt;script&gt;alert(1)&lt;/script&gt;" in page


def test_write_html_writes_utf8_beside_the_markdown_atomically(tmp_path, monkeypatch):
    md = tmp_path / "report.md"
    md.write_text("# r\n\n## Größen\n\nsteer near ±π/2\n", encoding="utf-8")
    out = write_html(md)
    assert out == tmp_path / "report.html"
    assert "steer near ±π/2" in out.read_bytes().decode("utf-8")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.html", "report.md"]

    # a failure half-way through writing (a lone surrogate cannot be encoded in UTF-8, so
    # the encoder fails after the first part) leaves the previous page untouched and no
    # temporary file behind
    before = out.read_bytes()
    monkeypatch.setattr(report_html, "markdown_to_html",
                        lambda *a, **k: "<html>" + "x" * 100_000 + "\ud800</html>")
    with pytest.raises(UnicodeEncodeError):
        write_html(md)
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.html", "report.md"]


def test_write_html_names_a_missing_report(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such report"):
        write_html(tmp_path / "report.md")


def test_example_report_renders_clean():
    """The committed example report: no literal escapes, every TOC link lands, every figure
    it references is embedded."""
    markdown = EXAMPLE.read_text(encoding="utf-8")
    page = markdown_to_html(markdown, EXAMPLE.parent)
    assert "\\|" not in page and "**" not in page
    assert set(_toc_links(page)) <= set(_ids(page))
    n_figures = len(re.findall(r"!\[[^\]]*\]\(", markdown))
    assert page.count('src="data:image/png;base64,') == n_figures
    assert 'class="missing-figure"' not in page
