"""Two promises of the benchmark-file module (reference_model/parameters/benchmark_files.py)
that its other tests leave open: a written file has the mode of any new file, and a file that
starts with a UTF-8 byte-order mark reads like one without. ~0.1 s."""

from __future__ import annotations

import os

import pytest

from reference_model.parameters.benchmark_files import _write_atomically, read_benchmark_file

TABLE1 = ("w = 1.02\nc = 0.08\nlam = 0.3141592653589793\ng = 9.81\nrR = 0.3\nmR = 2.0\n"
          "IRxx = 0.0603\nIRyy = 0.12\nxB = 0.3\nzB = -0.9\nmB = 85.0\nIBxx = 9.2\nIByy = 11.0\n"
          "IBzz = 2.8\nIBxz = 2.4\nxH = 0.9\nzH = -0.7\nmH = 4.0\nIHxx = 0.05892\n"
          "IHyy = 0.06\nIHzz = 0.00708\nIHxz = -0.00756\nrF = 0.35\nmF = 3.0\nIFxx = 0.1405\n"
          "IFyy = 0.28\n")


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_a_written_file_has_the_mode_of_a_new_file(tmp_path, mask):
    """The docstring: 0666 less the umask, as open() would give, not the temporary's private
    0600. Compared with a file made by plain open() under the same umask. Planted: 0666 | ~mask,
    0667 & ~mask, 0666 & mask."""
    old = os.umask(mask)
    try:
        (tmp_path / "plain.txt").write_text("x")
        _write_atomically(tmp_path / "written.txt", "x")
    finally:
        os.umask(old)
    want = (tmp_path / "plain.txt").stat().st_mode & 0o7777
    assert want == 0o666 & ~mask
    assert (tmp_path / "written.txt").stat().st_mode & 0o7777 == want


def test_a_byte_order_mark_is_accepted_as_in_toml_files(tmp_path):
    """Table 1 in BicycleParameters' spelling, saved by an editor that starts UTF-8 files with
    a byte-order mark, reads to the same values as the same file without one. Planted: the
    file read in the locale's encoding (the mark becomes part of the first name, 'w')."""
    plain, marked = tmp_path / "PlainBenchmark.txt", tmp_path / "MarkedBenchmark.txt"
    plain.write_text(TABLE1, encoding="utf-8")
    marked.write_bytes(b"\xef\xbb\xbf" + TABLE1.encode("utf-8"))
    assert dict(read_benchmark_file(marked).values) == dict(read_benchmark_file(plain).values)
    assert read_benchmark_file(marked).values["w"] == 1.02
