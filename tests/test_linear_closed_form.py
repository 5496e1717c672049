"""The benchmark's closed form (comparisons/judgments/meijaard.py) against a third-party
implementation, and the linearization check built on it (`bicycle-xval run --model`'s
"Linearization of <model> against the benchmark's closed form").

Expected values are independent of the code under test:

* BicycleParameters' own ``bicycleparameters.bicycle.benchmark_par_to_canonical`` (Moore's
  implementation of the same appendix, imported once per module: ~2 s) on its ten shipped sets,
  nominal values parsed by tests/shipped_sets.py;
* the critical speeds computed here from BicycleParameters' matrices: numpy eigenvalues of the
  4x4 state matrix, brentq on the real part of the complex pair (weave) and on the larger real
  eigenvalue (capsize), bracketed on a 0.05 m/s grid;
* Meijaard et al.'s printed matrices of the benchmark bicycle (comparisons/judgments/
  published.py, typed from the paper).

**Izz = Ixx of the wheels.** The paper's wheels have IRzz = IRxx, IFzz = IFxx; the closed form
reads only IRxx, IFxx, and ``benchmark_par_to_canonical`` overwrites IRzz, IFzz with them.
Only Silver's file gives IRzz and IFzz: the test checks they equal IRxx, IFxx, so nothing a file
says is dropped by that assumption.

Tolerances (each a claim):

* closed form vs BicycleParameters, 1e-12 relative to each matrix's largest entry: the same
  formulas in double, so they differ by rounding only (a reassociated sum of ~20 terms: ~1e-15);
  measured 0 (identical order of operations). A Table 1 value read wrongly or a term mistyped
  moves entries by far more (changing trail by 1e-9 m moves C1 by ~1e-8 relative).
* the check's critical speeds vs the ones computed here, 1e-9 m/s: brentq to 1e-14 on both
  sides on matrices equal to rounding; measured <= 2e-14.
* the benchmark bicycle's linearization at 5 m/s vs the printed matrices, 1e-13 absolute for
  M, C1, K0, K2 (14 printed decimals: rounding 5e-15, entries up to 81 carry a few ulps of
  1.4e-14), 1e-14 relative to the largest entry for K = g K0 + v^2 K2 and C = v C1 (entries
  up to 1.9e3, whose ulp is 2.3e-13; measured 4.8e-16). 5 m/s, so that v^2 != v.

Cost: ~2 s importing BicycleParameters, ~0.6 s for the ten checks, ~3 s for the file.
"""

from __future__ import annotations

import dataclasses
import math
import pickle

import numpy as np
import pytest
from scipy.optimize import brentq

import reference_model.linearize as linearize_module
from comparisons.judgments.meijaard import MATRICES, closed_form
from comparisons.judgments.published import MEIJAARD_MATRICES
from comparisons.stages.linear_check import linear_check
from comparisons.judgments.tolerances import load_tolerances
from reference_model import load_model
from reference_model.linearize import Linearization, linearize
from shipped_sets import SETS, file_values, import_shipped, shipped, table1

TOLS = load_tolerances()   # the packaged tolerances.toml, read once
TOL_CANONICAL, TOL_SPEED, TOL_PRINTED, TOL_K = 1e-12, 1e-9, 1e-13, 1e-14
V = 5.0


@pytest.fixture(scope="module")
def canonical():
    """BicycleParameters' M, C1, K0, K2 of each shipped set, by name (its code, imported once)."""
    from bicycleparameters.bicycle import benchmark_par_to_canonical
    out = {}
    for name in SETS:
        values = file_values(shipped(name))
        for wheel in ("R", "F"):          # the paper's Izz = Ixx (module docstring)
            if f"I{wheel}zz" in values:
                assert values[f"I{wheel}zz"] == values[f"I{wheel}xx"], name
        out[name] = dict(zip(MATRICES, (np.asarray(m, dtype=float)
                                        for m in benchmark_par_to_canonical(dict(values)))))
    return out


@pytest.fixture(scope="module")
def specs(tmp_path_factory):
    """Each shipped set imported by the project's import path: the spec linear_check takes."""
    out = tmp_path_factory.mktemp("linear-closed-form")
    return {name: str(import_shipped(name, out)) for name in SETS}


def _state(mats: dict, g: float, v: float) -> np.ndarray:
    Minv = np.linalg.inv(mats["M"])
    return np.block([[np.zeros((2, 2)), np.eye(2)],
                     [-Minv @ (g * mats["K0"] + v * v * mats["K2"]), -v * Minv @ mats["C1"]]])


def _weave(mats, g, v) -> float:
    lam = np.linalg.eigvals(_state(mats, g, v))
    pair = lam[np.abs(lam.imag) > 0]
    return float(pair.real.max()) if pair.size else math.nan


def _capsize(mats, g, v) -> float:
    lam = np.linalg.eigvals(_state(mats, g, v))
    real = lam[lam.imag == 0].real
    return float(real.max()) if real.size else math.nan


def _root(f, lo: float, hi: float, falling: bool) -> float | None:
    grid = np.linspace(lo, hi, int(round((hi - lo) / 0.05)) + 1)
    values = [f(v) for v in grid]
    for a, b, fa, fb in zip(grid, grid[1:], values, values[1:]):
        if (fa > 0 >= fb) if falling else (fa < 0 <= fb):
            return brentq(f, a, b, xtol=1e-14, rtol=1e-15)
    return None


def _critical_from_canonical(mats: dict, g: float) -> tuple[float | None, float | None]:
    """(weave, capsize) in 0..10 m/s: the weave pair's real part falls through zero, then the
    capsize eigenvalue (the larger real one) rises through zero."""
    weave = _root(lambda v: _weave(mats, g, v), 0.0, 10.0, falling=True)
    capsize = _root(lambda v: _capsize(mats, g, v), 0.0 if weave is None else weave, 10.0,
                    falling=False)
    return weave, capsize


# --------------------------------------------------------------------------------------------
# the closed form against BicycleParameters
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", SETS)
def test_closed_form_equals_bicycleparameters_canonical_matrices(canonical, name):
    cf = closed_form(table1(shipped(name)))
    for key in MATRICES:
        expected = canonical[name][key]
        err = np.max(np.abs(getattr(cf, key) - expected)) / np.max(np.abs(expected))
        assert err <= TOL_CANONICAL, f"{name} {key}: relative difference {err:.1e}"


# --------------------------------------------------------------------------------------------
# the stage on the ten sets
# --------------------------------------------------------------------------------------------


def _rows(sec) -> dict:
    return {c["quantity"].removeprefix("linearization vs closed form: "): c for c in sec.comparisons}


@pytest.mark.parametrize("name", SETS)
def test_linear_check_passes_and_its_speeds_are_bicycleparameters(canonical, specs, name):
    sec = linear_check(TOLS, specs[name])
    assert sec.title == f"Linearization of {name}Benchmark against the benchmark's closed form"
    rows = _rows(sec)
    assert set(rows) == {*MATRICES, "weave speed", "capsize speed"}
    assert all(r["passed"] is True for r in rows.values()), [r for r in rows.values()
                                                            if not r["passed"]]
    weave, capsize = _critical_from_canonical(canonical[name], table1(shipped(name))["g"])
    for mode, expected in (("weave", weave), ("capsize", capsize)):
        row = rows[f"{mode} speed"]
        for side in ("closed_form", "linearization"):
            got = row[side]
            if expected is None:
                assert got is None, f"{name} {mode} ({side}): {got}, none expected"
            else:
                assert got is not None and abs(got - expected) <= TOL_SPEED, (
                    f"{name} {mode} ({side}): {got!r} vs {expected!r}")
    assert weave is not None        # every set weaves in 0..10 m/s
    pickle.dumps(sec)               # stages run in worker processes


def _planted(monkeypatch, change):
    """Replace the linearization's speed-independent matrices (model signs) by ``change`` of
    them: what linearize, eigenvalues and the critical speeds all read."""
    original = linearize_module._expansion
    monkeypatch.setattr(linearize_module, "_expansion",
                        lambda params: dataclasses.replace(original(params),
                                                           **change(original(params))))


@pytest.mark.parametrize("bug, failing", [
    (lambda e: {"K2": -e.K2}, {"K2", "weave speed", "capsize speed"}),
    # the velocity matrices read off a linearization at 2 m/s as if at 1 m/s
    (lambda e: {"C1": 2.0 * e.C1, "K2": 4.0 * e.K2}, {"C1", "K2", "weave speed", "capsize speed"}),
], ids=["K2-sign", "v-scaling"])
def test_a_planted_linearization_bug_fails_the_check(monkeypatch, specs, bug, failing):
    _planted(monkeypatch, bug)
    rows = _rows(linear_check(TOLS, specs["Benchmark"]))
    assert {q for q, r in rows.items() if r["passed"] is False} == failing


def test_thesis_contact_is_not_applicable_and_drag_is_removed_and_said():
    rows = linear_check(TOLS, "thesis").comparisons
    assert len(rows) == 1 and rows[0]["passed"] is None
    assert rows[0]["note"].startswith("not applicable: no benchmark counterpart: model.contact")
    sec = linear_check(TOLS, "thesis-disc")                      # cv = 0.8 kg/m
    assert all(c["passed"] is True for c in sec.comparisons)
    assert "checked with cv = 0" in sec.blocks[0].text


# --------------------------------------------------------------------------------------------
# Linearization at 5 m/s against the paper's printed matrices
# --------------------------------------------------------------------------------------------


def test_linearization_at_5_m_s_is_the_printed_benchmark():
    lin = linearize(load_model("benchmark"), V)
    printed = {k: np.array(v) for k, v in MEIJAARD_MATRICES.items()}
    for key in MATRICES:
        np.testing.assert_allclose(getattr(lin, key), printed[key], rtol=0, atol=TOL_PRINTED,
                                   err_msg=key)
    K = 9.81 * printed["K0"] + V**2 * printed["K2"]
    C = V * printed["C1"]
    for got, expected in ((lin.K, K), (lin.C, C)):
        assert np.max(np.abs(got - expected)) <= TOL_K * np.max(np.abs(expected))


def test_max_matched_error_matches_each_eigenvalue_once_relative_above_one():
    """Worked by hand: each expected eigenvalue takes its nearest remaining one, the error is
    relative where |expected| > 1 and absolute below, and a value once matched is gone."""
    from comparisons.judgments.meijaard import max_matched_error
    got = np.array([10.5, 1.1, 2 + 1j])
    # 1 <-> 1.1: 0.1 / 1; 2+1j <-> 2+1j: 0; 10 <-> 10.5: 0.5 / 10
    assert max_matched_error(np.array([1.0, 2 + 1j, 10.0]), got) == pytest.approx(0.1, rel=1e-12)
    # 0.5 <-> 0.45: absolute 0.05 (|0.5| < 1)
    assert max_matched_error(np.array([0.5]), np.array([0.45])) == pytest.approx(0.05, rel=1e-12)
    # 1.2 cannot reuse 1.1 (taken by 1.0): it gets 5.0, 3.8 / 1.2
    assert max_matched_error(np.array([1.0, 1.2]), np.array([1.1, 5.0])) == \
        pytest.approx(3.8 / 1.2, rel=1e-12)
    # eigenvalues come in +- pairs: -1 takes -1.05 (0.05), not the 1.1 nearest to -(-1)
    assert max_matched_error(np.array([-1.0, 1.0]), np.array([1.1, -1.05])) == \
        pytest.approx(0.1, rel=1e-12)


def test_the_root_bracketing_on_functions_with_known_roots():
    """The critical speeds' root finder on straight lines, whose roots are known exactly, on a
    grid of binary fractions (1/8 m/s) so a root can fall exactly on a grid point: that point is
    the root, in either direction of the crossing (steep enough, 8 (0.5 - s), that the sample
    before is exactly 1); a rising crossing is none when only falling ones count; a root in the
    last interval is bracketed by the grid's ends; 1e-14 is brentq's xtol."""
    from comparisons.judgments.meijaard import _first_root, _grid
    grid = _grid(0.0, 1.0, 0.125)
    np.testing.assert_array_equal(grid, np.arange(9) * 0.125)
    np.testing.assert_array_equal(_grid(0.0, 0.005, 0.01), [0.0, 0.005])   # one step at least
    np.testing.assert_array_equal(_grid(2.0, 3.0, 0.5), [2.0, 2.5, 3.0])

    def falling(s):
        return 8.0 * (0.5 - np.asarray(s, dtype=float).reshape(-1))

    def rising(s):
        return np.asarray(s, dtype=float).reshape(-1) - 0.3

    def late(s):
        return np.asarray(s, dtype=float).reshape(-1) - 0.95

    assert _first_root(falling, grid, down_only=True) == 0.5
    assert _first_root(falling, grid, down_only=False) == 0.5
    assert _first_root(rising, grid, down_only=True) is None
    assert _first_root(rising, grid, down_only=False) == pytest.approx(0.3, abs=1e-14)
    assert _first_root(late, grid, down_only=False) == pytest.approx(0.95, abs=1e-14)


def test_the_closed_forms_matrices_are_read_only_and_a_scalar_speed_gives_one_state_matrix():
    from comparisons.judgments.meijaard import state_matrix
    from reference_model.benchmark import TABLE1
    cf = closed_form(TABLE1.as_dict())
    for key in MATRICES:
        with pytest.raises(ValueError, match="read-only"):
            getattr(cf, key)[0, 0] = 1.0
    A = state_matrix(cf, V)
    assert A.shape == (4, 4)
    # d/dt [q, q'] = [q', ...]: the upper half is [0 I]
    np.testing.assert_array_equal(A[:2], [[0, 0, 1, 0], [0, 0, 0, 1]])
    assert state_matrix(cf, [V, 2 * V]).shape == (2, 4, 4)


def test_the_capsize_speed_is_the_root_of_det_K_above_the_weave_speed_only():
    """The product of the four eigenvalues is det K(v) / det M, and K = g K0 + v^2 K2 with K2's
    first column zero makes det K linear in v^2: one root, v^2 = -g det K0 / (K0_11 K2_22 -
    K0_21 K2_12), worked here from the matrices. On the benchmark it is the capsize speed
    (above the weave speed); with the steer axis tilt halved (lam = pi/20) it lies
    below that bicycle's weave speed (5.38 < 6.40 m/s), where there is no capsize to find: the
    search starts at the weave speed, so none. 1e-9 m/s: brentq to 1e-14 on both."""
    from comparisons.judgments.meijaard import closed_form_critical_speeds
    from reference_model.benchmark import TABLE1

    def det_k_root(cf):
        K0, K2 = cf.K0, cf.K2
        return math.sqrt(-cf.g * np.linalg.det(K0)
                         / (K0[0, 0] * K2[1, 1] - K0[1, 0] * K2[0, 1]))

    b = TABLE1.as_dict()
    cf = closed_form(b)
    weave, capsize = closed_form_critical_speeds(cf)
    assert weave < capsize == pytest.approx(det_k_root(cf), abs=TOL_SPEED)
    steep = closed_form({**b, "lam": b["lam"] / 2})
    weave, capsize = closed_form_critical_speeds(steep)
    assert det_k_root(steep) < weave and capsize is None


def test_the_linear_checks_fields_on_a_narrow_range_and_a_bicycle_without_counterpart():
    """The judgment itself (the stage's rows are above): on the benchmark over 0..5 m/s the
    weave speed (4.29) is in range and the capsize speed (6.02) is not, so neither side finds
    one and that agrees; the drag-free benchmark needs no note. The thesis bicycle (thesis
    contact, drag) has no counterpart, said with its model, its range and the drag note. A
    matrix's error is the largest difference over its scale (max |entry| here: 0.5 / 10) at
    the entry where it is largest."""
    from comparisons.judgments.linear_check import _matrix_check, linear_benchmark_check
    from comparisons.judgments.tolerances import Tolerance
    check = linear_benchmark_check(load_model("benchmark"), TOLS, speeds=(0.0, 5.0))
    assert (check.reason, check.note, check.speeds_range) == ("", "", (0.0, 5.0))
    weave, capsize = check.speeds
    assert weave.closed_form == pytest.approx(4.29238253634111, abs=TOL_SPEED)
    assert (capsize.closed_form, capsize.linearization, capsize.passed) == (None, None, True)
    assert check.passed
    other = linear_benchmark_check(load_model("thesis"), TOLS)
    assert other.model == "thesis" and other.speeds_range == (0.0, 10.0)
    assert other.reason.startswith("no benchmark counterpart: model.contact")
    assert other.note.startswith("thesis has drag (cv = ") and other.passed is None
    expected = np.array([[10.0, -2.0], [3.0, 4.0]])
    got = expected + np.array([[0.0, 0.1], [-0.5, 0.0]])
    m = _matrix_check("K0", got, expected, Tolerance("x", 1e-3, "max_abs", "by hand"))
    assert (m.error, m.worst, m.passed) == (pytest.approx(0.05, rel=1e-12), "K0[delta, phi]", False)
