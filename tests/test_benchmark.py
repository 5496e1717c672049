"""The Meijaard et al. (2007) benchmark bicycle on the reference model (issue 6).

Expectations come from the paper, not from the code: Table 1 (parameters, typed here again),
Table 2 (eigenvalues, weave and capsize speeds) and the printed linear matrices M, C1, K0, K2.
The parameter file is also recomputed in 40-digit arithmetic from Table 1 with rotation
matrices (not the closed forms of reference_model/benchmark.py), and the linearization is
checked against finite differences of the generated C forward dynamics (another code path).

Tolerances and why:

* eigenvalues 1e-10 (the issue's criterion): Table 2 prints 14 decimals but is itself only good
  to ~1e-12 (its v = 7 castor eigenvalue is 8.5e-13 away from the eigenvalue of the paper's own
  printed matrices, computed in 40 digits); our rounding is ~1e-13 (measured max error 6.1e-13,
  at that same entry). A 1 nm change of the fork offset moves the eigenvalues by 8e-8, so the
  tolerance still catches any modelling error (see the negative control).
* weave/capsize speeds 1e-9 (the issue's): brentq to xtol 1e-14 on the exact linearization;
  measured errors are ~1e-14.
* M, C1, K0, K2 1e-13: printed to 14 decimals (rounding <= 5e-15); ours carry a few ulps of
  rounding of entries up to 81 (1 ulp = 1.4e-14); measured max 4.3e-14.
* parameter file: bit-exact against benchmark.py's formulas (the file is their repr());
  1e-15 relative against the 40-digit recomputation (a few roundings in double: measured
  3 ulp at most, on I3xx).
"""

from __future__ import annotations

import argparse
import math
import time
import tomllib

import mpmath as mp
import numpy as np
import pandas as pd
import pytest

from comparisons.cli import UsageError
from comparisons.judgments.published import (MEIJAARD_CAPSIZE_SPEED, MEIJAARD_MATRICES,
                                             MEIJAARD_TABLE2, MEIJAARD_WEAVE_SPEED,
                                             table2_eigenvalues)
from comparisons.cli.eigenvalues import add_eigenvalues_parser, parse_speeds, run_eigenvalues
from comparisons.judgments.eigenvalues import eigenvalue_curves, eigenvalue_table
from comparisons.report.figures import save_figure
from reference_model import ParameterError, load_model
from reference_model.benchmark import reference_parameters
from reference_model.linearize import (LinearizationError, eigenvalues, linearize,
                                       sort_eigenvalues, capsize_speed, weave_speed)
from reference_model.params import BENCHMARK_FILE, PARAMETER_GROUPS, PARAMETER_NAMES
from reference_model.solvers import dependent_rates, solve_beta

# -- Meijaard et al. 2007, Table 1 (x forward, z down) ----------------------------------------
W, C_TRAIL, LAM, G = "1.02", "0.08", mp.pi / 10, "9.81"
RR, MR, IRXX, IRYY = "0.3", "2", "0.0603", "0.12"
XB, ZB, MB, IB = "0.3", "-0.9", "85", [["9.2", "0", "2.4"], ["0", "11", "0"], ["2.4", "0", "2.8"]]
XH, ZH, MH = "0.9", "-0.7", "4"
IH = [["0.05892", "0", "-0.00756"], ["0", "0.06", "0"], ["-0.00756", "0", "0.00708"]]
RF, MF, IFXX, IFYY = "0.35", "3", "0.1405", "0.28"

# -- Table 2 and the printed matrices (typed once, from the paper, in comparisons/published.py)
TABLE2 = MEIJAARD_TABLE2
WEAVE_SPEED, CAPSIZE_SPEED = MEIJAARD_WEAVE_SPEED, MEIJAARD_CAPSIZE_SPEED
PUBLISHED = MEIJAARD_MATRICES
TOL_EIG, TOL_SPEED, TOL_MATRIX = 1e-10, 1e-9, 1e-13


table2_row = table2_eigenvalues


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


# --------------------------------------------------------------------------------------------
# the parameter file
# --------------------------------------------------------------------------------------------


def _file_values() -> dict[str, float]:
    data = tomllib.loads(BENCHMARK_FILE.read_text(encoding="utf-8"))
    return {n: data[PARAMETER_GROUPS[n]][n]["value"] for n in PARAMETER_NAMES}


def test_parameter_file_is_exactly_the_documented_formulas():
    found, expected = _file_values(), reference_parameters()
    assert {n: found[n] for n in PARAMETER_NAMES} == {n: expected[n] for n in PARAMETER_NAMES}
    assert expected["contact"] == "disc"                          # never the thesis's implicitly


def _independent_parameters() -> dict[str, mp.mpf]:
    """Table 1 -> the model's parameters in 40 digits, by rotation matrices."""
    mp.mp.dps = 40
    f = mp.mpf
    flip = mp.diag([1, -1, -1])                      # z down -> z up (rotation by pi about x)
    c, s = mp.cos(LAM), mp.sin(LAM)
    Rf = mp.matrix([[c, 0, -s], [0, 1, 0], [s, 0, c]])   # frame axes: Ry(-lambda), columns x3 y3 z3

    def frame(vec):                                  # global z-up vector -> frame components
        return Rf.T * mp.matrix(vec)

    def tensor(I):
        return Rf.T * flip * mp.matrix([[f(x) for x in row] for row in I]) * flip.T * Rf

    G2 = mp.matrix([0, 0, f(RR)])
    B = mp.matrix([f(XB), 0, -f(ZB)])
    H = mp.matrix([f(XH), 0, -f(ZH)])
    G5 = mp.matrix([f(W), 0, f(RF)])
    P0 = mp.matrix([f(W) + f(C_TRAIL), 0, 0])        # the steering axis meets the ground here
    axis = Rf[:, 2]
    A = P0 + axis * (axis.T * (G5 - P0))[0]          # foot of the perpendicular from the hub
    b, a, h, hub = frame(B - G2), frame(A - G2), frame(H - A), frame(G5 - A)
    I3, I4 = tensor(IB), tensor(IH)
    return {
        "R_rear": f(RR), "R_front": f(RF), "x3": b[0], "z3": b[2], "xa": a[0], "za": a[2],
        "dx4": h[0], "dz4": h[2], "x5": hub[0], "z5": hub[2],
        "m2": f(MR), "m3": f(MB), "m4": f(MH), "m5": f(MF),
        "I2xx": f(IRXX), "I2yy": f(IRYY), "I2zz": f(IRXX),
        "I3xx": I3[0, 0], "I3yy": I3[1, 1], "I3zz": I3[2, 2], "I3xz": I3[0, 2],
        "I4xx": I4[0, 0], "I4yy": I4[1, 1], "I4zz": I4[2, 2], "I4xz": I4[0, 2],
        "I5xx": f(IFXX), "I5yy": f(IFYY), "I5zz": f(IFXX), "g": f(G), "cv": f(0),
    }


def test_parameter_file_matches_table1_recomputed_in_40_digits():
    found = _file_values()
    for name, exact in _independent_parameters().items():
        assert abs(found[name] - float(exact)) <= 1e-15 * max(1.0, abs(found[name])), name


def test_named_model_benchmark(bench):
    p = bench.params
    assert (bench.name, bench.contact, p.cv) == ("benchmark", "disc", 0.0)
    assert p.source == str(BENCHMARK_FILE)


def _upright(model) -> np.ndarray:
    q, _ = solve_beta(model, np.zeros(8))
    return q


def test_geometry_at_upright_is_table1(bench):
    """Through the model's own kinematics: beta = -lambda, every point where Table 1 puts it
    (z up), the steering axis meeting the ground at the trail, inertias back in global axes."""
    lam = math.pi / 10
    q = _upright(bench)
    assert q[5] == pytest.approx(-lam, abs=1e-15)
    pts = bench.points(q)
    expected = {"rC": (0, 0, 0), "rG2": (0, 0, 0.3), "rG3": (0.3, 0, 0.9), "rG4": (0.9, 0, 0.7),
                "rG5": (1.02, 0, 0.35), "rD": (1.02, 0, 0)}
    for name, xyz in expected.items():
        np.testing.assert_allclose(pts[name], xyz, rtol=0, atol=2e-15, err_msg=name)
    axis = np.array([-math.sin(lam), 0.0, math.cos(lam)])             # z3 at upright
    ground = pts["rA"] - pts["rA"][2] / axis[2] * axis
    np.testing.assert_allclose(ground, (1.02 + 0.08, 0, 0), rtol=0, atol=2e-15)
    c, s = math.cos(q[5]), math.sin(q[5])
    A3 = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    flip = np.diag([1.0, -1.0, -1.0])
    for body, table in ((3, IB), (4, IH)):
        I_up = flip @ np.array(table, dtype=float) @ flip
        np.testing.assert_allclose(A3 @ bench.params.inertia(body) @ A3.T, I_up, rtol=0,
                                   atol=1e-14, err_msg=f"body {body}")


# --------------------------------------------------------------------------------------------
# the linearization against the paper
# --------------------------------------------------------------------------------------------


def test_linear_matrices_match_the_published_ones(bench):
    lin = linearize(bench, 0.0)
    for name, published in PUBLISHED.items():
        np.testing.assert_allclose(getattr(lin, name), published, rtol=0, atol=TOL_MATRIX,
                                   err_msg=name)


@pytest.mark.parametrize("v", sorted(TABLE2))
def test_eigenvalues_match_table2(bench, v):
    got = eigenvalues(bench, float(v))
    assert got.shape == (4,)
    np.testing.assert_allclose(got, table2_row(v), rtol=0, atol=TOL_EIG)


def test_eigenvalues_batch_equals_single_speeds(bench):
    vs = np.arange(11.0)
    batch = eigenvalues(bench, vs)
    assert batch.shape == (11, 4)
    for v, row in zip(vs, batch):
        np.testing.assert_array_equal(row, eigenvalues(bench, v))
        np.testing.assert_allclose(linearize(bench, v).eigenvalues(), row, rtol=0, atol=1e-12)


def test_weave_and_capsize_speeds(bench):
    assert abs(weave_speed(bench) - WEAVE_SPEED) <= TOL_SPEED
    assert abs(capsize_speed(bench) - CAPSIZE_SPEED) <= TOL_SPEED
    # the definition: weave real part and capsize eigenvalue vanish there
    assert abs(eigenvalues(bench, weave_speed(bench))[0].real) < 1e-12
    assert abs(eigenvalues(bench, capsize_speed(bench))[2]) < 1e-12


def test_roll_steer_decouple_from_the_rear_wheel_and_upright_is_steady(bench):
    lin = linearize(bench, 5.0)
    assert lin.coupling < 1e-12       # left-right symmetry: psi does not enter roll/steer
    assert lin.residual < 1e-12       # no force needed to keep rolling straight (no drag)
    assert lin.beta0 == pytest.approx(-math.pi / 10, abs=1e-15)


def test_negative_control_a_nanometre_of_fork_offset_fails_the_tolerance(bench):
    moved = bench.with_params(bench.params.replace(x5=bench.params.x5 + 1e-9))
    errors = [np.max(np.abs(eigenvalues(moved, float(v)) - table2_row(v))) for v in TABLE2]
    assert max(errors) > 10 * TOL_EIG


def test_negative_control_z_down_products_of_inertia_are_caught(bench):
    """Taking Table 1's xz products without the sign change to z up is caught: for the front
    assembly the tensor is then not even positive definite (the loader refuses it); for the
    rear body the mass matrix is off by far more than rounding."""
    c, s = math.cos(math.pi / 10), math.sin(math.pi / 10)

    def wrong_xz(xx, zz, xz_down):        # the same rotation, but xz not flipped
        return c * s * (zz - xx) + (c * c - s * s) * xz_down

    with pytest.raises(ParameterError, match="I4xz.*not positive definite"):
        bench.params.replace(I4xz=wrong_xz(0.05892, 0.00708, -0.00756))
    p = bench.params.replace(I3xz=wrong_xz(9.2, 2.8, 2.4))
    lin = linearize(bench.with_params(p), 0.0)
    assert np.max(np.abs(lin.M - PUBLISHED["M"])) > 1.0


@pytest.mark.parametrize("contact", ["disc", "thesis"])
def test_state_matrix_matches_finite_differences_of_the_generated_c(bench, contact):
    """The generated C forward dynamics (KKT solve, another code path): d(dd theta, dd gamma)
    by central differences in (theta, gamma, d theta, d gamma) at fixed d psi = v / R_rear.
    Their error is O(h^2) (measured 4e-11 at h = 1e-6, 4e-9 at h = 1e-5, entries up to 15), so
    the tolerance is 1e-9 of the largest entry.

    Also with the thesis's front contact on this geometry (rake and trail: the two contacts
    are different points, and at 4 m/s the weave pair is 0.41 +- 3.08j with the disc and
    0.80 +- 8.40j with the thesis contact), so a linearization that ignored the model's contact
    could not pass both."""
    if contact != bench.contact:
        bench = bench.with_params(bench.params.with_contact(contact))
    v = 4.0
    lin = linearize(bench, v)
    R = bench.params.R_rear

    def rates(x):
        q = np.zeros(8)
        q[3], q[6] = x[0], x[1]
        q, _ = solve_beta(bench, q)
        dq = dependent_rates(bench, q, np.array([x[2], v / R, x[3]]))
        ddq = bench.forward_acceleration(q, dq)
        return np.array([ddq[3], ddq[6]])

    h = 1e-6
    J = np.column_stack([(rates(h * e) - rates(-h * e)) / (2 * h) for e in np.eye(4)])
    np.testing.assert_allclose(lin.A[2:], J, rtol=0, atol=1e-9 * np.max(np.abs(lin.A)))
    np.testing.assert_array_equal(lin.A[:2], [[0, 0, 1, 0], [0, 0, 0, 1]])


def test_sorting_is_pairs_then_real_descending():
    lam = np.array([-3.0, 1 - 2j, 0.5, 1 + 2j])
    np.testing.assert_array_equal(sort_eigenvalues(lam), [1 + 2j, 1 - 2j, 0.5, -3.0])
    quartet = np.array([-1 - 1j, 1 - 1j, -1 + 1j, 1 + 1j])
    np.testing.assert_array_equal(sort_eigenvalues(quartet), [1 + 1j, 1 - 1j, -1 + 1j, -1 - 1j])


def test_model_with_drag_is_refused_with_the_fix(thesis):
    with pytest.raises(LinearizationError, match=r"cv = 0.8.*replace\(cv=0.0\)"):
        linearize(thesis, 1.0)


def test_1001_speeds_are_fast(bench):
    eigenvalues(bench, 1.0)                    # the model's matrices, once
    t0 = time.perf_counter()
    lam = eigenvalues(bench, np.linspace(0.0, 10.0, 1001))
    elapsed = time.perf_counter() - t0
    assert lam.shape == (1001, 4)
    assert elapsed < 1.0, f"{elapsed:.3f} s for 1001 speeds (measured 0.01 s)"


# --------------------------------------------------------------------------------------------
# CSV, figure and the command
# --------------------------------------------------------------------------------------------


def _args(*argv):
    parser = argparse.ArgumentParser(prog="bicycle-xval")
    add_eigenvalues_parser(parser.add_subparsers(dest="command"))
    return parser.parse_args(["eigenvalues", *map(str, argv)])


def test_run_eigenvalues_writes_the_table(tmp_path, capsys):
    out, fig = tmp_path / "eig.csv", tmp_path / "eig.png"
    code = run_eigenvalues(_args("--model", "benchmark", "--speeds", "0:10:0.01", "--out", out,
                                 "--figure", fig))
    stdout = capsys.readouterr().out
    assert code == 0
    assert "weave speed 4.29238253634" in stdout and "capsize speed 6.02426201538" in stdout
    frame = pd.read_csv(out)
    expected = ["v"] + [f"{p}_{k}" for k in range(1, 5) for p in ("re", "im")] + ["stable"]
    assert list(frame.columns) == expected
    assert len(frame) == 1001
    np.testing.assert_allclose(frame["v"], 0.01 * np.arange(1001), rtol=0, atol=1e-14)
    assert frame["v"].iloc[-1] == 10.0
    for v in TABLE2:
        row = frame.iloc[100 * v]
        got = np.array([row[f"re_{k}"] + 1j * row[f"im_{k}"] for k in range(1, 5)])
        np.testing.assert_allclose(got, table2_row(v), rtol=0, atol=TOL_EIG)   # 17 digits survive
    stable = frame.loc[frame["stable"], "v"]
    assert stable.min() == pytest.approx(4.30) and stable.max() == pytest.approx(6.02)
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_eigenvalue_table_and_figure_functions(bench, tmp_path):
    frame = eigenvalue_table(bench, [5.0])
    assert frame.shape == (1, 10)
    path = save_figure("eigenvalues", eigenvalue_curves(bench, np.linspace(0, 10, 201)),
                       tmp_path / "sub" / "e.png")
    assert path.stat().st_size > 1000


@pytest.mark.parametrize("text, fragment", [
    ("0:10", "expected start:stop:step"),
    ("0:x:0.1", "stop 'x' is not a number"),
    ("0:10:0", "step must be > 0"),
    ("0:10:-1", "step must be > 0"),
    ("10:0:1", "below start"),
    ("0:inf:1", "must be finite"),
    ("", "expected start:stop:step"),
    ("0:1e9:1e-6", "more than"),
])
def test_bad_speeds_are_usage_errors(text, fragment, tmp_path):
    with pytest.raises(UsageError) as info:
        run_eigenvalues(_args("--speeds", text, "--out", tmp_path / "x.csv"))
    message = str(info.value)
    assert "--speeds" in message and fragment in message and "\n" not in message
    assert "0:10:0.01" in message or "step" in message
    assert not (tmp_path / "x.csv").exists()


def test_speed_grids():
    np.testing.assert_array_equal(parse_speeds("0:0.3:0.1"), [0, 0.1, 0.2, 0.3])   # stop on grid
    np.testing.assert_allclose(parse_speeds("0:1:0.3"), [0, 0.3, 0.6, 0.9])        # stop off grid
    np.testing.assert_array_equal(parse_speeds("5"), [5.0])
    assert parse_speeds("0:10:0.01")[-1] == 10.0


def test_model_with_drag_needs_no_drag_flag(tmp_path, capsys):
    with pytest.raises(UsageError, match="--no-drag"):
        run_eigenvalues(_args("--model", "thesis", "--out", tmp_path / "t.csv"))
    assert run_eigenvalues(_args("--model", "thesis", "--no-drag", "--speeds", "0:2:1",
                                 "--out", tmp_path / "t.csv")) == 0
    assert len(pd.read_csv(tmp_path / "t.csv")) == 3
