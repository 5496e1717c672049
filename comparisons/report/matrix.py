"""The report's two matrices, built from its rows: the thesis's claims (claim x engine) and the
term summary (quantity x engine). Pure: rows in, a `Matrix` out; the writers render it
(report.md as a table with footnotes, report.html with each footnote a ``<details>``,
summary.json's ``claims_matrix`` and ``term_matrix`` through `Matrix.as_dict`).

    claims_matrix(summary["claims"])                          # one row per claim
    term_matrix(summary["comparisons"], summary["engines"])   # one row per quantity

A claims cell is its claim row's verdict; a claim judged on runs of an engine that declares a
model difference of its forward runs (the row's ``model_difference``) reads ``model
difference: <verdict>``: never a failure, and its verdict still shown. A term cell gathers
every comparison of that quantity on that engine (each of its run setups and variants, every
bicycle): ``FAIL (k of n)`` when any judged one failed, else ``pass`` when any is judged, else
``model difference`` when each says it is a declared one, else ``reported``; with the worst
error divided by its tolerance. Either cell's evidence is the rows behind it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from ..judgments.summary import summary_table
from ..stages.results import num

__all__ = ["Cell", "MODEL_DIFFERENCE", "Matrix", "claims_matrix", "column_of", "term_matrix"]

#: the words a cell judged under a declared model difference starts with
MODEL_DIFFERENCE = "model difference"
REFERENCE = "reference"


@dataclass(frozen=True)
class Cell:
    """One cell: its verdict (the words shown), the evidence behind it (one line per row),
    the worst error relative to its tolerance (term cells; None when nothing judged has a
    tolerance) and whether it was judged under a declared model difference."""

    verdict: str
    evidence: tuple[str, ...]
    ratio: float | None = None
    model_difference: bool = False


@dataclass(frozen=True)
class Matrix:
    """Rows x columns of cells (None: no row of that pair); ``agreement`` one word per row
    (claims: whether the engines judged without a model difference agree), else empty."""

    rows: tuple[str, ...]
    columns: tuple[str, ...]
    cells: tuple[tuple[Cell | None, ...], ...]
    agreement: tuple[str, ...] = ()

    def cell(self, row: str, column: str) -> Cell | None:
        return self.cells[self.rows.index(row)][self.columns.index(column)]

    def as_dict(self) -> dict:
        return {"rows": list(self.rows), "columns": list(self.columns),
                "cells": [[None if c is None else {**asdict(c), "evidence": list(c.evidence)}
                           for c in row] for row in self.cells],
                **({"agreement": list(self.agreement)} if self.agreement else {})}


def _grid(rows, columns, found: dict) -> tuple[tuple[Cell | None, ...], ...]:
    return tuple(tuple(found.get((r, c)) for c in columns) for r in rows)


def claims_matrix(claims) -> Matrix:
    """The claims as rows (in their order), the engines as columns (in order of first
    appearance), each cell its row's verdict and evidence."""
    rows = tuple(dict.fromkeys(c["claim"] for c in claims))
    columns = tuple(dict.fromkeys(c["engine"] for c in claims))
    found = {}
    for c in claims:
        difference = c.get("model_difference")
        verdict = f"{MODEL_DIFFERENCE}: {c['verdict']}" if difference else c["verdict"]
        evidence = (c["evidence"],) + ((f"judged under a declared model difference: "
                                        f"{difference}",) if difference else ())
        found[(c["claim"], c["engine"])] = Cell(verdict, evidence, None, bool(difference))
    cells = _grid(rows, columns, found)
    agreement = []
    for row in cells:
        judged = {c.verdict for c in row if c is not None and not c.model_difference
                  and c.verdict != "not assessed"}
        agreement.append("differ" if len(judged) > 1 else "agree" if judged else "-")
    return Matrix(rows, columns, cells, tuple(agreement))


def _separated(label: str, name: str) -> bool:
    return label == name or label.startswith((name + "-", name + " "))


def column_of(engines, names) -> str:
    """The engine column of a comparison between ``engines`` (run labels: ``name``,
    ``name-setup``, ``name setup``, ``reference (nonlinear)``): the first that is not the
    reference and is one of ``names`` (the longest matching name); else the reference when
    one of them is; else the last label as it is."""
    ordered = sorted(names, key=len, reverse=True)
    matched = [next((n for n in ordered if _separated(e, n)), None) for e in engines]
    for m in matched:
        if m is not None and m != REFERENCE:
            return m
    return REFERENCE if REFERENCE in matched else engines[-1]


def _ratio(rows) -> float | None:
    ratios = [r["max_error"] / r["tolerance"] for r in rows
              if r.get("passed") is not None and isinstance(r.get("max_error"), (int, float))
              and isinstance(r.get("tolerance"), (int, float)) and r["tolerance"] > 0]
    return max(ratios) if ratios else None


def _is_model_difference(row) -> bool:
    return "declared model difference" in (row.get("why") or row.get("note") or "")


def _term_cell(rows) -> Cell:
    judged = [r for r in rows if r.get("passed") is not None]
    failed = sum(r["passed"] is False for r in judged)
    if failed:
        verdict = f"FAIL ({failed} of {len(judged)})"
    elif judged:
        verdict = "pass"
    elif all(_is_model_difference(r) for r in rows):
        verdict = MODEL_DIFFERENCE
    else:
        verdict = "reported"
    evidence = tuple(
        f"{s['engines']}: {s['n']} comparison(s), max error {num(s['max_error'])}, tolerance "
        f"{s['tolerance'] if isinstance(s['tolerance'], str) else num(s['tolerance'])}, "
        f"{s['verdict']}{': ' + s['reason'] if s.get('reason') else ''}; worst at {s['worst']}"
        for s in summary_table(rows))
    return Cell(verdict, evidence, _ratio(rows), verdict == MODEL_DIFFERENCE)


def term_matrix(comparisons, engines) -> Matrix:
    """The quantities as rows (in order of first appearance), one column per engine of
    ``engines`` (registered names or ``module:Class`` specs, in their order) that has a
    comparison, then any other column `column_of` gives; each cell `_term_cell`."""
    names = [e.rsplit(":", 1)[-1] for e in engines]
    groups: dict[tuple[str, str], list] = {}
    for c in comparisons:
        groups.setdefault((c["quantity"], column_of(list(c["engines"]), names)), []).append(c)
    rows = tuple(dict.fromkeys(q for q, _ in groups))
    used = {col for _, col in groups}
    columns = tuple(n for n in dict.fromkeys(names) if n in used) + tuple(
        dict.fromkeys(col for _, col in groups if col not in names))
    return Matrix(rows, columns, _grid(rows, columns, {k: _term_cell(v) for k, v in groups.items()}))
