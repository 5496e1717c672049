"""The sweep's default chunk format (comparisons/stages/sweep_chunks.py `default_writer`), which
the sweep's tests only ever pass explicitly: docs/sweep.md says chunks are Parquet where pyarrow
is installed, else CSV. ~0.1 s."""

from __future__ import annotations

import importlib.util
import sys

from comparisons.stages.sweep_chunks import default_writer


def test_parquet_where_pyarrow_is_installed_else_csv(monkeypatch):
    """With pyarrow importable (it is installed here, as the expectation says) the writer is
    "parquet"; with its import failing (a None entry in sys.modules makes `import pyarrow`
    raise ImportError) it is "csv", the two names `write_table` accepts. Planted: either name
    misspelt or upper-cased (write_table would refuse it)."""
    assert importlib.util.find_spec("pyarrow") is not None
    assert default_writer() == "parquet"
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    assert default_writer() == "csv"
