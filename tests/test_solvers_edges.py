"""The solvers' edges (reference_model/solvers.py), issue 24: the parts of Newton's beta
solve, the dependent rates, the projection, inverse kinematics and dynamics and the forward
run that the physics tests in tests/test_solvers.py reach only on their happy path.

Expected values come from outside the code under test: Newton's method worked by hand on
scalar functions whose iterates are known exactly (a line: one step; no root: the iteration
count), the KKT system of the smallest kinetic-energy change solved here with numpy, the
documented contracts of the messages and settings (docs/model.md's run settings), and counts
of the model's own evaluations seen through a spy. Each test names the planted bug it was
seen failing on.
"""

import re

import numpy as np
import pytest

from reference_model import load_model
from reference_model.model import DEP, IND, N_C, N_Q, ForwardResult
from reference_model.solvers import (BETA, DEFAULT_FALL_LIMIT, THESIS_BAUMGARTE, THETA,
                                     ConstraintSolveError, IndependentMotion, Motion,
                                     consistent_state, dependent_rates, inverse_dynamics,
                                     inverse_kinematics, project_state, simulate, solve_beta)

XC, YC, PHI, PSI, GAMMA, EPS = 0, 1, 2, 4, 6, 7


@pytest.fixture(scope="module")
def model():
    return load_model("thesis")


class Scalar:
    """A duck-typed model whose front-contact height is ``h(beta)`` alone (the other four
    residuals zero), counting its evaluations: Newton's iterates are then those of a scalar
    function, known by hand."""

    def __init__(self, h, dh):
        self.h, self.dh, self.calls = h, dh, 0

    def constraint_residual(self, q, dq):
        self.calls += 1
        out = np.zeros(N_C)
        out[0] = self.h(q[BETA])
        return out

    def constraint_jacobian(self, q):
        D = np.zeros((N_C, N_Q))
        D[0, BETA] = self.dh(q[BETA])
        return D


# -- Newton on [rD]_z = 0 -------------------------------------------------------------------

def test_newton_on_a_line_takes_one_exact_step_and_leaves_the_input_alone():
    """h = beta - 0.25 from beta = 5: one Newton step lands on the root exactly (every number
    a binary fraction); the other coordinates and the caller's array are untouched. Planted:
    the step's sign (beta += h / slope)."""
    m = Scalar(lambda b: b - 0.25, lambda b: 1.0)
    q0 = np.arange(8.0)
    q, its = solve_beta(m, q0)
    assert its == 1 and q[BETA] == 0.25
    np.testing.assert_array_equal(np.delete(q, BETA), np.delete(np.arange(8.0), BETA))
    np.testing.assert_array_equal(q0, np.arange(8.0))


def test_a_residual_equal_to_the_tolerance_is_converged():
    """h = beta - 0.25 from beta = 0.5: |h| = 0.25 exactly, so tol = 0.25 stops at once and a
    tolerance just below it takes the step. Planted: |h| < tol."""
    m = Scalar(lambda b: b - 0.25, lambda b: 1.0)
    q0 = np.zeros(8)
    q0[BETA] = 0.5
    assert solve_beta(m, q0, tol=0.25)[1] == 0
    assert solve_beta(m, q0, tol=np.nextafter(0.25, 0))[1] == 1


def test_a_slope_at_the_singular_bound_is_still_followed():
    """h = 1e-12 (beta - 1) from 0: the slope is exactly 1e-12, not below it, and the step
    lands on beta = 1. A constant h has slope 0: the singular configuration is named.
    Planted: |slope| <= 1e-12."""
    m = Scalar(lambda b: 1e-12 * (b - 1.0), lambda b: 1e-12)
    q, its = solve_beta(m, np.zeros(8))
    assert its == 1 and q[BETA] == 1.0
    flat = Scalar(lambda b: 1.0, lambda b: 0.0)
    with pytest.raises(ConstraintSolveError, match=r"^d\[rD\]_z/dbeta = 0\.00e\+00 at q = "
                                                   r"\[0\.0, .*singular configuration\)$"):
        solve_beta(flat, np.zeros(8))


def test_no_root_raises_after_max_iter_steps_with_the_last_residual():
    """h = beta^2 + 1 has no real root: Newton evaluates h once per iteration, max_iter + 1
    times (the start and each of max_iter steps), then says so with the last residual.
    Planted: range(max_iter) (one evaluation fewer), and the message's count."""
    m = Scalar(lambda b: b * b + 1.0, lambda b: 2.0 * b)
    q0 = np.zeros(8)
    q0[BETA] = 0.7
    # the iterates by hand: beta <- beta - (beta^2 + 1) / (2 beta) = (beta^2 - 1) / (2 beta)
    b = 0.7
    for _ in range(5):
        b = (b * b - 1.0) / (2.0 * b)
    with pytest.raises(ConstraintSolveError) as info:
        solve_beta(m, q0, max_iter=5)
    assert m.calls == 6
    assert str(info.value) == (f"Newton on [rD]_z = 0 did not converge in 5 iterations "
                               f"(residual {b * b + 1.0:.3e} m); is the configuration reachable?")


# -- dependent rates and the consistent state --------------------------------------------------

class Linear:
    """A duck-typed model with a constant constraint Jacobian D."""

    def __init__(self, D):
        self.D = D

    def constraint_jacobian(self, q):
        return self.D


def test_dependent_rates_solve_the_velocity_constraints_and_keep_the_independent_ones():
    """D dq = 0 for the returned dq, with dq[IND] as given, on a random D (its D_dep
    well-conditioned by construction). Planted: D_ind's sign, IND and DEP swapped."""
    rng = np.random.default_rng(7)
    D = rng.normal(size=(N_C, N_Q))
    D[:, DEP] += 5.0 * np.eye(N_C)
    dq_ind = np.array([0.3, -1.2, 0.8])
    dq = dependent_rates(Linear(D), np.zeros(8), dq_ind)
    np.testing.assert_array_equal(dq[IND], dq_ind)
    np.testing.assert_allclose(D @ dq, 0.0, rtol=0, atol=1e-13)   # ~ 10 eps x |D| |dq|


def test_a_singular_d_dep_is_named_with_the_state():
    D = np.zeros((N_C, N_Q))
    D[:, IND] = 1.0
    with pytest.raises(ConstraintSolveError, match=r"^D_dep is singular at q = \[0\.0, 0\.0, "
                                                   r"0\.0, 0\.0, 0\.0, 0\.0, 0\.0, 0\.0\]: the "
                                                   r"dependent rates are not determined by theta, "
                                                   r"psi, gamma here$"):
        dependent_rates(Linear(D), np.zeros(8), [1.0, 0.0, 0.0])


def test_the_consistent_state_keeps_what_the_constraints_leave_free_and_says_what_it_moved(model):
    """From a pitched, rolling state: beta moves (Newton from the given beta), theta, psi,
    gamma, xc, yc, phi, eps and the independent rates stay; the residuals before and after
    are the model's own at the given and the returned state; describe() prints those numbers.
    Planted: residual_before taken at the result, the beta correction's sign."""
    q0 = np.array([0.4, -0.2, 0.3, 0.1, 0.5, 0.05, 0.2, 0.7])
    dq0 = np.array([1.0, 0.5, 0.1, 0.2, 5.0, 0.3, -0.4, 2.0])
    s = consistent_state(model, q0, dq0)
    keep = [i for i in range(8) if i != BETA]
    np.testing.assert_array_equal(s.q[keep], q0[keep])
    np.testing.assert_array_equal(s.dq[IND], dq0[IND])
    np.testing.assert_array_equal(s.q_given, q0)
    np.testing.assert_array_equal(s.dq_given, dq0)
    q_ref, its = solve_beta(model, q0)
    assert s.q[BETA] == q_ref[BETA] and s.iterations == its >= 2
    np.testing.assert_array_equal(s.residual_before, model.constraint_residual(q0, dq0))
    np.testing.assert_array_equal(s.residual_after, model.constraint_residual(s.q, s.dq))
    assert abs(s.residual_before[0]) > 1e-3 and np.max(np.abs(s.residual_after)) < 1e-12
    assert s.beta_correction == s.q[BETA] - 0.05
    assert s.describe() == (
        f"beta corrected by {s.q[BETA] - 0.05:+.6e} rad in {its} Newton iteration(s); front "
        f"contact height {s.residual_before[0]:+.3e} m -> {s.residual_after[0]:+.1e} m; max "
        f"|velocity constraint| {np.max(np.abs(s.residual_before[1:])):.3e} -> "
        f"{np.max(np.abs(s.residual_after[1:])):.1e} m/s")


@pytest.mark.parametrize("where", ["q", "dq"])
def test_the_consistent_state_refuses_a_non_finite_rate_or_coordinate(model, where):
    q, dq = np.zeros(8), np.zeros(8)
    (q if where == "q" else dq)[3] = np.inf
    with pytest.raises(ValueError, match=r"^initial state must be finite \(no NaN or inf in q0, "
                                         r"dq0\)$"):
        consistent_state(model, q, dq)


# -- the projection onto the constraints ---------------------------------------------------

def test_the_projection_is_the_smallest_kinetic_energy_change(model):
    """project_state's dq minimises (dq' - dq)^T M (dq' - dq) subject to D dq' = 0: the KKT
    system [[M, D^T], [D, 0]] [dq'; lam] = [M dq; 0], solved here with numpy, gives the
    same; q moves in beta alone, onto [rD]_z = 0. Planted: the Euclidean metric (M left
    out), the correction's sign."""
    q0 = np.array([0.1, 0.2, 0.3, 0.15, 0.4, 0.08, 0.25, 0.5])
    dq0 = np.array([1.5, -0.3, 0.2, 0.4, 4.0, 0.1, -0.6, 3.0])
    q, dq = project_state(model, q0, dq0)
    keep = [i for i in range(8) if i != BETA]
    np.testing.assert_array_equal(q[keep], q0[keep])
    assert abs(model.constraint_residual(q, np.zeros(8))[0]) < 1e-14
    M, D = model.mass_matrix(q), model.constraint_jacobian(q)
    K = np.block([[M, D.T], [D, np.zeros((N_C, N_C))]])
    expected = np.linalg.solve(K, np.concatenate([M @ dq0, np.zeros(N_C)]))[:N_Q]
    # both solves of the same well-posed system (cond(K) ~ 1e3): agreement to ~1e-13
    np.testing.assert_allclose(dq, expected, rtol=0, atol=1e-12)
    assert np.max(np.abs(dq - dq0)) > 0.01      # a real change, not the identity


# -- inverse kinematics and dynamics -------------------------------------------------------

def _upright_rolling(t):
    """theta = gamma = 0, psi = 5 t: straight rolling at 5 rad/s."""
    t = np.asarray(t, dtype=float)
    z = np.zeros_like(t)
    return (np.stack([z, 5.0 * t, z], -1), np.stack([z, 5.0 + z, z], -1),
            np.stack([z, z, z], -1))


ROLLING = IndependentMotion(_upright_rolling, "straight rolling")


@pytest.mark.parametrize("t, message", [
    (np.array([0.0]), "at least 2 samples"),
    (np.array([0.0, 0.1, 0.1]), "strictly increasing"),
    (np.zeros((2, 2)) + [[0, 1], [2, 3]], "1-D grid"),
])
def test_inverse_kinematics_refuses_a_bad_grid(model, t, message):
    with pytest.raises(ValueError, match=r"^t must be a strictly increasing 1-D grid of at least "
                                         r"2 samples$"):
        inverse_kinematics(model, ROLLING, t)


def test_inverse_kinematics_refuses_a_q_dep0_of_the_wrong_shape(model):
    with pytest.raises(ValueError, match=r"^q_dep0 must be \[xc, yc, phi, beta, eps\] \(5,\); "
                                         r"got shape \(4,\)$"):
        inverse_kinematics(model, ROLLING, [0.0, 1.0], q_dep0=(0, 0, 0, 0))


def test_inverse_kinematics_starts_consistent_and_reports_its_settings(model):
    """Given beta0 = 0.05 on the thesis geometry (consistent at beta = 0 upright): the start
    is corrected by Newton from 0.05, the correction reported in info with the heights before
    and after; straight rolling then keeps xc = R_rear psi and beta = 0. Planted: the
    correction's sign, the info's keys, reproject not passed on."""
    t = np.linspace(0.0, 1.0, 11)
    m = inverse_kinematics(model, ROLLING, t, q_dep0=(0.0, 0.0, 0.0, 0.05, 0.0), rtol=1e-11,
                           atol=1e-11)
    start = np.zeros(8)
    start[BETA] = 0.05
    fixed, its = solve_beta(model, start)
    h0 = model.constraint_residual(start, np.zeros(8))[0]
    h1 = model.constraint_residual(fixed, np.zeros(8))[0]
    assert m.info["beta_correction"] == fixed[BETA] - 0.05
    assert abs(fixed[BETA]) < 1e-14                 # the upright thesis bicycle: beta = 0
    assert m.info["initial_correction"] == (
        f"beta corrected by {fixed[BETA] - 0.05:+.6e} rad in {its} Newton iteration(s); front "
        f"contact height {h0:+.3e} m -> {h1:+.1e} m")
    assert {k: m.info[k] for k in ("rtol", "atol", "reproject")} == \
        {"rtol": 1e-11, "atol": 1e-11, "reproject": False}
    assert m.info["nfev"] > 10 and m.info["wall_seconds"] >= 0
    np.testing.assert_array_equal(m.t, t)
    R = model.params.R_rear
    # straight rolling: the dependent coordinates integrate exactly linear rates (DOP853 is
    # exact on them up to round-off over 1 s)
    np.testing.assert_allclose(m.q[:, XC], R * 5.0 * t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m.q[:, BETA], 0.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m.dq[:, XC], R * 5.0, rtol=0, atol=1e-12)
    assert inverse_kinematics(model, ROLLING, t, reproject=True).info["reproject"] is True


class SingularAt:
    """The model, whose 13x13 inverse-dynamics system is singular from sample ``k`` on."""

    def __init__(self, model, k):
        self._model, self.k = model, k

    def __getattr__(self, name):
        return getattr(self._model, name)

    def inverse_dynamics_step(self, q, dq, ddq_ind):
        ddq, T, lam, status = self._model.inverse_dynamics_step(q, dq, ddq_ind)
        status = status.copy()
        status[self.k:] = 1
        return ddq, T, lam, status


def test_inverse_dynamics_names_the_first_singular_sample_and_how_many(model):
    """Planted: the last bad sample's time named, the count of all samples."""
    t = np.linspace(0.0, 1.0, 11)
    motion = inverse_kinematics(model, ROLLING, t)
    with pytest.raises(ConstraintSolveError, match=r"^the 13x13 inverse-dynamics system is "
                                                   r"singular at t = 0\.7000 s \(4 sample\(s\)\)$"):
        inverse_dynamics(SingularAt(model, 7), motion)
    ok = inverse_dynamics(model, motion)
    assert ok.status.tolist() == [0] * 11 and ok.motion is motion


# -- the forward run -----------------------------------------------------------------------

def _rolling_state(model):
    """Straight rolling at 5 rad/s (an exact equilibrium of the thesis model with the pedal
    torque that balances the drag, tests/test_solvers.py)."""
    p = model.params
    v = p.R_rear * 5.0
    return (np.zeros(8), np.array([v, 0, 0, 0, 5.0, 0, 0, v / p.R_front]),
            (0.0, p.cv * v ** 2 * p.R_rear, 0.0))


class Spy:
    """The model, counting the single-state forward evaluations (the integrator's)."""

    def __init__(self, model, status_from=None):
        self._model, self.calls, self.status_from = model, 0, status_from

    def __getattr__(self, name):
        return getattr(self._model, name)

    def forward(self, q, dq, *args, **kwargs):
        res = self._model.forward(q, dq, *args, **kwargs)
        if np.ndim(q) == 1:
            self.calls += 1
        elif self.status_from is not None:       # the output grid's batch: singular from k on
            status = res.status.copy()
            status[self.status_from:] = 1
            res = ForwardResult(res.ddq, res.lam, status)
        return res


@pytest.mark.parametrize("constraints, baumgarte", [("baumgarte", THESIS_BAUMGARTE),
                                                    ("baumgarte", (5.0, 3.0)),
                                                    ("projection", THESIS_BAUMGARTE),
                                                    ("none", (5.0, 3.0))])
def test_the_settings_say_how_the_run_was_made(model, constraints, baumgarte):
    """docs/model.md's run settings: the integrator, its tolerances, the constraint handling,
    Baumgarte's two constants only when used, and the fall limit; timing counts every
    right-hand side the integrator evaluated. Planted: baumgarte reported for 'none', the
    thesis's constants reported instead of the given ones, nfev counted twice."""
    q0, dq0, T = _rolling_state(model)
    spy = Spy(model)
    traj = simulate(spy, q0, dq0, np.linspace(0.0, 0.2, 5), T, constraints=constraints,
                    baumgarte=baumgarte, rtol=1e-9, atol=1e-11, fall_limit=1.2)
    assert traj.settings == {"integrator": "DOP853", "rtol": 1e-9, "atol": 1e-11,
                             "constraints": constraints,
                             "baumgarte": list(baumgarte) if constraints == "baumgarte" else None,
                             "fall_limit": 1.2}
    assert traj.timing["nfev"] == spy.calls > 0
    assert traj.timing["wall_seconds"] >= 0


def test_baumgarte_bounds_the_step_and_progress_reports_every_step(model):
    """With Baumgarte (a1 = a2 = 10: the velocity rows decay at 2 a1 + a2^2 = 120 /s) no step
    is longer than 3/120 s = 0.025 s, even at an exact equilibrium whose error estimate
    vanishes; without stabilisation the same run steps far longer. progress is called once
    per accepted step with its end time, the last at the grid's end. Planted: the bound
    left out, 2 a1 + a2 (a rate of 30: steps up to 0.1 s)."""
    q0, dq0, T = _rolling_state(model)
    t = np.linspace(0.0, 2.0, 21)
    steps = {}
    for c in ("baumgarte", "none"):
        ends = []
        traj = simulate(model, q0, dq0, t, T, constraints=c, progress=ends.append)
        assert traj.status == "completed"
        assert ends[-1] == 2.0 and np.all(np.diff(ends) > 0)
        steps[c] = np.diff([0.0, *ends])
    assert steps["baumgarte"].max() <= 0.025 * (1 + 1e-12)
    assert steps["baumgarte"].max() > 0.02         # the bound is what limits it
    assert steps["none"].max() > 0.1


@pytest.mark.parametrize("theta", [DEFAULT_FALL_LIMIT, -DEFAULT_FALL_LIMIT])
def test_a_start_exactly_at_the_fall_limit_has_fallen(model, theta):
    """|theta| = fall_limit is fallen (>=), on either side, with the angle in the message.
    Planted: |theta| > fall_limit, theta >= fall_limit."""
    q = np.zeros(8)
    q[THETA] = theta
    traj = simulate(model, q, np.zeros(8), np.linspace(0.0, 1.0, 11))
    assert traj.status == "fell" and traj.t.tolist() == [0.0] and traj.t_end == 0.0
    assert traj.message == f"|theta| = {DEFAULT_FALL_LIMIT:.3f} rad >= fall limit at the start"


def test_a_fall_is_located_on_the_side_it_happens(model):
    """A run leaned to -theta that topples: the crossing of -fall_limit is found by root
    finding between two steps (the last row is the fall itself, |theta| = limit to 1e-9 as
    in tests/test_solvers.py), and the message gives the limit and the time. Planted: the
    sign of the side (brentq given a bracket without a crossing)."""
    q = np.zeros(8)
    q[THETA] = -0.4
    s = consistent_state(model, q, np.zeros(8))
    traj = simulate(model, s.q, s.dq, np.linspace(0.0, 3.0, 31), fall_limit=0.9)
    assert traj.status == "fell"
    assert traj.q[-1, THETA] == pytest.approx(-0.9, abs=1e-9)
    assert traj.message == (f"|theta| reached the fall limit {0.9:.4f} rad at "
                            f"t = {traj.t_end:.6f} s")


@pytest.mark.parametrize("bad, message", [
    (dict(fall_limit=float("nan")), r"^fall_limit must be a positive angle in rad; got nan$"),
    (dict(fall_limit=-0.1), r"^fall_limit must be a positive angle in rad; got -0\.1$"),
    (dict(constraints="exact"), r"^constraints must be one of \('baumgarte', 'projection', "
                                r"'none'\); got 'exact'$"),
    (dict(t_eval=[0.0]), r"^t_eval must be a strictly increasing 1-D grid of at least 2 "
                         r"samples$"),
    (dict(t_eval=[[0.0, 1.0]]), r"^t_eval must be a strictly increasing 1-D grid"),
    (dict(torques=[[0.0, 1.0, 0.0]]), r"^torques must be \[Mdir, Mped, Mvue\] \(3 finite numbers\) "
                                      r"or a function of t; got \[\[0\.0, 1\.0, 0\.0\]\]$"),
    (dict(torques=(0.0, np.inf, 0.0)), r"^torques must be \[Mdir, Mped, Mvue\]"),
])
def test_bad_run_arguments_are_named(model, bad, message):
    """Each refusal names the argument and what it must be. Planted: NaN let through as a
    fall limit (fall_limit <= 0), a 2-D grid accepted."""
    args = dict(t_eval=np.linspace(0.0, 1.0, 11))
    args.update(bad)
    with pytest.raises(ValueError, match=message):
        simulate(model, np.zeros(8), np.zeros(8), args.pop("t_eval"), **args)


def test_a_torque_function_is_called_at_each_time(model):
    """A callable torque is used as given, at the output times too (the T column)."""
    q0, dq0, (_, Mped, _) = _rolling_state(model)
    t = np.linspace(0.0, 0.3, 4)
    traj = simulate(model, q0, dq0, t, lambda s: np.array([0.0, Mped, 0.1 * s]))
    np.testing.assert_array_equal(traj.T, np.stack([0 * t, Mped + 0 * t, 0.1 * t], -1))


def test_a_singular_rhs_is_named_as_such(model):
    """The integrator's first evaluation singular: the run fails at t = 0 with the reason.
    Planted: the two reasons swapped."""
    class Singular(Spy):
        def forward(self, q, dq, *args, **kwargs):
            res = self._model.forward(q, dq, *args, **kwargs)
            return ForwardResult(res.ddq, res.lam, np.ones_like(res.status))
    q0, dq0, T = _rolling_state(model)
    traj = simulate(Singular(model), q0, dq0, np.linspace(0.0, 1.0, 11), T)
    assert traj.status == "failed" and traj.t.size == 0
    assert traj.message == "right-hand side failed at t = 0.000000 s: singular constraint/mass system"


def test_a_nan_torque_is_a_non_finite_state(model):
    q0, dq0, _ = _rolling_state(model)
    traj = simulate(model, q0, dq0, np.linspace(0.0, 1.0, 11), lambda s: np.full(3, np.nan))
    assert traj.status == "failed"
    assert traj.message == "right-hand side failed at t = 0.000000 s: non-finite state"


def test_output_samples_after_a_singular_one_are_cut(model):
    """The output grid's own accelerations singular from sample 4 on: the run keeps samples
    0-3 and names the last kept time. Planted: the cut at k + 1, the first sample's time."""
    q0, dq0, T = _rolling_state(model)
    t = np.linspace(0.0, 1.0, 11)
    traj = simulate(Spy(model, status_from=4), q0, dq0, t, T)
    assert traj.status == "failed" and traj.t.tolist() == t[:4].tolist()
    assert traj.message == "singular system at t = 0.300000 s"
    for name in ("q", "dq", "ddq", "C", "T"):
        assert getattr(traj, name).shape[0] == 4, name
    assert traj.t_end == t[3]


def _leaning_and_steering(t):
    """theta = 0.1 + 0.2 t, psi = 5 t, gamma = 0.3 t: every sample a different upright pitch."""
    t = np.asarray(t, dtype=float)
    z = np.zeros_like(t)
    return (np.stack([0.1 + 0.2 * t, 5.0 * t, 0.3 * t], -1),
            np.stack([0.2 + z, 5.0 + z, 0.3 + z], -1), np.stack([z, z, z], -1))


def test_inverse_kinematics_starts_on_the_constraint_at_the_first_time(model):
    """beta(t0) is solved at the independent coordinates of t0, so every sample's front
    contact stays on the ground (to the integration's 1e-12 tolerance, ~1e-11 m over 1 s).
    Planted: the start solved at the grid's last time (its front contact is then 6.3e-3 m
    below the ground at t0)."""
    t = np.linspace(0.0, 1.0, 11)
    m = inverse_kinematics(model, IndependentMotion(_leaning_and_steering), t)
    heights = np.array([model.constraint_residual(q, np.zeros(8))[0] for q in m.q])
    assert np.max(np.abs(heights)) < 1e-10
    np.testing.assert_array_equal(m.q[:, IND], _leaning_and_steering(t)[0])
