"""The harness's file writing (comparisons/stages/files.py): a file appears whole or not at
all, with the permissions the umask gives, in UTF-8; the CSV cells are what Arrow's writer
gives (the oracle here: pyarrow's own C++ writer, and strings worked out by hand from its
documented shortest round-trip rule); a report folder is swapped in whole and an exception
leaves the old one as it was. Temporary folders only: a few milliseconds each."""

from __future__ import annotations

import io
import os
import sys

import numpy as np
import pytest

from comparisons.stages import files


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def _leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def test_a_file_appears_complete_with_the_umasks_permissions(tmp_path, umask_022):
    target = tmp_path / "deep" / "er" / "out.txt"          # its folders are made
    with files.atomic_path(target) as tmp:
        assert tmp.parent == target.parent and tmp != target
        assert tmp.name.startswith(".out.txt.") and tmp.name.endswith(".txt")
        tmp.write_text("whole")
        assert not target.exists()                          # not before the block ends
    assert target.read_text() == "whole"
    assert (target.stat().st_mode & 0o777) == 0o644         # 0o666 less the umask's 0o022
    assert _leftovers(target.parent) == []
    with files.atomic_path(tmp_path / "x.csv", suffix=".part") as tmp:
        assert tmp.name.endswith(".part")
        tmp.write_text("y")


def test_an_exception_leaves_the_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with files.atomic_path(target) as tmp:
            tmp.write_text("half")
            raise KeyboardInterrupt
    assert target.read_text() == "old" and _leftovers(tmp_path) == []


def test_a_write_error_names_the_file_being_written(tmp_path):
    import errno
    target = tmp_path / "out.txt"
    with pytest.raises(OSError) as info:
        with files.atomic_path(target):
            raise OSError(errno.ENOSPC, "No space left on device")
    exc = info.value
    assert exc.errno == errno.ENOSPC and exc.filename == str(target)
    assert exc.strerror == "No space left on device while writing"
    assert isinstance(exc.__cause__, OSError) and not target.exists()
    assert _leftovers(tmp_path) == []
    with pytest.raises(OSError) as info:                    # no strerror: the exception's text
        with files.atomic_path(target):
            raise FileNotFoundError("gone")
    assert info.value.strerror == "gone while writing"


def test_text_is_utf8_and_the_writers_return_the_path(tmp_path):
    """(UTF-8 under an ASCII locale needs a child process: tests/test_files_edges.py.)"""
    p = files.write_text(str(tmp_path / "a.md"), "π ≈ 3.14\n")
    assert p == tmp_path / "a.md" and isinstance(p, type(tmp_path))
    assert p.read_bytes() == "π ≈ 3.14\n".encode("utf-8")
    q = files.write_bytes(str(tmp_path / "b.bin"), b"\x00\xff")
    assert q == tmp_path / "b.bin" and q.read_bytes() == b"\x00\xff"


#: hand-worked cells: the shortest digits that read back, plain decimals for 1e-6 <= |v| <
#: 1e10 (no trailing '.0'), else d.ddde+X / d.ddde-X; NaN empty, infinities by name
CELLS = [(1.0, "1"), (-3.0, "-3"), (0.5, "0.5"), (0.0, "0"), (-0.0, "-0"), (100.0, "100"),
         (1e-4, "0.0001"), (1.2345e-5, "0.000012345"), (1e-5, "0.00001"), (1e-6, "0.000001"),
         (-2.5e-6, "-0.0000025"), (9.99999e-7, "9.99999e-7"), (1e-7, "1e-7"),
         (-2.5e-7, "-2.5e-7"), (123456789.0, "123456789"), (9999999999.0, "9999999999"),
         (9999999999.5, "9999999999.5"), (1e10, "1e+10"), (1.5e10, "1.5e+10"),
         (12345678901.0, "1.2345678901e+10"), (1e16, "1e+16"), (1.25e21, "1.25e+21"),
         (5e-324, "5e-324"), (1.7976931348623157e308, "1.7976931348623157e+308"),
         (float("nan"), ""), (float("inf"), "inf"), (float("-inf"), "-inf")]


@pytest.mark.parametrize("v, cell", CELLS)
def test_a_cell_is_the_shortest_decimal_arrow_writes(v, cell):
    assert files.arrow_float(v) == cell
    assert files.arrow_float(np.float64(v)) == cell      # numpy 2 reprs it np.float64(...)
    pa = pytest.importorskip("pyarrow")
    import pyarrow.csv as pa_csv
    buf = io.BytesIO()        # the oracle: Arrow's own writer
    pa_csv.write_csv(pa.table({"x": files._arrow_column(np.array([v]))}), buf,
                     pa_csv.WriteOptions(include_header=False))
    assert buf.getvalue().decode().strip() == cell


def test_the_plain_rows_of_each_kind_of_column():
    cols = [np.array([1.5, np.nan]), np.array([True, False]), np.array([3, -4]),
            np.array(['a"b,c', None], dtype=object), np.array([np.uint8(7), np.uint8(0)]),
            np.array([float("nan"), "t"], dtype=object), np.array([1.0, 2.0], dtype=np.float32)]
    assert files.plain_csv_rows(cols) == '1.5,true,3,"a""b,c",7,,1\n,false,-4,,0,"t",2\n'


def test_csv_bytes_header_and_rows_with_and_without_pyarrow(monkeypatch):
    frame = {"t": np.array([0.0, 0.001]), "ok": np.array([True, False]),
             "name": np.array(["x", None], dtype=object)}
    expected = b't,ok,name\n0,true,"x"\n0.001,false,\n'
    assert files.csv_bytes(frame) == expected
    pd = pytest.importorskip("pandas")
    assert files.csv_bytes(pd.DataFrame(frame)) == expected
    monkeypatch.setitem(sys.modules, "pyarrow", None)       # the core install: no pyarrow
    assert files.csv_bytes(frame) == expected
    for bad in ("a,b", 'q"', "two\nlines"):
        with pytest.raises(ValueError, match="needs quoting"):
            files.csv_bytes({bad: np.zeros(1)})


def test_write_csv_writes_csv_bytes(tmp_path):
    p = files.write_csv({"a": np.array([1, 2])}, str(tmp_path / "a.csv"))
    assert p == tmp_path / "a.csv" and p.read_bytes() == b"a\n1\n2\n"


def test_an_arrow_column_keeps_nan_as_null_and_other_types_as_they_are():
    pa = pytest.importorskip("pyarrow")
    col = files._arrow_column(np.array([1.0, np.nan, 3.0])[::1])
    assert col.type == pa.float64() and col.null_count == 1
    assert col.to_pylist() == [1.0, None, 3.0]
    strided = files._arrow_column(np.arange(6.0)[::2])      # not contiguous: copied
    assert strided.to_pylist() == [0.0, 2.0, 4.0] and strided.null_count == 0
    assert files._arrow_column(np.array([1, 2])).type == pa.int64()


def test_a_new_report_folder_is_renamed_in_whole_with_its_manifest(tmp_path, umask_022):
    out = tmp_path / "sub" / "report"
    with files.ReportFolder(out) as folder:
        assert folder.path.parent == out.parent and folder.path.name.startswith(".report.partial-")
        assert (folder.path.stat().st_mode & 0o777) == 0o755
        files.write_text(folder.path / "report.md", "r\n")
        files.write_text(folder.path / "figures" / "a.png", "p\n")
        assert not out.exists()
    assert (out / files.MANIFEST).read_text() == "figures/a.png\nreport.md\n"
    assert (out / "figures" / "a.png").read_text() == "p\n"
    assert sorted(p.name for p in out.parent.iterdir()) == ["report"]


def test_a_failed_report_leaves_the_old_one_and_no_staging(tmp_path):
    out = tmp_path / "report"
    with files.ReportFolder(out) as folder:
        files.write_text(folder.path / "report.md", "old\n")
    with pytest.raises(RuntimeError):
        with files.ReportFolder(out) as folder:
            files.write_text(folder.path / "report.md", "new\n")
            raise RuntimeError("a stage failed")
    assert (out / "report.md").read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]


def test_a_second_report_replaces_the_first_and_removes_its_emptied_folders(tmp_path):
    out = tmp_path / "report"
    with files.ReportFolder(out) as folder:
        for name in ("report.md", "figures/a.png", "data/x.csv"):
            files.write_text(folder.path / name, "1\n")
    (out / "figures" / "mine.txt").write_text("the user's\n")   # keeps figures/ alive
    with files.ReportFolder(out) as folder:
        files.write_text(folder.path / "report.md", "2\n")
        files.write_text(folder.path / "summary.json", "{}\n")
    assert (out / "report.md").read_text() == "2\n"
    assert not (out / "figures" / "a.png").exists() and not (out / "data").exists()
    assert (out / "figures" / "mine.txt").read_text() == "the user's\n"
    assert (out / files.MANIFEST).read_text() == "report.md\nsummary.json\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]


def test_a_name_the_writer_never_produces_is_refused_at_the_swap(tmp_path):
    out = tmp_path / "report"
    out.mkdir()
    with pytest.raises(OSError, match="notes.txt: not a file a report may write"):
        with files.ReportFolder(out, force=True) as folder:
            files.write_text(folder.path / "notes.txt", "x\n")
    assert list(out.iterdir()) == [] and sorted(p.name for p in tmp_path.iterdir()) == ["report"]


def test_the_swap_is_not_cut_by_a_signal(tmp_path, monkeypatch):
    """SIGINT and SIGTERM are blocked while the files move in, and unblocked after."""
    import signal
    seen = []
    real = files.ReportFolder._swap

    def swap(self, staged):
        seen.append(signal.pthread_sigmask(signal.SIG_BLOCK, set()))
        return real(self, staged)

    monkeypatch.setattr(files.ReportFolder, "_swap", swap)
    with files.ReportFolder(tmp_path / "r") as folder:
        files.write_text(folder.path / "report.md", "x\n")
    (during,) = seen
    assert {signal.SIGINT, signal.SIGTERM} <= set(during)
    assert not {signal.SIGINT, signal.SIGTERM} & set(signal.pthread_sigmask(signal.SIG_BLOCK,
                                                                           set()))
