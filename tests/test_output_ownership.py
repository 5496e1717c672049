"""Who owns the files of an output folder (issue 23): a report folder's manifest is believed
only for the names the report writer produces, inside ``--out``, never through a symbolic
link; someone else's non-empty folder is refused unless ``--force``; the package folders are
never written into. `ReportFolder` is tested directly (no runs: a few milliseconds each); the
command line once, for the one-line refusal before any stage runs.
"""

import os
import shutil
from pathlib import Path

import pytest

import reference_model
from comparisons.cli import main
from comparisons.stages.files import MANIFEST, ReportFolder, write_text
from comparisons.stages.ownership import OutFolderError, is_report_name

VICTIM = "the user's own file\n"


def _report(out: Path, force: bool = False, names=("report.md", "summary.json")) -> None:
    with ReportFolder(out, force) as folder:
        for name in names:
            write_text(folder.path / name, "new\n")


def test_crafted_manifest_deletes_nothing_outside_out_nor_files_it_never_writes(tmp_path):
    out = tmp_path / "box" / "r"
    (out / "figures").mkdir(parents=True)
    (tmp_path / "box" / "elsewhere").mkdir()
    victims = [tmp_path / "victim", tmp_path / "abs_victim", tmp_path / "box" / "victim2",
               tmp_path / "box" / "elsewhere" / "linked.png", out / "notes.txt",
               out / "figures" / "deep" / "x.png"]
    for v in victims:
        v.parent.mkdir(parents=True, exist_ok=True)
        v.write_text(VICTIM)
    os.symlink(tmp_path / "box" / "elsewhere" / "linked.png", out / "figures" / "link.png")
    os.symlink(tmp_path / "victim", out / "report.html")
    entries = ["../../victim", str(tmp_path / "abs_victim"), "figures/../../victim2",
               "figures/link.png", "report.html", "notes.txt", "figures/deep/x.png",
               "./summary.json", "figures/"]
    (out / MANIFEST).write_text("\n".join(entries) + "\n")
    _report(out)
    assert all(v.read_text() == VICTIM for v in victims), [v for v in victims if not v.exists()]
    assert (out / "figures" / "link.png").is_symlink() and (out / "report.html").is_symlink()
    assert (out / "report.md").read_text() == "new\n"
    assert (out / MANIFEST).read_text().split() == ["report.md", "summary.json"]


def test_manifest_entries_under_a_symlinked_folder_are_not_followed(tmp_path):
    out, elsewhere = tmp_path / "r", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (elsewhere / "a.csv").write_text(VICTIM)
    os.symlink(elsewhere, out / "data")
    (out / MANIFEST).write_text("data/a.csv\n")
    with pytest.raises(OutFolderError, match="data is a symbolic link"):
        _report(out)
    assert (elsewhere / "a.csv").read_text() == VICTIM


def test_the_writers_own_names_are_the_only_trusted_ones():
    # the set is the writer's (comparisons/report/writer.py): four top-level files, figures/*.png,
    # data/*.csv, one level down
    for name in ("report.md", "report.html", "summary.json", "timings.json",
                 "figures/check-forward_trajectories.png", "data/check-forward_reference.csv"):
        assert is_report_name(name), name
    for name in ("../victim", "/abs/victim", "figures/../../victim", "notes.txt",
                 "figures/x.csv", "data/x.png", "figures/a/b.png", "figures//x.png",
                 "./report.md", "report.md/", "figures\\x.png", "", "figures/.png"):
        assert not is_report_name(name), name


def test_an_earlier_reports_files_are_still_replaced_and_removed(tmp_path):
    out = tmp_path / "r"
    _report(out, names=("report.md", "figures/a.png", "data/a.csv"))
    _report(out, names=("report.md",))
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "report.md"]   # emptied folders go


def test_someone_elses_folder_is_refused_and_with_force_keeps_its_files(tmp_path):
    out = tmp_path / "theirs"
    (out / "data").mkdir(parents=True)
    mine = {out / "notes.txt": VICTIM, out / "data" / "mine.csv": VICTIM,
            out / "report.md": "my own report\n"}
    for f, text in mine.items():
        f.write_text(text)
    with pytest.raises(OutFolderError, match="--force"):
        _report(out)
    assert all(f.read_text() == text for f, text in mine.items())
    _report(out, force=True)
    assert (out / "notes.txt").read_text() == VICTIM == (out / "data" / "mine.csv").read_text()
    assert (out / "report.md").read_text() == "new\n"          # what the harness writes
    _report(out)                                                # now it holds a manifest
    assert (out / "notes.txt").read_text() == VICTIM


def test_empty_folder_is_accepted(tmp_path):
    _report(tmp_path / "empty")
    (tmp_path / "new").mkdir()
    _report(tmp_path / "new")
    assert (tmp_path / "new" / "report.md").is_file()


def test_out_inside_a_package_or_the_project_root_is_refused(tmp_path):
    pkg = Path(reference_model.__file__).resolve().parent
    root = pkg.parent
    for bad in (pkg, pkg / "reports"):
        with pytest.raises(OutFolderError, match="package folder"):
            ReportFolder(bad, force=True)
    if (root / "pyproject.toml").is_file():
        with pytest.raises(OutFolderError, match="sources"):
            ReportFolder(root, force=True)
    assert not (pkg / "reports").exists()


def test_run_into_the_package_is_one_line_before_any_stage(tmp_path, capsys):
    bad = Path(reference_model.__file__).resolve().parent / "report"
    try:
        assert main(["run", "--quick", "--scenarios", "check", "--engines", "reference",
                     "--out", str(bad)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "package folder" in err, err   # no stage's line
        assert not bad.exists()
    finally:                                    # a planted bug must not leave a report there
        shutil.rmtree(bad, ignore_errors=True)


def test_a_copy_of_the_project_is_refused_and_another_projects_folder_is_not(tmp_path):
    from comparisons.stages.ownership import check_out_folder
    copy = tmp_path / "copy"
    copy.mkdir()
    (copy / "pyproject.toml").write_text('[project]\nname = "bicycle-xval"\n', encoding="utf-8")
    with pytest.raises(OutFolderError, match="holds the bicycle-xval sources"):
        check_out_folder(copy, force=True)
    # another project's, a pyproject without [project], one that is not TOML: someone else's
    # folder (refused without --force, as any non-empty folder), never the sources
    for i, text in enumerate(('[project]\nname = "other"\n', "[tool.x]\na = 1\n", "not = [toml")):
        other = tmp_path / f"other{i}"
        other.mkdir()
        (other / "pyproject.toml").write_text(text, encoding="utf-8")
        check_out_folder(other, force=True)
        with pytest.raises(OutFolderError, match="no earlier report"):
            check_out_folder(other)                     # force defaults to False
    # a folder named pyproject.toml is not a pyproject
    odd = tmp_path / "odd"
    (odd / "pyproject.toml").mkdir(parents=True)
    check_out_folder(odd, force=True)


def test_a_file_as_out_is_refused_in_one_line(tmp_path):
    from comparisons.stages.ownership import check_out_folder
    f = tmp_path / "report.md"
    f.write_text("x")
    with pytest.raises(OutFolderError) as err:
        check_out_folder(f, force=True)
    assert str(err.value) == f"--out {f} is a file; give a folder for the report"


def test_names_with_a_backslash_or_a_nul_are_never_the_writers():
    # PurePosixPath takes both as ordinary characters: "figures/a\\b.png" would pass the shape
    for name in ("figures/a\\b.png", "data/a\0.csv", "report.md\0"):
        assert not is_report_name(name), repr(name)
