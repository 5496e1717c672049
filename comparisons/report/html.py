"""report.md -> one self-contained report.html: rendered by markdown-it-py, with a table of
contents, an anchor on every heading, figures embedded as data URIs and inline CSS.

Why a library and not a converter of our own: the report's markdown uses GitHub tables whose
cells escape pipes (``max \\|C\\|``), bold, code spans, links, lists and images; the earlier
hand-written converter let escapes leak as literal backslashes outside tables. markdown-it-py
is a maintained CommonMark parser with the GFM table rule, so every escape is resolved the way
GitHub resolves it. Raw HTML in the markdown is not passed through (it is escaped).

The output opens offline and can be mailed as one file or attached to a CI run: no link to
any other file is needed to see it (figures are base64 ``data:`` URIs; a figure that is
missing or of an unknown type is shown as a visible note, never a crash).

Layout: the table of contents (h2 and h3) sits in a side column on a wide screen, so the
first screen shows the report's own beginning (its verdict and what follows it); on a narrow
screen or in print it comes first. Wide tables scroll horizontally inside their own wrapper;
figures take the full content width.
"""

from __future__ import annotations

import base64
import html
import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import unquote

from markdown_it import MarkdownIt
from markdown_it.token import Token
from mdit_py_plugins.anchors import anchors_plugin
from mdit_py_plugins.footnote import footnote_plugin

__all__ = ["CSS", "TocEntry", "markdown_to_html", "write_html"]

TOC_LEVELS = (2, 3)   # h2 and h3 in the table of contents (h1 is the report's title)

# image suffix -> MIME type of the data URI; anything else is reported, not embedded
_IMAGE_TYPES = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg",
                ".gif": "image/gif", ".svg": "image/svg+xml", ".webp": "image/webp"}

# a table cell whose whole text is a verdict word gets a class (colour); matched on the
# lower-cased text, "FAIL (2 of 5)" by its first word
_VERDICT_CLASS = {
    "pass": "pass", "ok": "pass", "yes": "pass", "holds": "pass", "reproduced": "pass",
    "detected": "pass", "localized": "pass", "converges": "pass",
    "fail": "fail", "fails": "fail", "no": "fail", "not reproduced": "fail", "missed": "fail",
    "detected, mislocalized": "fail", "failed": "fail",
    "partly": "partly", "inconclusive": "partly",
    "reported": "info", "not assessed": "info", "not observable": "info",
    "model difference": "info", "agree": "pass", "differ": "partly",
}

CSS = """
:root { --toc-width: 17rem; --fg: #222; --muted: #666; --rule: #ccc; }
* { box-sizing: border-box; }
body { font: 15px/1.5 system-ui, -apple-system, "Segoe UI", sans-serif; color: var(--fg);
       margin: 0; background: #fff; }
main { margin-left: var(--toc-width); padding: 1rem 2rem 4rem; max-width: 100rem; }
nav.toc { position: fixed; top: 0; left: 0; bottom: 0; width: var(--toc-width);
          overflow-y: auto; padding: 1rem; border-right: 1px solid var(--rule);
          background: #f7f7f7; font-size: 13px; }
nav.toc p.toc-title { font-weight: 600; margin: 0 0 .5rem; }
nav.toc ul { list-style: none; margin: 0; padding-left: 0; }
nav.toc ul ul { padding-left: 1rem; }
nav.toc li { margin: .2rem 0; }
nav.toc a { color: #124; text-decoration: none; }
nav.toc a:hover { text-decoration: underline; }
@media (max-width: 900px), print {
  nav.toc { position: static; width: auto; border-right: 0; border-bottom: 1px solid var(--rule); }
  main { margin-left: 0; }
}
h1 { border-bottom: 2px solid #333; margin-top: .3rem; }
h2 { border-bottom: 1px solid #aaa; margin-top: 2.2rem; }
h1, h2, h3, h4 { scroll-margin-top: .5rem; }
a.header-anchor { color: #bbb; text-decoration: none; margin-left: .3rem; font-weight: normal; }
a.header-anchor:hover { color: #333; }
.table-wrap { overflow-x: auto; margin: .8rem 0; max-width: 100%; }
table { border-collapse: collapse; font-size: 13px; }
th, td { border: 1px solid var(--rule); padding: 3px 8px; text-align: left; vertical-align: top; }
th { background: #f0f0f0; }
td { font-variant-numeric: tabular-nums; }
tr:nth-child(even) td { background: #fafafa; }
td.pass { background: #e3f4e3 !important; }
td.fail { background: #f8d7d7 !important; font-weight: bold; }
td.partly { background: #fff4d6 !important; }
td.info { background: #e8eef8 !important; }
details.evidence { font-size: 12px; color: var(--muted); font-weight: normal; }
details.evidence summary { cursor: pointer; }
details.evidence[open] { min-width: 18rem; max-width: 32rem; }
details.evidence p { margin: .2rem 0; }
code { font-family: ui-monospace, "DejaVu Sans Mono", monospace; background: #f3f3f3;
       padding: 0 3px; border-radius: 3px; font-size: 92%; }
pre { background: #f3f3f3; padding: .6rem .8rem; overflow-x: auto; border-radius: 3px; }
pre code { background: none; padding: 0; font-size: 13px; }
img { display: block; width: 100%; max-width: 100%; height: auto; border: 1px solid #ddd;
      margin: .8rem 0; }
.missing-figure { display: block; color: #900; border: 1px dashed #c66; padding: .4rem .6rem;
                  margin: .8rem 0; font-style: italic; }
"""


@dataclass(frozen=True)
class TocEntry:
    """One heading of the table of contents."""

    level: int
    anchor: str
    text: str


#: what a matrix cell adds after its verdict: footnote references, the error relative to the
#: tolerance ("pass 8.3e-04")
_CELL_TAIL = re.compile(r"(?:\s*\[\^[^\]\s]+\])+$|\s+[-+]?\d(?:\.\d+)?e[-+]\d+$")


def _verdict_class(text: str) -> str | None:
    words = " ".join(text.split()).lower()
    while _CELL_TAIL.search(words):
        words = _CELL_TAIL.sub("", words)
    if words.startswith("model difference"):   # a claims cell judged under one: never a failure
        return "info"
    if words in _VERDICT_CLASS:
        return _VERDICT_CLASS[words]
    if words.startswith("fail ("):       # the summary's "FAIL (2 of 5)"
        return "fail"
    return None


def _image_html(src: str, alt: str, base: Path) -> str:
    """An <img> with the file embedded as a data URI, or a visible note when it cannot be."""
    if src.startswith(("data:", "http://", "https://")):
        return f'<img src="{html.escape(src)}" alt="{html.escape(alt)}">'
    path = base / unquote(src)   # markdown-it percent-encodes the link (spaces, non-ASCII)
    mime = _IMAGE_TYPES.get(path.suffix.lower())
    if mime is None:
        return (f'<span class="missing-figure">figure {html.escape(src)} not embedded: '
                f'unknown image type {html.escape(path.suffix or "(no suffix)")}</span>')
    try:
        data = path.read_bytes()
    except OSError as exc:
        reason = "file not found" if isinstance(exc, FileNotFoundError) else exc.strerror
        return (f'<span class="missing-figure">missing figure {html.escape(src)} '
                f'({html.escape(str(reason))})</span>')
    encoded = base64.b64encode(data).decode("ascii")
    return f'<img src="data:{mime};base64,{encoded}" alt="{html.escape(alt)}">'


def _parser(base: Path) -> MarkdownIt:
    """CommonMark + GFM tables, raw HTML escaped, anchors on every heading, our render rules."""
    md = MarkdownIt("commonmark", {"html": False}).enable(["table", "strikethrough"])
    anchors_plugin(md, min_level=1, max_level=6, permalink=True, permalinkSymbol="#")
    footnote_plugin(md)

    def image(self, tokens: list[Token], idx: int, options, env) -> str:
        token = tokens[idx]
        alt = self.renderInlineAsText(token.children or [], options, env)
        return _image_html(str(token.attrGet("src") or ""), alt, base)

    def table_open(self, tokens, idx, options, env) -> str:
        return '<div class="table-wrap">\n' + self.renderToken(tokens, idx, options, env)

    def table_close(self, tokens, idx, options, env) -> str:
        return self.renderToken(tokens, idx, options, env) + "</div>\n"

    def td_open(self, tokens, idx, options, env) -> str:
        inline = tokens[idx + 1] if idx + 1 < len(tokens) else None
        cls = _verdict_class(inline.content) if inline is not None and inline.type == "inline" else None
        if cls:
            tokens[idx].attrSet("class", cls)
        return self.renderToken(tokens, idx, options, env)

    def footnote_ref(self, tokens, idx, options, env) -> str:
        """A footnote reference (a matrix cell's evidence) as a ``<details>`` holding the
        footnote's text, so the evidence opens in place, one click away; the footnotes
        stay listed at the end as well."""
        text = env.get("footnote_html", {}).get(tokens[idx].meta["id"])
        if text is None:
            return default_ref(tokens, idx, options, env)
        return f'<details class="evidence"><summary>evidence</summary>{text}</details>'

    default_ref = md.renderer.rules["footnote_ref"]

    md.add_render_rule("image", image)
    md.add_render_rule("footnote_ref", footnote_ref)
    md.add_render_rule("table_open", table_open)
    md.add_render_rule("table_close", table_close)
    md.add_render_rule("td_open", td_open)
    return md


def _footnote_html(md: MarkdownIt, tokens: list[Token], env: dict) -> dict[int, str]:
    """Each footnote's text as HTML (without its back-reference), by its id: what a cell's
    ``<details>`` shows."""
    out, start = {}, None
    for i, tok in enumerate(tokens):
        if tok.type == "footnote_open":
            start = i
        elif tok.type == "footnote_close" and start is not None:
            inner = [t for t in tokens[start + 1:i] if t.type != "footnote_anchor"]
            out[tokens[start].meta["id"]] = md.renderer.render(inner, md.options, env).strip()
            start = None
    return out


def _toc(tokens: list[Token]) -> list[TocEntry]:
    """The h2/h3 headings in document order, with the anchors the plugin gave them."""
    out = []
    for i, tok in enumerate(tokens):
        if tok.type != "heading_open" or int(tok.tag[1:]) not in TOC_LEVELS:
            continue
        text, in_permalink = [], False
        for child in tokens[i + 1].children or []:
            if child.type == "link_open" and child.attrGet("class") == "header-anchor":
                in_permalink = True
            elif child.type == "link_close" and in_permalink:
                in_permalink = False
            elif not in_permalink and child.type in ("text", "code_inline"):
                text.append(child.content)
        out.append(TocEntry(int(tok.tag[1:]), str(tok.attrGet("id")), "".join(text).strip()))
    return out


def _toc_html(entries: list[TocEntry]) -> str:
    """Nested list: h3 entries inside the h2 before them."""
    if not entries:
        return ""
    parts = ['<nav class="toc" aria-label="Contents"><p class="toc-title">Contents</p><ul>']
    open_sub = False
    for k, e in enumerate(entries):
        link = f'<a href="#{html.escape(e.anchor)}">{html.escape(e.text)}</a>'
        if e.level == TOC_LEVELS[0]:
            if open_sub:
                parts.append("</ul></li>")
                open_sub = False
            elif k:
                parts.append("</li>")
            parts.append(f"<li>{link}")
        else:
            if not open_sub:
                parts.append("<ul>" if k else "<li><ul>")
                open_sub = True
            parts.append(f"<li>{link}</li>")
    parts.append("</ul></li>" if open_sub else "</li>")
    parts.append("</ul></nav>")
    return "".join(parts)


def markdown_to_html(markdown: str, base: Path, title: str = "bicycle-xval report") -> str:
    """Render the report's markdown as one self-contained HTML page.

    ``base`` is the folder relative to which image paths are read (the report's folder); each
    image is embedded as a data URI. The page has a table of contents of the h2 and h3
    headings, each linking to the anchor (``id``) the heading carries."""
    md = _parser(Path(base))
    env: dict = {}
    tokens = md.parse(markdown, env)
    env["footnote_html"] = _footnote_html(md, tokens, env)
    body = md.renderer.render(tokens, md.options, env)
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
            f"<title>{html.escape(title)}</title>\n<style>{CSS}</style></head>\n<body>\n"
            f"{_toc_html(_toc(tokens))}\n<main>\n{body}</main>\n</body></html>\n")


def write_html(report_md: Path) -> Path:
    """report.md -> report.html beside it (UTF-8), written atomically: a temporary file in
    the same folder, then ``os.replace``, so a reader never sees half a page."""
    report_md = Path(report_md)
    try:
        markdown = report_md.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"{report_md}: no such report; run `bicycle-xval run --out "
                                f"{report_md.parent}` first") from None
    page = markdown_to_html(markdown, report_md.parent)
    out = report_md.with_suffix(".html")
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(page)
        os.chmod(tmp, 0o644)   # mkstemp makes it private; a report is for reading
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return out
