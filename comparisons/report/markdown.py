"""report.md from a `ComparisonResult`: the verdict first, then failures (if any) and the
thesis's claims (claim x engine), then the summary (quantity x engine), then every section's
details, and last the footnotes that hold each matrix cell's evidence (`matrix`).

How to read each section and verdict: docs/report.md.

Escaping: everything the harness measured or was told (evidence, messages, engine and model
names, file paths, reasons, headings, table cells) is plain text, and reaches the markdown
through :func:`inline` only, which escapes what CommonMark would read as markup (``kg*m^2 ...
kg*m^2`` stays two asterisks, not italics). The writer's own formatting (the bold verdict,
the code spans it means) is written as :class:`Markdown`, which :func:`inline` leaves alone;
`stages.results.Text` paragraphs are markdown written by the stages, as their docstring says.
"""

from __future__ import annotations

import re
import string

from ..stages.results import Figure, Heading, Section, Table, Text, num
from .matrix import Matrix, claims_matrix, term_matrix

__all__ = ["Markdown", "cell", "code", "escape", "inline", "md", "render", "table"]


class Markdown(str):
    """Text that is markdown already (the writer's own formatting): not escaped again."""


# What CommonMark (with GFM tables and strikethrough, as html.py parses it) could read as
# markup in a line of text: backslash, code, emphasis, table and strikethrough delimiters
# anywhere; an underscore unless it sits inside a word (``psi_dot``: intraword underscores
# never open or close emphasis, and stay readable); ``<`` before what could start an autolink;
# an entity (``&lt;``); a ``]`` that could close a link or image (``](``, ``][``, ``]:``, the
# only ways a link forms without a definition, and the report defines none). Where the text
# opens a block (a list item's text; not a table cell, whose "-" is a value), also what would
# start a heading, quote, list or thematic break (``# ``, ``>``, ``- ``, ``---``, ``+ ``,
# ``1. ``; not ``0.1.0``).
_SPECIAL = re.compile(r"[\\`*|~]|(?<![^\W_])_|_(?![^\W_])|<(?=[A-Za-z/!?])|&(?=#?\w+;)"
                      r"|\](?=[(\[:])")
_BLOCK_START = re.compile(r"^(?:#(?=#{0,5}(?:\s|$))|>|-(?=[-\s]|$)|\+(?=\s|$)"
                          r"|\d{1,9}(?=[.)](?:\s|$)))")
#: what may precede a field in md()'s template for the field to open a block
_LIST_MARKER = re.compile(r"\s*(?:[-+*]|\d{1,9}[.)])?\s*")


def escape(text: str, opens_block: bool = False) -> str:
    """``text`` with a backslash before every character CommonMark would read as markup (a
    block-opening ``1.`` as ``1\\.``): it renders as the same characters."""
    text = _SPECIAL.sub(lambda m: "\\" + m[0], text)
    if opens_block:
        text = _BLOCK_START.sub(lambda m: m[0] + "\\" if m[0][0].isdigit() else "\\" + m[0], text)
    return text


def inline(x, opens_block: bool = False) -> Markdown:
    """Harness text as one line of markdown: whitespace collapsed, then escaped; a
    :class:`Markdown` value is the writer's own and passes as it is."""
    if isinstance(x, Markdown):
        return x
    return Markdown(escape(" ".join(str(x).split()), opens_block))


def cell(text) -> str:
    """Text safe inside a markdown table cell (one line, escaped: a pipe is ``\\|``)."""
    return inline(text)


def code(text) -> Markdown:
    """``text`` as a code span (shown exactly as it is: no escaping inside one)."""
    text = " ".join(str(text).split())
    fence = "`" * (max((len(r) for r in re.findall("`+", text)), default=0) + 1)
    pad = " " if text.startswith("`") or text.endswith("`") else ""
    return Markdown(f"{fence}{pad}{text}{pad}{fence}")


def md(template: str, *args) -> Markdown:
    """``template`` (the writer's markdown, ``{}`` fields in order) with every field filled by
    :func:`inline` text; numbers pass through, so a field may carry a format (``{:.3f}``). A
    field with only a list marker before it (``- {}``) opens a block, and is escaped so."""
    out, values = [], iter(args)
    for literal, field, spec, conversion in string.Formatter().parse(template):
        out.append(literal)
        if field is None:
            continue
        x = next(values)
        if not (isinstance(x, (int, float)) and not isinstance(x, bool)):
            x = inline(x, opens_block=len(out) == 1 and _LIST_MARKER.fullmatch(literal) is not None)
        out.append(format(x, spec or ""))
    return Markdown("".join(out))


def table(header, rows, note: str = "") -> list[str]:
    out = ["| " + " | ".join(cell(h) for h in header) + " |",
           "|" + "---|" * len(header)]
    out += ["| " + " | ".join(cell(c) for c in r) + " |" for r in rows]
    if note:
        out += ["", note]
    return out + [""]


def _blocks(section: Section, level: int) -> list[str]:
    out = [f"{'#' * level} {inline(section.title)}", ""]
    for b in section.blocks:
        if isinstance(b, Text):
            out += [b.text, ""]
        elif isinstance(b, Heading):
            out += [f"{'#' * (level + 1)} {inline(b.text)}", ""]
        elif isinstance(b, Table):
            out += table(b.header, b.rows, b.note)
        elif isinstance(b, Figure):
            out += [f"![{inline(b.caption or b.name[:-4])}](figures/{b.name})", ""]
    return out


_FIGURES_SAID = {
    "failing": "drawn only for the sections where a comparison failed (`--figures failing`, "
               "the default of `--quick`); `--figures all` draws every one.",
    "none": "none drawn (`--figures none`)."}


def _verdict(summary: dict) -> list[str]:
    comps = summary["comparisons"]
    n_fail = sum(c["passed"] is False for c in comps)
    n_judged = sum(c["passed"] is not None for c in comps)
    faults = summary["faults"]
    verdicts: dict[str, int] = {}
    for c in summary["claims"]:
        verdicts[c["verdict"]] = verdicts.get(c["verdict"], 0) + 1
    dropped = summary.get("dropped_engines", [])
    if summary["passed"]:
        head = "All judged comparisons are within tolerance."
    elif n_fail:
        head = f"Something is out of tolerance: {n_fail} comparison(s) failed."
    elif dropped:
        head = f"{len(dropped)} engine(s) could not be run (below); the rest agree."
    else:
        head = "Something failed (below)."
    unobservable = sum(f["verdict"] == "not observable" for f in faults)
    not_run = sum(f['verdict'] == 'not run' for f in faults)
    return [
        f"**{head}**", "",
        *[md("- **Dropped**: engine {}: {}", code(d["engine"]), d["reason"]) for d in dropped],
        *[md("- Not run: engine {}: {}", code(d["engine"]), d["reason"])
          for d in summary.get("not_installed_engines", [])],
        md("- Engines: {}", ", ".join(summary["engines"]))
        + f"{' (quick subset of scenarios and states)' if summary.get('quick') else ''}.",
        *([f"- Figures: {_FIGURES_SAID[summary['figures']]}"]
          if summary.get("figures", "all") != "all" else []),
        f"- {len(comps)} comparisons, {n_judged} judged against a tolerance, {n_fail} failed; "
        f"the rest are reported (the row says who judges them).",
        (f"- Fault injection: {len(faults)} fault-engine pairs, "
         f"{sum(f['verdict'] == 'localized' for f in faults)} detected and localized"
         + (f", {unobservable} not observable by the engine" if unobservable else "")
         + (f", {not_run} not run (the engine cannot represent that bicycle: a declared "
            "limitation)" if not_run else "") + "."
         if "engine_sections" not in summary else
         f"- Fault injection and the engine sections: {summary['engine_sections']}."),
        md("- The thesis's claims: {}.", ", ".join(f"{v} {k}" for k, v in sorted(verdicts.items()))
           or "none judged"),
        *_bicycles(summary),
        *_models(summary),
        "", GUIDE_LINE, ""]


#: where the reading guide is, for a reader with the repository and for one with the wheel
#: (pyproject.toml ships docs/ as comparisons/docs/; `bicycle-xval --version` prints its path)
GUIDE_LINE = ("How to read this report: `docs/report.md`, in the repository and in the "
              "installed package (`bicycle-xval --version` prints where). Tolerances and their "
              "reasons: `comparisons/judgments/tolerances.toml`. Machine-readable: "
              "`summary.json`.")


def _bicycles(summary: dict) -> list[str]:
    """The verdict block's lines on the built-in bicycles compared (a --model run names its
    models instead, below): name, parameter file, contact, how many comparisons."""
    if "models" in summary:
        return []
    out = []
    for b in summary.get("provenance", {}).get("bicycles", []):
        variants = f", some with {', '.join(b['variants'])}" if b["variants"] else ""
        out.append(md("  - {}: {}, {} contact ({} comparisons{})", b["name"], code(b["source"]),
                      b["contact"], b["comparisons"], variants))
    return ["- Bicycles compared:", *out] if out else []


def _models(summary: dict) -> list[str]:
    """The verdict block's lines on the models of a --model / --scenario-file run (none for the
    thesis's own run): name, source, contact, and every model's warnings, said here."""
    out = []
    for m in summary.get("models", []):
        out.append(md("- Model {}: {}, contact {}", m["name"], m["source"], m["contact"])
                   + (", **with warnings** (below)." if m["warnings"] else "."))
        out += [md("  - **Warning** ({}): {}", m["name"], w) for w in m["warnings"]]
    if summary.get("not_run"):
        out.append(f"- Not run: {len(summary['not_run'])} scenario-model pair(s), each with its "
                   "reason in 'Models of this run'.")
    return out


def _failures(summary: dict, localization) -> list[str]:
    bad = [c for c in summary["comparisons"] if c["passed"] is False]
    bad_checks = [c for c in summary["checks"] if not c["passed"]]
    bad_faults = [f for f in summary["faults"]
                  if f["verdict"] not in ("localized", "not observable", "not run")]
    if not (bad or bad_checks or bad_faults or localization):
        return []
    out = ["## Failures", ""]
    if bad:
        out += table(("quantity", "scenario", "engines", "error", "tolerance", "where"),
                     [(c["quantity"], c["scenario"], " vs ".join(c["engines"]),
                       num(c["max_error"]), num(c["tolerance"]), c.get("localized_to", "-"))
                      for c in bad])
    out += [md("- analytic check failed: {} ({})", c["check"], c["evidence"]) for c in bad_checks]
    out += [md("- fault {} on {}: {} ({})", f["fault"], f["engine"], f["verdict"], f["evidence"])
            for f in bad_faults]
    for title, text in localization:
        out += [md("### Where the engines disagree: {}", title), ""]
        out += [md("- {}", line) for line in text.splitlines() if line.strip()] + [""]
    return out


#: a footnote of a matrix cell: its label, the row's and column's names, the evidence lines
Note = tuple[str, str, str, tuple[str, ...]]


def _cells(m: Matrix, prefix: str, notes: list[Note], text) -> list[list]:
    """Each cell of ``m`` as its ``text(cell)`` with a footnote to its evidence (appended to
    ``notes``), or ``-`` where no row is."""
    out = []
    for i, (row, cells) in enumerate(zip(m.rows, m.cells)):
        line = []
        for j, (column, c) in enumerate(zip(m.columns, cells)):
            if c is None:
                line.append("-")
                continue
            key = f"{prefix}{i + 1}-{j + 1}"
            notes.append((key, row, column, c.evidence))
            line.append(Markdown(inline(text(c)) + f"[^{key}]"))
        out.append(line)
    return out


def _claims(summary: dict, notes: list[Note]) -> list[str]:
    if not summary["claims"]:
        return []
    m = claims_matrix(summary["claims"])
    cells = _cells(m, "c", notes, lambda c: c.verdict)
    return ["## The thesis's claims, engine by engine", "",
            "Each row is the thesis's sentence, each column an engine's runs; the footnote of a "
            "cell gives the numbers and the threshold that turned them into its verdict. "
            "`model difference: ...`: judged on runs of an engine that declares a model "
            "difference (a soft contact, not ideal rolling): shown, never a failure. "
            "`agreement`: whether the engines judged without one agree (`differ` names a "
            "disagreement; `-`: none judged).", ""] + table(
        ("claim", *m.columns, "agreement"),
        [(row, *line, agree) for row, line, agree in zip(m.rows, cells, m.agreement)])


def _term_text(c) -> str:
    return c.verdict if c.ratio is None else f"{c.verdict} {c.ratio:.1e}"


def _summary_table(summary: dict, notes: list[Note]) -> list[str]:
    m = term_matrix(summary["comparisons"], summary["engines"])
    if not m.rows:
        return []
    cells = _cells(m, "t", notes, _term_text)
    return ["## Summary: quantity x engine", ""] + table(
        ("quantity", *m.columns), [(row, *line) for row, line in zip(m.rows, cells)],
        note="Each cell: every comparison of the quantity on that engine (its run setups, "
             "variants and bicycles), `FAIL (k of n)` if any judged one failed, else `pass`, "
             "else `reported` (or `model difference`: declared, not judged), and the worst "
             "error divided by its tolerance (1 is the tolerance; errors relative to the "
             "scale each tolerance names, absolute for trajectories and constraint "
             "residuals). Its footnote lists the engine pairs behind it; every row is in its "
             "section below and in summary.json (`summary_table`, `comparisons`).")


def _notes(notes: list[Note]) -> list[str]:
    """The matrices' footnotes, at the end (where GitHub and the HTML list them too)."""
    if not notes:
        return []
    return ["", "## Evidence of the matrices' cells", ""] + [
        f"[^{key}]: " + md("{} / {}: {}", row, column, "; ".join(evidence))
        for key, row, column, evidence in notes]


def _reference(summary: dict) -> list[str]:
    out = ["## Scenarios on the reference model", ""]
    out += table(("scenario", "kind", "status", "t_end [s]", "max abs C [m, m/s]"),
                 [(r["scenario"], r["kind"], r["status"], r["t_end"], r["max_abs_C"])
                  for r in summary["scenarios"]])
    out += ["Engine runs:", ""] + table(
        ("scenario", "engine", "status", "end [s]", "message"),
        [(r["scenario"], r["engine"], r["status"], f"{r['t_end']:.3f}", r["message"])
         for r in summary["engine_runs"]])
    if summary["initial_corrections"]:
        out += ["Initial states: every engine starts from the same projected state (beta from "
                "[rD]_z = 0, dependent rates from D dq = 0). Corrections applied:", ""]
        out += [md("- {}: {}", name, text)
                for name, text in summary["initial_corrections"].items()] + [""]
    for c in summary["checks"]:
        out += [md("Analytic check: {}: {} ({}).", c["check"], "holds" if c["passed"] else "FAILS",
                   c["evidence"]), ""]
    return out


def _tail(summary: dict) -> list[str]:
    out = []
    if summary["expected_differences"]:
        out += ["## Expected differences (declared in the scenario registry)", ""]
        out += [md("- {}, {}, {}: expected '{}' because {}", e["scenario"], e["quantity"],
                   e["engines"], e["expected"], e["reason"])
                for e in summary["expected_differences"]] + [""]
    env = summary["environment"]
    out += ["## Environment", "",
            *_code_line(summary.get("provenance")),
            md("Machine: {}, {} cores, {}.", env["machine"]["cpu"], env["machine"]["cores"],
               env["machine"]["platform"]), "",
            md("Packages: {}.", ", ".join(f"{k} {v}" for k, v in env["packages"].items())), "",
            "Solver settings:", ""]
    out += [md("- {}: {}", k, v) for k, v in env["solvers"].items()]
    out += ["", md("Steps: {}.", ", ".join(f"{k} = {v}" for k, v in env["steps"].items())), "",
            "Run times are in `timings.json` (kept apart so the report is identical run to run)."]
    return out


def _code_line(p: dict | None) -> list[str]:
    """The code that wrote the report: version and, in a git checkout, the commit."""
    if not p:
        return []
    commit = "" if not p["commit"] else (
        md(", commit {}", code(p["commit"][:12])) + (" (uncommitted changes)" if p["dirty"] else ""))
    return [md("Code: bicycle-xval {}", p["version"] or "(not installed)") + commit + ".", ""]


def render(result) -> str:
    """The whole report.md of a `comparisons.stages.pipeline.ComparisonResult`."""
    s = result.summary
    notes: list[Note] = []
    lines = ["# bicycle-xval report", ""]
    lines += (_verdict(s) + _failures(s, result.localization) + _claims(s, notes)
              + _summary_table(s, notes))
    lines += _reference(s)
    for sec in result.sections:
        lines += _blocks(sec, 2)
    lines += _tail(s) + _notes(notes)
    return "\n".join(lines).rstrip("\n") + "\n"
