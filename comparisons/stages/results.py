"""What a stage of `bicycle-xval run` returns: a section of plain data, no files, no drawing.

A stage computes; the report package renders. A `Section` is a title, an ordered list of blocks
(`Text`, `Table`, `Figure`) and the comparisons it judged (`judgments.rows.Comparison`, the
rows of summary.json's ``comparisons``: quantity, scenario, model, engines, max_error,
tolerance, passed, localized_to, note, and what one kind of row adds). A `Figure` names a drawing of `comparisons.report.figures` and carries
the arrays it needs, so figures are drawn once, by the writer, into the output folder it owns.

Everything here is picklable: stages run in worker processes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Union

from ..judgments.rows import Comparison


@dataclass(frozen=True)
class Text:
    """A paragraph of markdown text (the renderer does not escape it)."""

    text: str


@dataclass(frozen=True)
class Heading:
    """A sub-heading inside a section (rendered one level below the section title)."""

    text: str


@dataclass(frozen=True)
class Table:
    """A table of plain-text cells (the renderer escapes what markdown would misread)."""

    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    note: str = ""      # a line under the table: how to read it


@dataclass(frozen=True)
class Figure:
    """A figure to draw: ``kind`` names a drawing function of `comparisons.report.figures`,
    ``data`` its keyword arguments (arrays and labels), ``name`` the PNG file name."""

    name: str
    kind: str
    data: dict[str, Any]
    caption: str = ""


Block = Union[Text, Heading, Table, Figure]

#: which figures a run draws (``bicycle-xval run --figures``): every one, those of the sections
#: where a comparison failed (what a reader debugging a failure looks at; --quick's default, as
#: a quick run that passes is read for its verdict), or none
FIGURE_POLICIES = ("all", "failing", "none")


@dataclass
class Section:
    """One section of the report: its blocks in order and the comparisons it judged."""

    title: str
    blocks: list[Block] = field(default_factory=list)
    comparisons: list[Comparison] = field(default_factory=list)
    seconds: float = 0.0

    def text(self, *paragraphs: str) -> None:
        self.blocks.extend(Text(p) for p in paragraphs)

    def heading(self, text: str) -> None:
        self.blocks.append(Heading(text))

    def table(self, header, rows, note: str = "") -> None:
        self.blocks.append(Table(tuple(header), tuple(tuple(str(c) for c in r) for r in rows), note))

    def figure(self, name: str, kind: str, caption: str = "", **data) -> None:
        self.blocks.append(Figure(name, kind, data, caption))

    @property
    def figures(self) -> list[Figure]:
        return [b for b in self.blocks if isinstance(b, Figure)]


def verdict_word(passed: bool | None, reason: str = "") -> str:
    """'pass' / 'FAIL' / 'reported', with the reason where the verdict is not obvious."""
    word = "reported" if passed is None else ("pass" if passed else "FAIL")
    return f"{word}: {reason}" if reason else word


def num(x, fmt: str = ".1e") -> str:
    """A number for a table cell; '-' for None."""
    return "-" if x is None else format(x, fmt)
