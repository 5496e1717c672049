"""Edges of the harness's file writing (comparisons/stages/files.py) that tests/test_files.py
leaves open: a pandas frame's own index never becomes a CSV column, a column name is refused
only for the three characters CSV would need to quote, a number in a text column is written
rather than dropped, text and the manifest are UTF-8 under a locale whose encoding is ASCII
(a real one, in a child process: Python 3.11's ``open`` asks the C library for the locale's
encoding, so patching the ``locale`` module changes nothing), and `ReportFolder`'s defaults
(no ``force``, missing parent folders made) and its clean-up after a failure.

The contract is the module's docstrings, docs/report.md ("Output", the manifest) and
docs/robustness.md ("Report writing": non-UTF-8 locale, someone else's folder). Expected CSV
bytes are written out by hand from `csv_bytes`' documented format (a header of the column
names, numbers as their shortest exact decimal, booleans true/false, text quoted). Temporary
folders only; the two child processes take ~0.1 s each, the rest a few milliseconds.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from comparisons.stages import files
from comparisons.stages.ownership import OutFolderError

ROOT = Path(__file__).resolve().parents[1]

#: a locale whose encoding is ASCII, kept so: no UTF-8 mode (PEP 540) and no coercion of the C
#: locale to C.UTF-8 (PEP 538), which Python would otherwise apply to LC_ALL=C
ASCII_LOCALE = {"LC_ALL": "C", "LANG": "C", "PYTHONUTF8": "0", "PYTHONCOERCECLOCALE": "0",
                "PYTHONIOENCODING": "utf-8"}


def _in_ascii_locale(code: str, *args: str) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter under `ASCII_LOCALE`, with this checkout first on
    its path; the locale's encoding is checked to be ASCII there (else the test proves
    nothing)."""
    prelude = textwrap.dedent(f"""\
        import locale, sys
        sys.path.insert(0, {str(ROOT)!r})
        assert locale.getpreferredencoding(False) in ("ANSI_X3.4-1968", "ascii"), \\
            locale.getpreferredencoding(False)
        """)
    env = {**os.environ, **ASCII_LOCALE}
    return subprocess.run([sys.executable, "-c", prelude + textwrap.dedent(code), *args],
                          env=env, capture_output=True, text=True, encoding="utf-8", timeout=60)


# --- CSV ------------------------------------------------------------------------------------

def test_a_frames_own_index_is_never_a_column_of_its_csv(monkeypatch):
    """`csv_bytes` writes a header of the frame's column names and then its rows (docstring):
    the frame's index is not among them, whatever it is. Expected bytes by hand: the sweep's
    rows of the bicycles that passed, picked by a mask (index 0, 1, 3: not a range, so Arrow
    would keep it as a column of its own), and the same rows indexed by the bicycles' names.
    The pyarrow-less writer must give the same bytes. Fails when the index is handed to
    Arrow's writer (``preserve_index`` at its default, None): a fourth field on every row
    under a header of three names, the rows no longer those of the header."""
    pd = pytest.importorskip("pandas")
    sweep = pd.DataFrame({"bicycle": [0, 1, 2, 3], "v_w": [4.29, 4.5, np.nan, 6.25],
                          "ok": [True, True, False, True]})
    passed = sweep[[True, True, False, True]]
    assert list(passed.index) == [0, 1, 3]                 # the case this test is about
    expected = b"bicycle,v_w,ok\n0,4.29,true\n1,4.5,true\n3,6.25,true\n"
    named = passed.set_index(pd.Index(["benchmark", "browser", "pista"], name="name"))
    for frame in (passed, named):
        assert files.csv_bytes(frame) == expected
    monkeypatch.setitem(sys.modules, "pyarrow", None)       # the core install: no pyarrow
    for frame in (passed, named):
        assert files.csv_bytes(frame) == expected


def test_only_the_three_characters_csv_would_quote_are_refused_in_a_column_name():
    """A column name is refused only when it holds a comma, a double quote or a newline
    (`csv_bytes` raises "needs quoting" for those, test_files.py); any other name, capitals,
    spaces, Greek letters and punctuation included, is written as it is in the header (UTF-8).
    Fails when the refused set grows (e.g. the literal ',"\\n' edited to hold other
    characters): the harness's own names such as "X" or "delta_dot" would stop a report."""
    names = ["X", "XX", "delta_dot [rad/s]", "δ", "a;b", "x'y", "t\tab"]
    frame = {name: np.array([1.0]) for name in names}
    header = ",".join(names).encode("utf-8") + b"\n"
    assert files.csv_bytes(frame) == header + b",".join([b"1"] * len(names)) + b"\n"


def test_a_number_in_a_text_column_is_written_quoted_not_dropped():
    """`plain_csv_rows` (the writer without pyarrow): in a column that is neither float, bool
    nor integer, "NaN and None empty, anything else quoted with its quotes doubled" (its
    docstring). So a float among texts (e.g. a failure column holding a message, a number, or
    nothing) is quoted with its repr, and only a NaN or None is an empty field. Fails when the
    NaN test is loosened to any float (``isinstance(x, float) or x != x``): 1.5 and 2.0 would
    vanish into empty fields, read back as missing."""
    col = np.array(["timed out", 1.5, None, float("nan"), 2.0, 'say "hi"'], dtype=object)
    assert files.plain_csv_rows([col]) == '"timed out"\n"1.5"\n\n\n"2.0"\n"say ""hi"""\n'


# --- UTF-8 whatever the locale -------------------------------------------------------------

def test_text_is_written_as_utf8_under_an_ascii_locale(tmp_path):
    """Module docstring, docs/robustness.md ("non-UTF-8 locale"): text is always UTF-8,
    whatever the locale. In a child process whose locale encoding is ASCII, `write_text` of
    the thesis symbols gives their UTF-8 bytes. Fails when the encoding is left to the locale
    (``encoding=None`` or omitted): UnicodeEncodeError on the first non-ASCII character, the
    file not written (before the fix: a 0-byte report.md)."""
    target = tmp_path / "report.md"
    text = "δ = 0.1 rad, φ̇ ≈ 2 rad/s, Θ\n"
    proc = _in_ascii_locale(f"""\
        from comparisons.stages import files
        files.write_text(sys.argv[1], {ascii(text)})
        """, str(target))
    assert proc.returncode == 0, proc.stderr[-800:]
    assert target.read_bytes() == text.encode("utf-8")


def test_a_manifest_with_a_non_ascii_line_is_read_under_an_ascii_locale(tmp_path):
    """The manifest is text the harness writes as UTF-8 (module docstring) and anyone may edit
    (docs/report.md: "any other entry of a list someone edited or handed over is ignored").
    A manifest listing report.md, summary.json and a user's line "notes-δ.txt" (bytes
    UTF-8), a report into that folder in a child process under an ASCII locale: the run
    succeeds, summary.json (listed, not written again) is removed, report.md replaced, and the
    new manifest lists report.md alone. Fails when the manifest is read in the locale's
    encoding: UnicodeDecodeError at the swap, the new report never moved in."""
    out = tmp_path / "report"
    out.mkdir()
    (out / "report.md").write_text("old\n")
    (out / "summary.json").write_text("{}\n")
    (out / files.MANIFEST).write_bytes("report.md\nsummary.json\nnotes-δ.txt\n".encode("utf-8"))
    proc = _in_ascii_locale("""\
        from pathlib import Path
        from comparisons.stages import files
        with files.ReportFolder(Path(sys.argv[1])) as folder:
            files.write_text(folder.path / "report.md", "new\\n")
        """, str(out))
    assert proc.returncode == 0, proc.stderr[-800:]
    assert (out / "report.md").read_text() == "new\n"
    assert sorted(p.name for p in out.iterdir()) == [files.MANIFEST, "report.md"]
    assert (out / files.MANIFEST).read_text() == "report.md\n"


# --- ReportFolder ---------------------------------------------------------------------------

def test_someone_elses_folder_is_refused_without_force_by_default(tmp_path):
    """`ReportFolder(out)` without ``force``: a non-empty folder with no manifest is refused
    (its docstring, docs/report.md: "a folder with other files and no list is refused ...
    unless you add --force"), and nothing in it changes. Fails when ``force`` defaults to True:
    the user's report.md would be overwritten without a word (docs/robustness.md, the
    "before" of that row)."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "report.md").write_text("the user's own\n")
    with pytest.raises(OutFolderError, match="holds files and no earlier report"):
        files.ReportFolder(out)
    assert (out / "report.md").read_text() == "the user's own\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine"]


def test_a_report_into_a_folder_several_levels_new_makes_them_all(tmp_path):
    """``--out a/b/c/report`` where none of a, b, c exists yet: the folders are made (as
    `atomic_path` does for a file) and the report lands there whole with its manifest. Fails
    when only the last missing parent may be made (``parents`` False or omitted):
    FileNotFoundError before any stage."""
    out = tmp_path / "a" / "b" / "c" / "report"
    with files.ReportFolder(out) as folder:
        files.write_text(folder.path / "report.md", "r\n")
    assert (out / "report.md").read_text() == "r\n"
    assert (out / files.MANIFEST).read_text() == "report.md\n"


@pytest.mark.parametrize("raised", [RuntimeError("a stage failed"), KeyboardInterrupt()])
def test_the_failure_surfaces_even_when_the_staging_folder_is_already_gone(tmp_path, raised):
    """`ReportFolder`'s docstring: on an exception (Ctrl-C, a failure) the staging folder is
    removed and ``out`` untouched; the exception is the one the user sees. Here the staging
    folder vanished before the failure (a stage that removed it, a cleaner of temporary
    folders): the clean-up has nothing to remove and must not raise its own error. Fails when
    the clean-up's errors are not ignored (``ignore_errors`` False or omitted): a
    FileNotFoundError about the staging folder replaces the stage's error or the Ctrl-C."""
    import shutil
    out = tmp_path / "report"
    with files.ReportFolder(out) as folder:
        files.write_text(folder.path / "report.md", "old\n")
    with pytest.raises(type(raised)) as info:
        with files.ReportFolder(out) as folder:
            files.write_text(folder.path / "report.md", "new\n")
            shutil.rmtree(folder.path)
            raise raised
    assert info.value is raised
    assert (out / "report.md").read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]
