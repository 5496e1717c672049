"""BicycleParameters' ten measured bicycles, where pip installed them, read independently of
the project (tests/test_bicycleparameters.py and tests/test_linear_closed_form.py).

The ``<Name>Benchmark.txt`` files ship inside the ``bicycleparameters`` package on PyPI
(``bicycleparameters/app-data/bicycles/<Name>/Parameters/``; BSD-2-Clause, the BicycleParameters
authors), a test dependency (pyproject's ``test`` extra). Only the package's location is looked
up here; nothing is copied into this repository. Values are the nominal ones (the files'
``+/-`` uncertainties are dropped).
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import numpy as np

from reference_model.benchmark import BENCHMARK_NAMES
from reference_model.benchmark_files import write_import

SETS = ("Benchmark", "Browser", "Browserins", "Crescendo", "Fisher", "Pista", "Rigid", "Silver",
        "Yellow", "Yellowrev")
_LINE = re.compile(r"^\s*(\w+)\s*=\s*([-+0-9.eE]+)\s*(?:\+/-\s*[-+0-9.eE]+)?\s*$")


def shipped(name: str) -> Path:
    """The installed ``<name>Benchmark.txt``."""
    spec = importlib.util.find_spec("bicycleparameters")
    assert spec is not None and spec.submodule_search_locations, (
        "the test dependency bicycleparameters is not installed: pip install -e '.[test]'")
    root = Path(next(iter(spec.submodule_search_locations)))
    return root / "app-data" / "bicycles" / name / "Parameters" / f"{name}Benchmark.txt"


def file_values(path: Path) -> dict[str, float]:
    """Every ``name = value+/-u`` of a BicycleParameters file (the extras too), by regex."""
    values = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        m = _LINE.match(line)
        assert m, f"{path.name}: unexpected line {line!r}"
        values[m.group(1)] = float(m.group(2))
    return values


def table1(path: Path) -> dict[str, float]:
    """Table 1's 26 values of a BicycleParameters file."""
    values = file_values(path)
    return {k: values[k] for k in BENCHMARK_NAMES}


def breaks_triangle(b: dict[str, float]) -> bool:
    """Whether a body's principal moments (numpy, here) break the triangle inequality."""
    tensors = ((b["IRxx"], b["IRyy"], b["IRxx"], 0.0), (b["IBxx"], b["IByy"], b["IBzz"], b["IBxz"]),
               (b["IHxx"], b["IHyy"], b["IHzz"], b["IHxz"]), (b["IFxx"], b["IFyy"], b["IFxx"], 0.0))
    for xx, yy, zz, xz in tensors:
        m = np.sort(np.linalg.eigvalsh(np.array([[xx, 0, xz], [0, yy, 0], [xz, 0, zz]])))
        if m[0] + m[1] < m[2]:
            return True
    return False


def import_shipped(name: str, folder: Path) -> Path:
    """The set imported by the project's import path into ``folder``/<name>.toml (the triangle
    inequality allowed where the set breaks it, as ``bicycle-xval import
    --allow-triangle-violation``)."""
    path, written = shipped(name), folder / f"{name}.toml"
    write_import(path, written, allow_triangle_violation=breaks_triangle(table1(path)))
    return written
