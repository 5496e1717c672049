"""BicycleParameters' measured bicycles (issue 13's checks on real data).

The ten ``<Name>Benchmark.txt`` sets ship inside the ``bicycleparameters`` package on PyPI
(``tests/shipped_sets.py`` finds and parses them where pip installed them); the package's code
is not imported here (tests/test_linear_closed_form.py checks the closed form against it).

Expected values are independent of the code under test:

* Table 1 values parsed with a regular expression of the file's ``name = value+/-u`` lines;
* M, C1, K0, K2 from the benchmark's closed form (``comparisons/judgments/meijaard.py``, the
  paper's appendix; itself checked against BicycleParameters' own implementation in
  tests/test_linear_closed_form.py), eigenvalues from numpy on its 4x4 state matrix;
* which sets break the triangle inequality: the principal moments computed with numpy.

Tolerances are the issue's (and tests/test_import.py's, where they are argued): linear matrices
1e-10 relative to each matrix's largest entry, eigenvalues at 0..10 m/s 1e-10 relative to
max(1, |lambda|); the round trip benchmark -> TOML -> benchmark is exact (==).
"""

from __future__ import annotations

import numpy as np
import pytest

from comparisons.judgments.meijaard import (MATRICES, closed_form, closed_form_eigenvalues,
                                           max_matched_error)
from reference_model import load_model, load_parameters
from reference_model.benchmark import to_benchmark
from reference_model.benchmark_files import read_benchmark_file, write_import
from reference_model.linearize import eigenvalues, linearize
from reference_model.params import TriangleInequalityError
from shipped_sets import SETS, breaks_triangle, shipped, table1

TOL_MATRIX, TOL_EIG = 1e-10, 1e-10
SPEEDS = np.arange(0.0, 11.0)


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    """Each shipped set imported (strictly, or with the triangle allowed where it breaks it)."""
    out = tmp_path_factory.mktemp("bicycleparameters")
    result = {}
    for name in SETS:
        path = shipped(name)
        b = table1(path)
        broken = breaks_triangle(b)
        if broken:
            with pytest.raises(TriangleInequalityError):
                write_import(path, out / f"{name}-strict.toml")
            assert not (out / f"{name}-strict.toml").exists()
        written = out / f"{name}.toml"
        params = write_import(path, written, allow_triangle_violation=broken)
        result[name] = (b, broken, written, load_model(written))
        assert bool(params.warnings) == broken, name
    return result


def test_three_of_the_ten_break_the_triangle_inequality(imported):
    """The issue's count: three ship with a violation of 1-3 % (Browser, Yellow, Yellowrev)."""
    assert sum(broken for _, broken, _, _ in imported.values()) == 3


@pytest.mark.parametrize("name", SETS)
def test_linearization_matches_the_closed_form(imported, name):
    b, _, _, model = imported[name]
    assert model.name == f"{name}Benchmark" and model.contact == "disc"
    expected = closed_form(b)
    lin = linearize(model, 0.0)
    for key in MATRICES:
        mat = getattr(expected, key)
        err = np.max(np.abs(getattr(lin, key) - mat)) / np.max(np.abs(mat))
        assert err < TOL_MATRIX, f"{name} {key}: relative error {err:.2e}"
    worst = max(max_matched_error(closed_form_eigenvalues(expected, v),
                                  eigenvalues(model, v)) for v in SPEEDS)
    assert worst < TOL_EIG, f"{name}: eigenvalues 0..10 m/s off by {worst:.2e}"


@pytest.mark.parametrize("name", SETS)
def test_round_trip_is_exact(imported, name):
    b, _, written, _ = imported[name]
    assert to_benchmark(load_parameters(written)) == b


def test_the_extras_of_rigid_and_silver_are_said_not_dropped(imported):
    rigid = read_benchmark_file(shipped("Rigid"))
    assert any("handlebar (G)" in n for n in rigid.notes)
    assert any("fork (S)" in n for n in rigid.notes)
    assert "mH used as given" in imported["Rigid"][2].read_text(encoding="utf-8")
    silver = read_benchmark_file(shipped("Silver"))
    assert sorted(n.split(" =")[0] for n in silver.notes) == ["IFzz", "IRzz", "yB", "yH"]
    assert "IRzz = 0.078" in imported["Silver"][2].read_text(encoding="utf-8")
