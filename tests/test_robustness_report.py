"""The report folder under damage, interruption and hostile environments (issue: nothing lost,
nothing crashes, nothing silently wrong). Runs are the smallest that write a whole report
(the reference on the check scenario); signals: tests/test_shutdown.py.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from comparisons.cli import main
from comparisons.stages.files import MANIFEST, ReportFolder, write_text
from comparisons.stages.ownership import is_report_name

TINY = ["run", "--quick", "--scenarios", "check", "--engines", "reference"]
ROOT = Path(__file__).resolve().parents[1]


def _cli(*args, env=None, **kw):
    return subprocess.Popen([sys.executable, "-m", "comparisons.cli", *args], cwd=ROOT,
                            env=env or dict(os.environ), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, **kw)


@pytest.mark.slow
def test_run_never_touches_files_it_did_not_write(tmp_path):
    out = tmp_path / "r"
    (out / "data").mkdir(parents=True)
    (out / "figures").mkdir()
    mine = [out / "data" / "mine.csv", out / "figures" / "mine.png", out / "notes.txt"]
    for f in mine:
        f.write_text("the user's own file\n")
    assert main([*TINY, "--out", str(out), "--force"]) == 0   # a folder without a report
    assert main([*TINY, "--out", str(out)]) == 0          # and again, over its own report
    assert all(f.read_text() == "the user's own file\n" for f in mine)
    written = (out / MANIFEST).read_text().split()
    assert "summary.json" in written and "data/mine.csv" not in written
    assert all(is_report_name(w) for w in written)        # so the next run may replace them


def test_a_failed_stage_leaves_the_old_report_as_it_was(tmp_path):
    out = tmp_path / "r"
    out.mkdir()
    (out / "summary.json").write_text('{"passed": true}\n')
    (out / MANIFEST).write_text("summary.json\n")            # an earlier report
    with pytest.raises(RuntimeError):
        with ReportFolder(out) as folder:
            write_text(folder.path / "summary.json", '{"passed": false}\n')
            raise RuntimeError("killed half way")
    assert (out / "summary.json").read_text() == '{"passed": true}\n'
    assert [p.name for p in tmp_path.iterdir()] == ["r"]      # no staging folder left


@pytest.mark.slow
def test_report_is_utf8_whatever_the_locale(tmp_path):
    env = dict(os.environ, LANG="C", LC_ALL="C", PYTHONIOENCODING="ascii", PYTHONUTF8="0")
    proc = _cli(*TINY, "--out", str(tmp_path / "r"), env=env)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err[-800:]
    text = (tmp_path / "r" / "report.md").read_text(encoding="utf-8")
    assert text.startswith("# bicycle-xval report") and "Environment" in text
    json.loads((tmp_path / "r" / "summary.json").read_text(encoding="utf-8"))


def test_out_that_is_a_file_is_a_usage_error(tmp_path, capsys):
    f = tmp_path / "report"
    f.write_text("not a folder")
    assert main([*TINY, "--out", str(f)]) == 2
    assert "is a file" in capsys.readouterr().err
    assert f.read_text() == "not a folder"
