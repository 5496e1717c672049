"""The documents in docs/ stand alone and keep up with the code.

* every relative link in docs/*.md lands on a file inside the repository;
* no document or cleaned source file refers to a path outside the repository;
* docs/model.md names every parameter, coordinate, constraint row and scenario the code has
  (the lists come from the code: a new parameter or scenario without a description fails);
* docs/report.md explains every verdict word that appears in a verdict column of the
  committed example report (the words come from the report, not from this test).
"""

import re
from pathlib import Path
from urllib.parse import unquote

import pytest
from markdown_it import MarkdownIt

from reference_model import COORDINATES
from reference_model.model import CONSTRAINT_NAMES
from reference_model.params import PARAMETER_NAMES
from reference_model.scenarios import SCENARIOS

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted((ROOT / "docs").glob("*.md"))
# files that once pointed outside the repository (issue 10); README.md and benchmarks/ are
# cleaned on their own branches and belong here once they are
CLEANED = [ROOT / p for p in (
    "LICENSE", "CITATION.cff", "reference_model/parameters/thesis.toml", "reference_model/params.py",
    "tests/oracle.py", "tests/thesis_params.py", "tests/test_cli.py", "engines/exudyn/mapping.py",
    "comparisons/report/html.py")]
#: a relative path climbing out of the file's folder (checked by resolving it), and the folder
#: the repository sits in written as an absolute path (a path of this machine only)
RELATIVE = re.compile(r"(?:\.\./)+[\w.-][\w./-]*")
ABOVE = str(ROOT.parent) + "/"


def _outside(path: Path, line: str) -> list[str]:
    """The references in ``line`` of ``path`` that leave the repository."""
    out = [tok for tok in RELATIVE.findall(line)
           if not (path.parent / tok).resolve().is_relative_to(ROOT)]
    if ABOVE in line.replace(str(ROOT) + "/", ""):
        out.append(ABOVE)
    return out


def _links(markdown: str) -> list[str]:
    """Targets of the real links and images (not text in code that looks like one)."""
    out = []
    for tok in MarkdownIt("commonmark").enable("table").parse(markdown):
        for child in tok.children or []:
            if child.type in ("link_open", "image"):
                out.append(unquote(str(child.attrGet("href") or child.attrGet("src"))))
    return out


def test_docs_exist():
    assert {p.name for p in DOCS} >= {"model.md", "report.md"}


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_relative_links_land_inside_the_repository(doc):
    for target in _links(doc.read_text(encoding="utf-8")):
        if re.match(r"[a-z]+:|#", target):
            continue
        path = (doc.parent / target.split("#")[0]).resolve()
        assert path.is_relative_to(ROOT), f"{doc.name}: link {target} leaves the repository"
        assert path.exists(), f"{doc.name}: link {target} points to nothing"


@pytest.mark.parametrize("path", DOCS + CLEANED, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_reference_to_paths_outside_the_repository(path):
    for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        assert not _outside(path, line), f"{path.relative_to(ROOT)}:{n}: {line.strip()}"


def test_model_doc_covers_the_code():
    text = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    section = text.split("\n## Parameters\n", 1)[1].split("\n## ", 1)[0]
    described = {name for line in section.splitlines() if line.startswith("| `")
                 for name in re.findall(r"`(\w+)`", line.split("|")[1])}
    missing = [n for n in PARAMETER_NAMES if n not in described]
    assert not missing, f"parameters without a row in docs/model.md's parameter table: {missing}"
    assert f"q = [{', '.join(COORDINATES)}]" in text
    assert f"C = [ {', '.join(CONSTRAINT_NAMES)} ]" in text
    missing = [s for s in SCENARIOS if f"`{s}`" not in text]
    assert not missing, f"scenarios not described in docs/model.md: {missing}"


def _verdict_words(report: str) -> set[str]:
    """Every cell of every column headed 'verdict' or 'as expected' in the report's tables."""
    words, header = set(), None
    for line in report.splitlines():
        if not line.startswith("|"):
            header = None
            continue
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]]
        if header is None:
            header = cells
        elif not set("".join(cells)) <= set("-: "):
            for name, cell in zip(header, cells):
                if re.search(r"\[\^[ct]\d+-\d+\]$", cell) or name == "agreement":
                    # a cell of the claims or summary matrix (its footnote): 'reproduced',
                    # 'pass 8.3e-04', 'model difference: partly'; the claims' agreement
                    cell = re.sub(r"\[\^[ct]\d+-\d+\]$", "", cell)
                    cell = re.sub(r" [-+]?\d\.\de[-+]\d+$", "", cell)
                    if cell.startswith("model difference: "):
                        words.add("model difference: <verdict>")
                        cell = cell.removeprefix("model difference: ")
                    words.add(re.sub(r" \(\d+ of \d+\)$", "", cell))
                elif name in ("verdict", "as expected", "detected"):
                    # 'pass: why' or 'reported: who judges it': the word is before the reason
                    word = cell.split(": ", 1)[0]
                    words.add(re.sub(r" \(\d+ of \d+\)$", "", word))
    return words


def test_report_doc_explains_every_verdict_word_of_the_example_report():
    example = (ROOT / "reports" / "example" / "report.md").read_text(encoding="utf-8")
    words = _verdict_words(example)
    assert {"pass", "reproduced", "localized"} <= words     # the parser found the tables
    text = (ROOT / "docs" / "report.md").read_text(encoding="utf-8")
    missing = sorted(w for w in words if f"`{w}`" not in text)
    assert not missing, f"verdict words not explained in docs/report.md: {missing}"
