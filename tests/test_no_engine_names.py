"""The harness names no engine (issue 22): outside ``engines/<name>/``, no Python file under
``comparisons/``, ``reference_model/`` or ``engines/*.py`` names a built-in engine in code:
string constants that are not docstrings (help texts and error messages included),
identifiers and attribute names. Docstrings and comments may; the MJCF export is a file format
(its tags are MuJoCo's) and is exempt; a file named after an engine (its own study) is too.

Costs about 0.3 s (parsing ~200 files).
"""

import ast
from pathlib import Path

from engines.registry import _pyproject_registrations

ROOT = Path(__file__).resolve().parents[1]
#: the built-in engines, as the project declares them (its pyproject's entry points)
NAMES = tuple(r.name for r in _pyproject_registrations() if r.name != "reference")
#: file formats whose keywords are an engine's own
EXEMPT = {"reference_model/exports/mjcf.py", "reference_model/export_mjcf.py",
          "comparisons/cli/export.py"}


def engine_names_in(source: str, path: str = "", names=NAMES) -> list[tuple[int, str]]:
    """(line, text) of every string constant that is not a docstring, identifier or attribute
    name in ``source`` that contains one of ``names`` (case-insensitive), unless the file's
    ``path`` itself names that engine."""
    tree = ast.parse(source)
    docs = {id(n.body[0].value) for n in ast.walk(tree)
            if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
            and n.body and isinstance(n.body[0], ast.Expr)
            and isinstance(n.body[0].value, ast.Constant)}
    hits = []
    for n in ast.walk(tree):
        if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs:
            word = n.value
        elif isinstance(n, ast.Name):
            word = n.id
        elif isinstance(n, ast.Attribute):
            word = n.attr
        else:
            continue
        if any(e in word.lower() and e not in path.lower() for e in names):
            hits.append((n.lineno, word))
    return sorted(hits)


def harness_files() -> list[str]:
    files = [*(ROOT / "comparisons").rglob("*.py"), *(ROOT / "reference_model").rglob("*.py"),
             *(ROOT / "engines").glob("*.py")]
    return sorted(str(f.relative_to(ROOT)) for f in files
                  if str(f.relative_to(ROOT)) not in EXEMPT)


def test_the_check_finds_a_name_in_code_and_not_in_docstrings():
    """The check itself: a planted constant, an identifier, an attribute and a help text are
    found; the docstrings and a file named after the engine are not."""
    e = NAMES[0]
    source = (f'"""Module: {e} in a docstring."""\n'
              f'def f():\n    """{e} here too."""\n    return "{e}-tree"\n'
              f'{e}_step = 1\nx.{e}_options = 2\nhelp = "runs on {e.capitalize()} only"\n')
    assert [line for line, _ in engine_names_in(source)] == [4, 5, 6, 7]
    assert engine_names_in(source, path=f"comparisons/stages/{e}_study.py") == []


def test_the_built_in_names_are_the_declared_ones():
    assert len(NAMES) >= 4 and "reference" not in NAMES


def test_the_harness_names_no_engine():
    files = harness_files()
    assert "comparisons/cli/main.py" in files and "engines/__init__.py" in files
    hits = {path: engine_names_in((ROOT / path).read_text(encoding="utf-8"), path)
            for path in files}
    hits = {path: h for path, h in hits.items() if h}
    assert not hits, f"engine names in code: {hits}"
