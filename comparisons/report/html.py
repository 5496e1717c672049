"""report.md -> a self-contained report.html (figures embedded as base64 PNG, inline CSS).

The report's markdown uses a small subset (headings, paragraphs, bullet lists, pipe tables,
images, `code`, **bold**, links), so a converter of ~100 lines does it without a dependency;
the output opens offline, can be mailed as one file and attached to a CI run.
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path

CSS = """
body { font: 14px/1.45 system-ui, sans-serif; max-width: 1200px; margin: 2em auto; padding: 0 1em; color: #222; }
h1 { border-bottom: 2px solid #333; } h2 { border-bottom: 1px solid #aaa; margin-top: 2em; }
table { border-collapse: collapse; margin: .8em 0; font-size: 13px; }
th, td { border: 1px solid #ccc; padding: 3px 7px; text-align: left; vertical-align: top; }
th { background: #f0f0f0; } tr:nth-child(even) td { background: #fafafa; }
td.pass, td.ok { background: #e3f4e3 !important; } td.fail { background: #f8d7d7 !important; font-weight: bold; }
td.partly, td.info { background: #fff4d6 !important; }
code { background: #f3f3f3; padding: 0 3px; border-radius: 3px; }
img { max-width: 100%; border: 1px solid #ddd; margin: .5em 0; display: block; }
"""

_VERDICT_CLASS = {"pass": "pass", "reproduced": "pass", "yes": "pass", "holds": "pass",
                  "detected": "pass", "fail": "fail", "not reproduced": "fail", "no": "fail",
                  "fails": "fail", "missed": "fail", "partly": "partly", "not assessed": "info",
                  "reported": "info"}


def _inline(text: str) -> str:
    text = html.escape(text, quote=False)
    text = re.sub(r"`([^`]+)`", r"<code>\1</code>", text)
    text = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", text)
    text = re.sub(r"\[([^\]]+)\]\(([^)]+)\)", r'<a href="\2">\1</a>', text)
    return text


def _cells(line: str) -> list[str]:
    body = line.strip()[1:-1] if line.strip().endswith("|") else line.strip()[1:]
    parts = re.split(r"(?<!\\)\|", body)
    return [p.strip().replace("\\|", "|") for p in parts]


def _image(alt: str, src: str, base: Path) -> str:
    path = base / src
    if path.is_file():
        data = base64.b64encode(path.read_bytes()).decode("ascii")
        return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'
    return f"<p><em>missing figure {html.escape(src)}</em></p>"


def markdown_to_html(markdown: str, base: Path, title: str = "bicycle-xval report") -> str:
    """Convert the report's markdown; images are read from ``base`` and embedded."""
    out, para, items = [], [], []
    lines = markdown.splitlines()

    def flush():
        if para:
            out.append(f"<p>{_inline(' '.join(para))}</p>")
            para.clear()
        if items:
            out.append("<ul>" + "".join(f"<li>{_inline(i)}</li>" for i in items) + "</ul>")
            items.clear()

    i = 0
    while i < len(lines):
        line = lines[i]
        img = re.fullmatch(r"!\[([^\]]*)\]\(([^)]+)\)", line.strip())
        if not line.strip():
            flush()
        elif line.startswith("#"):
            flush()
            level = len(line) - len(line.lstrip("#"))
            text = line[level:].strip()
            anchor = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")
            out.append(f'<h{level} id="{anchor}">{_inline(text)}</h{level}>')
        elif img:
            flush()
            out.append(_image(img.group(1), img.group(2), base))
        elif line.lstrip().startswith("|"):
            flush()
            block = []
            while i < len(lines) and lines[i].lstrip().startswith("|"):
                block.append(lines[i])
                i += 1
            out.append(_table(block))
            continue
        elif line.startswith("- "):
            if para:
                flush()
            items.append(line[2:])
        elif items and line.startswith("  "):
            items[-1] += " " + line.strip()
        else:
            para.append(line.strip())
        i += 1
    flush()
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{CSS}</style></head><body>\n"
            + "\n".join(out) + "\n</body></html>\n")


def _table(block: list[str]) -> str:
    header = _cells(block[0])
    rows = [_cells(b) for b in block[2:]] if len(block) > 1 and set(block[1].replace("|", "").strip()) <= set("-: ") else [_cells(b) for b in block[1:]]
    head = "".join(f"<th>{_inline(h)}</th>" for h in header)
    body = []
    for r in rows:
        tds = []
        for c in r:
            cls = _VERDICT_CLASS.get(c.strip().lower())
            tds.append(f'<td class="{cls}">{_inline(c)}</td>' if cls else f"<td>{_inline(c)}</td>")
        body.append("<tr>" + "".join(tds) + "</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def write_html(report_md: Path) -> Path:
    """report.md -> report.html next to it."""
    out = report_md.with_suffix(".html")
    out.write_text(markdown_to_html(report_md.read_text(), report_md.parent))
    return out
