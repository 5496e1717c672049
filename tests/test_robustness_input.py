"""User mistakes that gave tracebacks or silent results (issue 23, "Tracebacks for user
mistakes" and "Honest verdicts"; docs/robustness.md): each is one line naming the option or the
field and the fix, exit 2, or an honest verdict. In-process through the CLI's ``main``; about
4-6 s in all (most of it simulate and two compare-trajectory runs of stability-psid5 on the reference).
"""

from __future__ import annotations

import csv
import os
import stat

import numpy as np
import pytest

from comparisons.cli import main


def _err(capsys) -> list[str]:
    return capsys.readouterr().err.strip().splitlines()


@pytest.fixture(scope="module")
def psid5_rows(tmp_path_factory) -> list[list[str]]:
    """The reference's own stability-psid5 run as a CSV (simulate's documented columns)."""
    out = tmp_path_factory.mktemp("psid5") / "run.csv"
    assert main(["simulate", "--scenario", "stability-psid5", "--out", str(out)]) == 0
    with open(out, newline="") as f:
        return list(csv.reader(f))


def _write(path, rows) -> str:
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(rows)
    return str(path)


def test_a_short_run_is_not_assessed_never_a_fall(tmp_path, capsys, psid5_rows):
    """The issue's case: 3 rows of stability-psid5 (lean 0.2 rad, far from the 1.4 rad fall
    limit) said 'fell at 0.020 s'. Now the trajectory and the claim are 'not assessed', and
    the whole run, which does fall, is still judged a fall (the control)."""
    lean = float(psid5_rows[3][psid5_rows[0].index("theta")])
    assert abs(lean) < 0.5      # the file's own lean: nowhere near a fall
    short = _write(tmp_path / "short.csv", psid5_rows[:4])
    assert main(["compare-trajectory", "--scenario", "stability-psid5", "--csv", short]) == 0
    out = capsys.readouterr().out
    assert "fell" not in out.replace("not a fall", ""), out
    assert "trajectory" in out and "not assessed" in out.split("trajectory", 1)[1].splitlines()[0]
    assert "claim stability-psid5: not assessed" in out
    whole = _write(tmp_path / "whole.csv", psid5_rows)
    assert main(["compare-trajectory", "--scenario", "stability-psid5", "--csv", whole]) == 0
    out = capsys.readouterr().out
    assert "a fall" in out and "claim stability-psid5: reproduced" in out, out


@pytest.mark.parametrize("cell", ["abc", "1,5"])
def test_a_cell_that_is_not_a_number_is_one_line(tmp_path, capsys, psid5_rows, cell):
    rows = [list(r) for r in psid5_rows]
    rows[3][rows[0].index("psi")] = cell
    bad = _write(tmp_path / "bad.csv", rows)
    assert main(["compare-trajectory", "--scenario", "stability-psid5", "--csv", bad]) == 2
    err = _err(capsys)
    assert len(err) == 1 and "column psi, row 4" in err[0] and repr(cell) in err[0], err


def test_a_column_named_twice_is_refused(tmp_path, capsys, psid5_rows):
    """pandas reads the first of two 'theta' columns and renames the second: refused."""
    rows = [r + [r[psid5_rows[0].index("theta")]] for r in psid5_rows]
    rows[0][-1] = "theta"
    dup = _write(tmp_path / "dup.csv", rows)
    assert main(["compare-trajectory", "--scenario", "stability-psid5", "--csv", dup]) == 2
    err = _err(capsys)
    assert len(err) == 1 and "theta appear more than once" in err[0], err


@pytest.mark.parametrize("out", [".", "", ".."])
def test_export_to_a_folder_name_is_one_line(tmp_path, monkeypatch, capsys, out):
    monkeypatch.chdir(tmp_path)
    assert main(["export", "--format", "json", "--out", out]) == 2
    err = _err(capsys)
    assert len(err) == 1 and "names no file" in err[0], err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("name", ["a\nb", "a\x01b", "tab\there"])
def test_import_name_with_a_control_character_is_one_line(tmp_path, capsys, name):
    src = tmp_path / "b.toml"
    assert main(["export", "--format", "benchmark", "--model", "benchmark", "--out", str(src)]) == 0
    capsys.readouterr()
    assert main(["import", str(src), "--from", "benchmark", "--out", str(tmp_path / "n.toml"),
                 "--name", name]) == 2
    err = _err(capsys)
    assert len(err) == 1 and "--name holds the control character" in err[0], err
    assert not (tmp_path / "n.toml").exists()


def test_benchmark_txt_with_a_bom_is_read_and_files_get_the_umask_mode(tmp_path, capsys):
    """A BOM (as Windows editors write) is accepted as in TOML files; what import and export
    write has the mode any new file gets (0666 less the umask), not mkstemp's 0600."""
    txt = tmp_path / "b.txt"
    assert main(["export", "--format", "benchmark", "--model", "benchmark", "--out", str(txt)]) == 0
    bom = tmp_path / "bom.txt"
    bom.write_bytes(b"\xef\xbb\xbf" + txt.read_bytes())
    out = tmp_path / "bom.toml"
    assert main(["import", str(bom), "--from", "benchmark", "--out", str(out)]) == 0
    mask = os.umask(0o022)
    os.umask(mask)
    for f in (txt, out):
        assert stat.S_IMODE(f.stat().st_mode) == 0o666 & ~mask, (f, oct(f.stat().st_mode))
    from reference_model import load_model
    a, b = load_model(str(out)).params, load_model("benchmark").params
    assert np.isclose(a.m3, b.m3) and np.isclose(a.I3xz, b.I3xz)


@pytest.mark.parametrize("speeds", ["0:10:1e8", "0:10:10.5"])
def test_a_step_beyond_the_range_is_refused(capsys, tmp_path, speeds):
    """0:10:1e8 computed the one speed 0 without a word (the step read as a count?)."""
    assert main(["eigenvalues", "--model", "benchmark", "--speeds", speeds,
                 "--out", str(tmp_path / "e.csv")]) == 2
    err = _err(capsys)
    assert len(err) == 1 and "larger than the range" in err[0], err


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf"])
def test_stage_timeout_must_be_a_positive_time(capsys, tmp_path, value):
    assert main(["run", "--quick", "--stage-timeout", value, "--out", str(tmp_path / "r")]) == 2
    err = _err(capsys)
    assert len(err) == 1 and "--stage-timeout must be a positive" in err[0], err
    assert not (tmp_path / "r").exists()


def test_conformance_xfails_mistakes_are_usage_errors(tmp_path):
    """Were a pytest INTERNALERROR: an --xfails-file that is not UTF-8, an engine's
    conformance_xfails naming no file, a number, a list."""
    from comparisons.conformance.plugin import declared_xfails, read_xfails

    latin = tmp_path / "x.txt"
    latin.write_bytes("test_x  # caf\xe9\n".encode("latin-1"))
    with pytest.raises(pytest.UsageError, match=r"not UTF-8 text \(byte 13\)"):
        read_xfails(latin)

    class Declares:
        name = "mine"

    for value, words in ((str(tmp_path / "none.txt"), "names no file"), (3, "is int"),
                         (["test_x"], "is list")):
        Declares.conformance_xfails = value
        with pytest.raises(pytest.UsageError, match=f"engine 'mine': its conformance_xfails {words}"):
            declared_xfails(Declares())
    Declares.conformance_xfails = {"test_x[*]": "why"}      # the control: a mapping is read
    assert declared_xfails(Declares()) == {"test_x[*]": "why"}
