"""The refusals of ``--out`` (comparisons/stages/ownership.py, `check_out_folder`), word for
word, and the project root recognised whatever the machine's locale.

The contract (the function's docstring, docs/report.md after the table of files, README's
"run --out DIR" paragraph): a folder inside the installed packages, a folder holding this
project's sources, a ``figures`` or ``data`` in ``--out`` that is a symbolic link or not a
folder, and a non-empty folder without an earlier report (unless ``--force``) are refused
with ONE line that names the folder, says why, and says what to do; `run` prints that line
and exits 2 before any stage (comparisons/cli/main.py). The lines are what a user reads, so
they are asserted whole. Independent checks of what they promise: the fix each suggests is
one `check_out_folder` accepts (``--out reports/latest``, an empty or new folder, ``--force``),
and the files ``--force`` is said to overwrite are the report writer's own names
(`REPORT_FILES`, `REPORT_FOLDERS`).

`_is_project_root` reads pyproject.toml as UTF-8, as TOML files are (the TOML specification:
"A TOML file must be a valid UTF-8 encoded Unicode document"), not in the locale's encoding: a
copy of the project whose pyproject.toml holds non-ASCII text is refused on a machine whose
locale encoding is ASCII (a POSIX locale, no coercion) or cp1252 (Windows) too. Those machines
are stood in for by `io.text_encoding`, the hook through which pathlib turns
``encoding=None`` into the locale's encoding.

Each test names the planted bugs (mutmut's survivors of the module's measurement) it was
seen failing on. Folders live in tmp_path; nothing is run; the file takes well under a second.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import pytest

import reference_model
from comparisons.stages.ownership import (MANIFEST, REPORT_FILES, REPORT_FOLDERS,
                                          OutFolderError, check_out_folder)

#: what the non-empty-folder refusal says after "--out DIR "
NOT_OURS = ("holds files and no earlier report of bicycle-xval; choose an empty or new folder, "
            "or add --force to overwrite only the files the report writes (report.md, "
            "summary.json, figures/, data/ ...) and keep the rest")


def _refusal(out, force: bool = False) -> str:
    with pytest.raises(OutFolderError) as err:
        check_out_folder(out, force)
    message = str(err.value)
    assert "\n" not in message, message                 # one line, printed as it is
    return message


def _project_copy(folder: Path, extra: str = "") -> Path:
    folder.mkdir()
    (folder / "pyproject.toml").write_text(f'[project]\nname = "bicycle-xval"\n{extra}',
                                           encoding="utf-8")
    return folder


def test_a_folder_inside_a_package_is_refused_naming_the_package_and_a_folder_to_use(
        tmp_path, monkeypatch):
    """`--out reference_model/reports`: the line names the folder given, the package folder it
    lies in, and suggests --out reports/latest, which (relative to a working folder outside
    the project) is accepted. Planted: the suggestion's text padded ("XXreport elsewhere, ...
    reports/latestXX") or upper-cased ("REPORT ELSEWHERE, E.G. --OUT REPORTS/LATEST")."""
    pkg = Path(reference_model.__file__).resolve().parent
    out = pkg / "reports"
    assert _refusal(out, force=True) == (
        f"--out {out} is inside the package folder {pkg}; write the report elsewhere, "
        "e.g. --out reports/latest")
    assert not out.exists()
    monkeypatch.chdir(tmp_path)
    check_out_folder(Path("reports/latest"))            # the suggested folder is fine


def test_a_copy_of_the_sources_is_refused_with_a_folder_of_its_own_suggested(tmp_path,
                                                                             monkeypatch):
    """A folder with this project's pyproject.toml, even with --force: the line says it holds
    the bicycle-xval sources and suggests a folder of its own, --out reports/latest, which
    is accepted inside it. Planted: that suggestion padded ("XXinto a folder of its own, ...
    reports/latestXX") or upper-cased ("INTO A FOLDER OF ITS OWN, E.G. --OUT REPORTS/LATEST")."""
    copy = _project_copy(tmp_path / "copy")
    assert _refusal(copy, force=True) == (
        f"--out {copy} holds the bicycle-xval sources; write the report into a folder of its "
        "own, e.g. --out reports/latest")
    monkeypatch.chdir(copy)
    check_out_folder(Path("reports/latest"))            # a new folder below the sources is not


@pytest.mark.parametrize("sub", sorted(REPORT_FOLDERS))
@pytest.mark.parametrize("kind", ["symlink", "file"])
def test_a_report_subfolder_that_is_a_link_or_a_file_is_refused_saying_what_to_do(
        tmp_path, sub, kind):
    """figures or data in --out as a symbolic link (to a folder elsewhere) or as a plain file,
    with --force and with a manifest: the line names the folder and the subfolder, says the
    report writes sub/ inside --out only, and to remove it or choose another folder; once
    removed, the folder is accepted. Planted: the last words padded ("XXanother folderXX")
    or upper-cased ("ANOTHER FOLDER")."""
    out = tmp_path / "r"
    out.mkdir()
    (out / MANIFEST).write_text("report.md\n")
    if kind == "symlink":
        (tmp_path / "elsewhere").mkdir()
        os.symlink(tmp_path / "elsewhere", out / sub)
    else:
        (out / sub).write_text("not a folder\n")
    assert _refusal(out, force=True) == (
        f"--out {out}: {sub} is a symbolic link or not a folder; the report writes {sub}/ "
        "inside --out only: remove it or choose another folder")
    (out / sub).unlink()                                # what the line says to do
    check_out_folder(out)
    assert (tmp_path / "elsewhere").exists() or kind == "file"


def test_someone_elses_folder_is_refused_with_the_force_it_may_be_given(tmp_path):
    """A non-empty folder with no manifest: the line names it, says it holds no earlier report,
    and offers an empty or new folder or --force, which overwrites only the report's files
    (the names it lists are the writer's: REPORT_FILES and the REPORT_FOLDERS) and keeps the
    rest. Each offer is accepted. Planted: any part of the offer padded with XX ("XXchoose
    an empty ... only XX", "XXthe files the report writes ...XX", "XXdata/ ... restXX") or
    upper-cased ("THE FILES THE REPORT WRITES (REPORT.MD, ...", "DATA/ ...) AND KEEP THE
    REST")."""
    out = tmp_path / "theirs"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    assert _refusal(out) == f"--out {out} {NOT_OURS}"
    listed = NOT_OURS[NOT_OURS.index("(") + 1:NOT_OURS.index(" ...)")].split(", ")
    assert {n for n in listed if "/" not in n} <= REPORT_FILES
    assert {n.rstrip("/") for n in listed if "/" in n} == set(REPORT_FOLDERS)
    check_out_folder(out, force=True)                   # add --force
    check_out_folder(tmp_path / "new")                  # a new folder
    (tmp_path / "empty").mkdir()
    check_out_folder(tmp_path / "empty")                # an empty one


def test_a_symlinked_manifest_is_no_earlier_report(tmp_path):
    """A manifest that is a symbolic link (to a list elsewhere) does not make the folder an
    earlier report: the same refusal as with no manifest; a real one is accepted."""
    out = tmp_path / "r"
    out.mkdir()
    (tmp_path / "list").write_text("report.md\n")
    os.symlink(tmp_path / "list", out / MANIFEST)
    assert _refusal(out) == f"--out {out} {NOT_OURS}"
    (out / MANIFEST).unlink()
    (out / MANIFEST).write_text("report.md\n")
    check_out_folder(out)


@pytest.mark.parametrize("locale_encoding", ["ascii", "cp1252"])
def test_the_project_root_is_recognised_when_the_locale_is_not_utf8(tmp_path, monkeypatch,
                                                                    locale_encoding):
    """A copy of the project whose pyproject.toml lists an author "Ágúst Þór" (UTF-8, as TOML
    must be) is refused as the sources on a machine whose locale encoding is ASCII or cp1252,
    where these bytes do not decode (0xC3 is not ASCII; 0x81, the second byte of "Á", is
    undefined in cp1252). Such a machine is stood in for by `io.text_encoding`, which pathlib
    asks for the encoding when none is given; the same file read with the patch in place
    proves the stand-in bites. Planted: pyproject.toml read with encoding=None (the locale's):
    the decoding error is taken for "not a pyproject" and the sources are written into."""
    copy = _project_copy(tmp_path / "copy", 'authors = [{name = "Ágúst Þór"}]\n')
    real = io.text_encoding

    def locale_is(encoding, stacklevel=2):
        return locale_encoding if encoding is None else real(encoding, stacklevel)

    monkeypatch.setattr(io, "text_encoding", locale_is)
    with pytest.raises(UnicodeDecodeError):
        (copy / "pyproject.toml").read_text()           # the locale's encoding fails here
    assert _refusal(copy, force=True) == (
        f"--out {copy} holds the bicycle-xval sources; write the report into a folder of its "
        "own, e.g. --out reports/latest")
