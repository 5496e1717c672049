"""The inverse, mass-matrix and constraint comparisons of comparisons/judgments/
scenario_compare.py on hand-made runs (the forward one is tests/test_trajectory_judgment.py).

Every expected number is placed in the input: a planted difference of known size at a known
sample and entry, a scale chosen by hand, and for the constraint residual a physical fact: a
bicycle standing upright whose frame translates without turning a wheel slides both
contact points at exactly that velocity (a rigid translation moves every point alike), so the
reference model's |C| is that speed in vC_x and vD_x (or vC_y, vD_y sideways). No engine runs. ~20 ms."""

import numpy as np
import pytest

from comparisons.judgments.scenario_compare import (compare_constraints, compare_inverse,
                                                    compare_mass_matrix, constraint_series)
from comparisons.judgments.terms import random_states
from comparisons.judgments.tolerances import load_tolerances
from engines import Engine, load_engine
from engines.reference import ReferenceEngine
from engines.runs import Run
from reference_model.solvers import solve_beta

TOLS = load_tolerances()
T4 = np.array([0.0, 0.01, 0.02, 0.03])


def _inverse(engine, T, lam):
    return Run(engine, "check", "thesis", "inverse", "completed", "", 0.0, T4,
               np.zeros((4, 8)), np.zeros((4, 8)), T, lam)


def test_torques_and_multipliers_name_the_worst_entry_relative_to_their_scales():
    """Torques: largest |T| 5 N m -> scale max(1, 5) = 5 (max_abs_or_one); Mped at 0.02 s off
    by 2 tolerances x 5, so the error is 2 tolerances: fails. Multipliers: largest 200 N
    (max_abs); lambda[vD_y] at 0.01 s off by half a tolerance x 200: passes."""
    tol_T, tol_l = TOLS["torques"].tolerance, TOLS["multipliers"].tolerance
    T = np.tile([1.0, -5.0, 0.5], (4, 1))
    lam = np.tile([200.0, -3.0, 4.0, 10.0, -150.0], (4, 1))
    T2, lam2 = T.copy(), lam.copy()
    T2[2, 1] += 2 * tol_T * 5.0
    lam2[1, 4] += 0.5 * tol_l * 200.0
    torques, mult = (r.as_dict() for r in compare_inverse(_inverse("reference", T, lam),
                                                           _inverse("pinocchio", T2, lam2), TOLS))
    assert torques["quantity"] == "torques" and mult["quantity"] == "multipliers"
    for r in (torques, mult):
        assert (r["scenario"], r["model"], r["engines"]) == ("check", "thesis",
                                                             ["reference", "pinocchio"])
    # rel 1e-6: the plant (~1e-7) is recovered as a difference of O(1-100) numbers (1e-16
    # relative each: ~1e-9 of the plant's size at worst)
    assert torques["max_error"] == pytest.approx(2 * tol_T, rel=1e-6)
    assert torques["max_abs_error"] == pytest.approx(10 * tol_T, rel=1e-6)
    assert (torques["tolerance"], torques["passed"]) == (tol_T, False)
    assert torques["localized_to"] == "Mped at t = 0.02 s"
    assert torques["note"] == "over 4 samples; error relative to 5 (max_abs_or_one)"
    assert mult["max_error"] == pytest.approx(0.5 * tol_l, rel=1e-6)
    assert (mult["tolerance"], mult["passed"]) == (tol_l, True)
    assert mult["localized_to"] == "lambda[vD_y] at t = 0.01 s"
    assert mult["note"] == "over 4 samples; error relative to 200 (max_abs)"


class PlantedM(ReferenceEngine):
    """The reference with 3e-9 kg m^2 added to M[theta, gamma] at state 1."""

    name = "planted"

    def mass_matrix(self, q):
        M = np.array(super().mass_matrix(q), dtype=float)
        M[1, 3, 6] += 3e-9
        return M


def test_the_mass_matrix_is_compared_for_every_engine_that_has_one(thesis):
    class NoM(Engine):
        name = "no-m"
        capabilities = frozenset({"gravity"})

    q = random_states(3, seed=1).q
    engines = {"reference": load_engine("reference", thesis), "planted": PlantedM(thesis),
               "no-m": NoM(thesis)}
    (row,) = compare_mass_matrix("check", thesis, q, engines, TOLS)
    row = row.as_dict()
    scale = np.abs(thesis.mass_matrix(q[1])).max()     # max_abs: the reference's own M
    assert (row["quantity"], row["scenario"], row["model"], row["engines"]) == (
        "mass_matrix", "check", "thesis", ["reference", "planted"])
    # rel 1e-6 as above: 3e-9 against entries of O(1-100) kg m^2
    assert row["max_error"] == pytest.approx(3e-9 / scale, rel=1e-6)
    assert row["max_abs_error"] == pytest.approx(3e-9, rel=1e-6)
    assert (row["tolerance"], row["passed"]) == (TOLS["mass_matrix"].tolerance, False)
    assert row["localized_to"] == "M[theta, gamma] at state 1"
    assert row["note"] == "at the reference's 3 states of the scenario"


def _upright(thesis, n):
    q0 = np.zeros(8)
    q0[5] = -np.pi / 10
    return np.tile(solve_beta(thesis, q0)[0], (n, 1))


def test_the_constraint_residual_is_the_reference_models_at_the_runs_states(thesis):
    q = _upright(thesis, 4)
    dq = np.zeros((4, 8))
    dq[2, 0] = 5e-4            # the frame translates along x at 0.5 mm/s at t = 0.02 s
    run = Run("mujoco", "check", "thesis", "forward", "completed", "", 0.0, T4, q, dq)
    C = constraint_series(thesis, run)
    assert C.shape == (4, 5) and np.all(C >= 0)
    # 1e-15 m/s: the contact height and the slips at rest are round-off (measured ~1e-18)
    np.testing.assert_allclose(C[2], [0.0, 5e-4, 0.0, 5e-4, 0.0], atol=1e-15)
    row = compare_constraints(thesis, run, TOLS).as_dict()
    assert (row["quantity"], row["scenario"], row["model"], row["engines"]) == (
        "constraint_residual", "check", "thesis", ["mujoco"])
    assert row["max_error"] == pytest.approx(5e-4, abs=1e-15)
    # [constraint_residual] is 1e-3 (absolute): half of it passes, five times it fails
    assert row["tolerance"] == TOLS["constraint_residual"].tolerance == 1e-3
    assert row["passed"] is True
    assert row["localized_to"] == "C[vC_x] at t = 0.02 s"     # the first of the two equal
    assert row["note"] == "whole run to 0.030 s (completed)"
    dq[1, 1] = 5e-3                                           # sideways, at 0.01 s: fails
    row = compare_constraints(thesis, Run("mujoco", "check", "thesis", "forward", "fell", "",
                                          0.0, T4, q, dq), TOLS).as_dict()
    assert row["max_error"] == pytest.approx(5e-3, abs=1e-15) and row["passed"] is False
    assert row["localized_to"] == "C[vC_y] at t = 0.01 s"
    assert row["note"] == "whole run to 0.030 s (fell)"


def test_a_run_without_samples_has_no_constraint_residual(thesis):
    run = Run("mujoco", "check", "thesis", "forward", "failed", "boom", 0.0)
    assert constraint_series(thesis, run).shape == (0, 5)
    row = compare_constraints(thesis, run, TOLS).as_dict()
    assert row == {"quantity": "constraint_residual", "scenario": "check", "model": "thesis",
                   "engines": ["mujoco"], "max_error": None,
                   "tolerance": TOLS["constraint_residual"].tolerance, "passed": None,
                   "localized_to": "-", "note": "no samples (failed)"}


def test_errors_exactly_at_the_tolerance_pass_and_one_sample_is_measured(thesis):
    """A tolerance is the largest accepted error (tolerances.toml). Torques: a reference of
    zeros (scale max(1, 0) = 1) and one torque off by exactly the tolerance. Constraints: the
    rigid translation at exactly 1e-3 m/s, [constraint_residual]'s 1e-3 (the model gives 1e-3
    to the bit: vC_x = xc_dot at rest). A run of one sample is measured like any other."""
    tol_T = TOLS["torques"].tolerance
    T, lam = np.zeros((4, 3)), np.ones((4, 5))
    T2 = T.copy()
    T2[3, 2] = tol_T
    torques, _ = compare_inverse(_inverse("reference", T, lam), _inverse("e", T2, lam), TOLS)
    assert torques["max_error"] == tol_T and torques["passed"] is True
    q = _upright(thesis, 1)
    dq = np.zeros((1, 8))
    dq[0, 0] = 1e-3
    row = compare_constraints(thesis, Run("mujoco", "check", "thesis", "forward", "completed",
                                          "", 0.0, T4[:1], q, dq), TOLS)
    assert row["max_error"] == 1e-3 == TOLS["constraint_residual"].tolerance
    assert row["passed"] is True and row["localized_to"] == "C[vC_x] at t = 0.00 s"
