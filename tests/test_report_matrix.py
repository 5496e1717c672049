"""The report with eight engines (issue 25): the claims as a claim x engine matrix and the term
summary as a quantity x engine matrix (comparisons/report/matrix.py), rendered in report.md
with each cell's evidence a footnote and in report.html as a ``<details>`` in the cell.

Eight engines are made up here: the five built-ins' names and three plugins (one of them with
two run setups, ``plugin_b-x`` and ``plugin_b-y``, and one whose energy rows are labelled
``plugin_c fine``), with synthetic claim and comparison rows. Every expected verdict is
computed here from how the rows were made (`_claim_verdict`, `_TERMS`), never read from the
code under test. No run: milliseconds, plus ~0.1 s for markdown-it.
"""

import re
from pathlib import Path
from types import SimpleNamespace

import pytest

from comparisons.report import markdown
from comparisons.report.html import markdown_to_html
from comparisons.report.matrix import claims_matrix, column_of, term_matrix
from comparisons.report.writer import with_matrices

ENGINES = ("reference", "pinocchio", "exudyn", "kane", "mujoco", "plugin_a", "plugin_b",
           "examples/p.py:plugin_c")
NAMES = ("reference", "pinocchio", "exudyn", "kane", "mujoco", "plugin_a", "plugin_b", "plugin_c")
#: the run labels the claims are judged on (an engine's setup labels)
LABELS = ("reference", "pinocchio", "exudyn-tree", "kane", "mujoco", "plugin_a", "plugin_b-x",
          "plugin_c")
CLAIMS = tuple(f"claim {k}: the thesis says {k}" for k in range(7))
WORDS = ("reproduced", "partly", "not reproduced", "not assessed")
#: the engines whose runs declare a model difference (a soft contact)
SOFT = {"mujoco", "plugin_a"}


def _claim_verdict(k: int, j: int) -> str:
    """Claim k on engine j: a pattern every engine and claim differ in, so that a cell that
    took its neighbour's verdict shows."""
    return WORDS[(k + j) % len(WORDS)] if k != 0 else "reproduced"


def _claims() -> list[dict]:
    return [{"claim": text, "claim_id": f"c{k}", "engine": lab, "verdict": _claim_verdict(k, j),
             "evidence": f"evidence of claim {k} on {lab}",
             "model_difference": "soft contact" if lab in SOFT else None}
            for k, text in enumerate(CLAIMS) for j, lab in enumerate(LABELS)]


def _row(quantity, engines, error, tolerance, passed, **more) -> dict:
    return {"quantity": quantity, "scenario": "s", "model": "thesis", "engines": list(engines),
            "max_error": error, "tolerance": tolerance, "passed": passed,
            "localized_to": "-", "note": "", **more}


def _comparisons() -> list[dict]:
    # pinocchio fails one of two (the failure first); plugin_b passes on one setup and fails
    # on the other (the failure last)
    rows = [_row("mass_matrix", ("reference", "pinocchio"), 5e-12, 1e-12, False)]
    for j, name in enumerate(NAMES[1:], start=1):          # M on every engine but the reference
        label = "plugin_b-x" if name == "plugin_b" else name
        rows.append(_row("mass_matrix", ("reference", label), 1e-16 * j, 1e-12, True))
    rows.append(_row("mass_matrix", ("reference", "plugin_b-y"), 3e-12, 1e-12, False))
    # a soft contact's reported rows, and a fixed-step engine's reported trajectories
    rows.append(_row("contact fidelity", ("reference", "mujoco"), 1e-4, None, None,
                     why="declared model difference"))
    rows.append(_row("trajectory", ("reference", "exudyn-tree"), 8e-3, None, None,
                     note="reported, not judged: judged by its convergence order"))
    # the reference's own rows, labelled as the stages label them
    rows.append(_row("energy drift", ("reference thesis-disc",), 4e-8, 0.1, True))
    rows.append(_row("energy drift", ("plugin_c fine",), 0.2, 0.1, False))
    rows.append(_row("eigenvalue fit", ("reference (nonlinear)", "linearize"), 2e-2, 4e-2, True))
    rows.append(_row("weave speed", ("reference", "published"), 7e-15, 1e-9, True))
    return rows


#: (quantity, engine) -> (verdict, worst error / tolerance), from how the rows were made above
_TERMS = {("mass_matrix", n): ("pass", 1e-4 * j) for j, n in enumerate(NAMES) if j}
_TERMS.update({("mass_matrix", "pinocchio"): ("FAIL (1 of 2)", 5.0),
               ("mass_matrix", "plugin_b"): ("FAIL (1 of 2)", 3.0),
               ("contact fidelity", "mujoco"): ("model difference", None),
               ("trajectory", "exudyn"): ("reported", None),
               ("energy drift", "reference"): ("pass", 4e-7),
               ("energy drift", "plugin_c"): ("FAIL (1 of 1)", 2.0),
               ("eigenvalue fit", "reference"): ("pass", 0.5),
               ("weave speed", "reference"): ("pass", 7e-6)})


def _summary() -> dict:
    return {"passed": False, "engines": list(ENGINES), "comparisons": _comparisons(),
            "claims": _claims(), "faults": [], "checks": [], "summary_table": [],
            "scenarios": [], "engine_runs": [], "initial_corrections": {},
            "expected_differences": [],
            "environment": {"machine": {"cpu": "c", "cores": 2, "platform": "p"},
                            "packages": {}, "solvers": {}, "steps": {}}}


@pytest.fixture(scope="module")
def rendered() -> tuple[str, str]:
    text = markdown.render(SimpleNamespace(summary=_summary(), sections=[], localization=[]))
    return text, markdown_to_html(text, Path("."))


def test_the_claims_matrix_is_claims_by_engines_whatever_their_number():
    """Seven claims on eight engines: seven rows (not 56), eight columns in the engines'
    order, every cell filled."""
    m = claims_matrix(_claims())
    assert m.rows == CLAIMS and m.columns == LABELS
    assert all(c is not None for row in m.cells for c in row)
    assert len(m.cells) == 7 and {len(r) for r in m.cells} == {8}


def test_each_claims_cell_is_its_own_rows_verdict():
    """Cell (claim k, engine j) shows the verdict made for k and j, and its evidence.
    Planted: cells keyed by the first engine (a cell taking another engine's verdict)
    fails."""
    m = claims_matrix(_claims())
    for k, claim in enumerate(CLAIMS):
        for j, lab in enumerate(LABELS):
            c = m.cell(claim, lab)
            assert c.verdict.removeprefix("model difference: ") == _claim_verdict(k, j)
            assert c.evidence[0] == f"evidence of claim {k} on {lab}"


def test_a_model_difference_is_never_a_failure_and_never_hidden(rendered):
    """A soft-contact engine's claims read 'model difference: <verdict>', the verdict kept;
    in the HTML such a cell is classed as information, never 'fail'; an engine without one
    showing 'not reproduced' is still classed 'fail'. Planted: dropping the prefix (the cell
    then reads 'not reproduced' in red) fails."""
    m = claims_matrix(_claims())
    for k, claim in enumerate(CLAIMS):
        for j, lab in enumerate(LABELS):
            c = m.cell(claim, lab)
            assert c.model_difference == (lab in SOFT)
            assert c.verdict == (f"model difference: {_claim_verdict(k, j)}" if lab in SOFT
                                 else _claim_verdict(k, j))
    _, page = rendered
    by_text = {}     # a cell's text -> the classes it is drawn with
    for cls, text in re.findall(r'<td class="(\w+)">([^<]+)<details', page):
        by_text.setdefault(text, set()).add(cls)
    assert by_text["model difference: not reproduced"] == {"info"}
    assert by_text["not reproduced"] == {"fail"}
    assert by_text["FAIL (1 of 2) 5.0e+00"] == {"fail"}     # the term matrix's failure


def test_agreement_names_a_disagreement_among_the_engines_without_a_model_difference():
    """Claim 0 is reproduced everywhere: 'agree'; the others differ between engines judged
    without a model difference: 'differ'. A row whose only assessed verdicts are under a
    model difference says '-'. Planted: agreement counted over every cell, model
    differences included, still passes here; counted over none ('-' always) fails."""
    m = claims_matrix(_claims())
    assert m.agreement[0] == "agree"
    assert set(m.agreement[1:]) == {"differ"}
    only_soft = [dict(c, verdict="not assessed") if c["model_difference"] is None else c
                 for c in _claims()]
    assert set(claims_matrix(only_soft).agreement) == {"-"}


def test_the_term_matrix_has_one_column_per_engine_and_the_rows_verdicts():
    """Quantities as rows, the eight engines as columns (a plugin spec by its class name,
    setups and variants folded into their engine), each cell the verdict and worst
    error / tolerance made above. Planted: a failure rendered as pass (failures counted in
    the last row only) fails; so does a column taken from the first label (the reference)."""
    m = term_matrix(_comparisons(), ENGINES)
    assert m.columns == NAMES
    assert m.rows == ("mass_matrix", "contact fidelity", "trajectory", "energy drift",
                      "eigenvalue fit", "weave speed")
    for q in m.rows:
        for e in m.columns:
            c = m.cell(q, e)
            if (q, e) not in _TERMS:
                assert c is None, (q, e, c)
                continue
            verdict, ratio = _TERMS[(q, e)]
            assert c.verdict == verdict, (q, e)
            assert (c.ratio is None) == (ratio is None), (q, e)
            if ratio is not None:
                # the ratios are exact products of powers of ten: agreement to round-off
                assert c.ratio == pytest.approx(ratio, rel=1e-12), (q, e)
    assert m.cell("contact fidelity", "mujoco").model_difference
    assert not m.cell("trajectory", "exudyn").model_difference


def test_a_column_is_the_engine_under_test():
    assert column_of(["reference", "exudyn-tree-disc"], NAMES) == "exudyn"
    assert column_of(["plugin_c fine"], NAMES) == "plugin_c"
    assert column_of(["reference (nonlinear)", "linearize"], NAMES) == "reference"
    # the longest name wins: an engine 'exudyn-x' is not Exudyn's setup 'x'
    assert column_of(["reference", "exudyn-x"], NAMES + ("exudyn-x",)) == "exudyn-x"


def test_each_cell_s_footnote_holds_its_own_evidence(rendered):
    """report.md: the claims table keeps one row per claim with a column per engine; each
    cell's footnote names its claim and engine and carries that row's evidence; the HTML's
    ``<details>`` in that cell shows the same. Planted: numbering the footnotes by row only
    (every cell of a row pointing at one footnote) fails."""
    text, page = rendered
    lines = text.splitlines()
    head = lines.index("| claim | " + " | ".join(LABELS) + " | agreement |")
    body = lines[head + 2:head + 2 + len(CLAIMS)]
    assert len(body) == 7 and not lines[head + 2 + len(CLAIMS)].startswith("|")
    notes = dict(re.findall(r"^\[\^([\w-]+)\]: (.*)$", text, flags=re.M))
    for k, row in enumerate(body):
        cells = [c.strip() for c in row.strip("|").split(" | ")][1:-1]
        for j, cell in enumerate(cells):
            key = re.fullmatch(r".*\[\^([\w-]+)\]", cell)[1]
            assert f": evidence of claim {k} on {LABELS[j]}" in notes[key], (key, cell)
    details = re.findall(r"<td[^>]*>([^<]*)<details class=\"evidence\"><summary>evidence"
                         r"</summary><p>(.*?)</p></details>", page)
    claims_cells = [d for d in details if d[1].startswith("claim ")]
    assert len(claims_cells) == 7 * 8
    for k in range(7):
        for j, lab in enumerate(LABELS):
            verdict, evidence = claims_cells[8 * k + j]
            assert f"evidence of claim {k} on {lab}" in evidence
            assert verdict.removeprefix("model difference: ") == _claim_verdict(k, j)


def test_the_first_screen_is_the_verdict_then_the_claims_matrix(rendered):
    """The first heading after the verdict (and the failures, when any) is the claims
    matrix, whose table is one line per claim: with eight engines the verdict and the
    matrix fit in the first 40 lines."""
    text, _ = rendered
    lines = text.splitlines()
    h2 = [i for i, ln in enumerate(lines) if ln.startswith("## ")]
    titles = [lines[i] for i in h2]
    claims_at = titles.index("## The thesis's claims, engine by engine")
    assert titles[:claims_at] in ([], ["## Failures"])
    end = h2[claims_at + 1]
    assert titles[claims_at + 1] == "## Summary: quantity x engine"
    assert end < 40 and sum(ln.startswith("| claim |") for ln in lines[:end]) == 1


def test_summary_json_keeps_its_keys_and_adds_the_matrices():
    """with_matrices: every key the summary had, unchanged, and the two matrices under keys
    of their own."""
    s = _summary()
    out = with_matrices(s)
    assert {k: out[k] for k in s} == s
    assert set(out) - set(s) == {"claims_matrix", "term_matrix"}
    cm = out["claims_matrix"]
    assert cm["columns"] == list(LABELS) and len(cm["cells"]) == 7
    assert cm["cells"][0][0]["verdict"] == "reproduced"
    assert out["term_matrix"]["columns"] == list(NAMES)
