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
    (dict(fall_limit=np.inf), r"^fall_limit must be a positive angle in rad; got inf$"),
    (dict(fall_limit="1.4"), r"^fall_limit must be a positive angle in rad; got '1\.4'$"),
    (dict(fall_limit=True), r"^fall_limit must be a positive angle in rad; got True$"),
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


# -- round two: what the first measurement of these tests left (issue 24) ----------------------

def test_integer_and_row_inputs_are_states_like_any_other(model):
    """A user's q0 written as integers, or as a (1, 8) row and a (8, 1) column: the same
    solution as the float vector. Planted: Newton on an integer array (each step truncated,
    so it never converges), the reshape to (8,) left out."""
    q_int = [0, 0, 0, 1, 0, 0, 1, 0]          # leaned and steered 1 rad: beta is 0.098 rad
    q_ref, its = solve_beta(model, np.array(q_int, dtype=float))
    q, its_int = solve_beta(model, q_int)
    assert q.dtype == np.float64 and its_int == its and q[BETA] == q_ref[BETA] > 0.09
    ref = consistent_state(model, np.array(q_int, dtype=float), np.ones(8))
    row = consistent_state(model, [q_int], np.ones((8, 1), dtype=int))
    np.testing.assert_array_equal(row.q, ref.q)
    np.testing.assert_array_equal(row.dq, ref.dq)
    q0, dq0, T = _rolling_state(model)
    t = np.linspace(0.0, 0.2, 3)
    flat = simulate(model, q0, dq0, t, T)
    shaped = simulate(model, q0.reshape(1, 8), dq0.reshape(8, 1), t, T)
    np.testing.assert_array_equal(shaped.q, flat.q)


def test_the_states_in_messages_are_rounded_to_six_digits():
    """Planted: the rounding's digits (none: integers; seven)."""
    q = np.full(8, 0.1234567)
    with pytest.raises(ConstraintSolveError, match=r"at q = \[0\.123457, 0\.123457, "):
        solve_beta(Scalar(lambda b: 1.0, lambda b: 0.0), q)
    D = np.zeros((N_C, N_Q))
    with pytest.raises(ConstraintSolveError, match=r"at q = \[0\.123457, 0\.123457, "):
        dependent_rates(Linear(D), q, [1.0, 0.0, 0.0])


def test_describe_reports_the_worst_velocity_residual_of_rows_two_to_five():
    """On a state built by hand: the largest |C| among the four velocity rows, before and
    after. Planted: the after's rows from the third on (the second row's 5e-3 missed)."""
    from reference_model.solvers import ConsistentState
    q = np.zeros(8)
    s = ConsistentState(q, q, q, q, 3, np.array([1e-3, 0.0, 2e-2, 0.0, -4e-2]),
                        np.array([0.0, 5e-3, 0.0, 0.0, 0.0]))
    assert s.describe() == ("beta corrected by +0.000000e+00 rad in 3 Newton iteration(s); "
                            "front contact height +1.000e-03 m -> +0.0e+00 m; max |velocity "
                            "constraint| 4.000e-02 -> 5.0e-03 m/s")


def test_the_documented_defaults(model):
    """docs/model.md: forward runs at rtol 1e-10, atol 1e-12, Baumgarte 10, 10, the fall
    limit 1.4 rad; Newton gives up after 50 iterations (51 evaluations). Planted: each
    default changed."""
    q0, dq0, T = _rolling_state(model)
    traj = simulate(model, q0, dq0, [0.0, 0.1], T)
    assert traj.settings == {"integrator": "DOP853", "rtol": 1e-10, "atol": 1e-12,
                             "constraints": "baumgarte", "baumgarte": [10.0, 10.0],
                             "fall_limit": 1.4}
    assert traj.message == "reached the end of the grid" and traj.status == "completed"
    m = Scalar(lambda b: b * b + 1.0, lambda b: 2.0 * b)
    q = np.zeros(8)
    q[BETA] = 0.7
    with pytest.raises(ConstraintSolveError, match="did not converge in 50 iterations"):
        solve_beta(m, q)
    assert m.calls == 51


@pytest.mark.parametrize("baumgarte", [(5.0, 3.0), (0.2, 0.5)])
def test_the_step_bound_follows_both_baumgarte_constants(model, baumgarte):
    """3 / (2 a1 + a2^2): (5, 3) -> 3/19 s, (0.2, 0.5) -> 3/0.65 s (a rate below 1 still
    bounds the step). At the straight-rolling equilibrium the error estimate vanishes, so the
    steps grow to the bound. Planted: 3 a1, 2 a2, the bound only for rates above 1."""
    a1, a2 = baumgarte
    bound = 3.0 / (2 * a1 + a2 ** 2)
    q0, dq0, T = _rolling_state(model)
    ends = []
    traj = simulate(model, q0, dq0, np.linspace(0.0, 12 * bound, 13), T, baumgarte=baumgarte,
                    progress=ends.append)
    assert traj.status == "completed"
    steps = np.diff([0.0, *ends])
    assert bound * (1 - 1e-9) < steps.max() <= bound * (1 + 1e-12)


def test_the_shortest_grid_is_two_samples_and_no_time_repeats(model):
    """Planted: three samples required, a repeated time let through."""
    q0, dq0, T = _rolling_state(model)
    assert simulate(model, q0, dq0, [0.0, 0.05], T).t.tolist() == [0.0, 0.05]
    with pytest.raises(ValueError, match="strictly increasing"):
        simulate(model, q0, dq0, [0.0, 0.05, 0.05], T)


class Blowup(Spy):
    """xc'' = 1 / (1 - xc)^3 from rest: xc reaches 1 with an infinite speed at t = 1 exactly
    (energy: xc'^2 = 1/(1 - xc)^2 - 1, and the integral of u / sqrt(1 - u^2) over (0, 1) is
    1), so the integrator's steps shrink to nothing there."""

    def forward(self, q, dq, *args, **kwargs):
        res = self._model.forward(q, dq, *args, **kwargs)
        if np.ndim(q) != 1:
            return res
        ddq = np.zeros(N_Q)
        ddq[XC] = (1.0 - q[XC]) ** -3 if q[XC] < 1.0 else 1e300
        return ForwardResult(ddq, res.lam, res.status)


def test_an_integrator_failure_ends_the_run_where_it_happened(model):
    """The blow-up at t = 1: the run stops there as 'failed', with the integrator's own
    reason, and keeps every sample before it. Planted: the failure's branch not taken (the
    status string), its message lost, return for break (no trajectory at all)."""
    t = np.linspace(0.0, 5.0, 11)
    traj = simulate(Blowup(model), np.zeros(8), np.zeros(8), t, constraints="none")
    assert traj.status == "failed"
    found = re.fullmatch(r"integrator failed at t = (1\.0000\d\d) s: Required step size is "
                         r"less than spacing between numbers\.", traj.message)
    assert found, traj.message
    assert traj.t.tolist() == [0.0, 0.5, 1.0][:traj.t.size] and traj.t.size >= 2
    assert traj.t[-1] <= float(found.group(1))


def test_an_unknown_status_of_the_model_is_a_question_mark(model):
    class Odd(Spy):
        def forward(self, q, dq, *args, **kwargs):
            res = self._model.forward(q, dq, *args, **kwargs)
            return ForwardResult(res.ddq, res.lam, np.full_like(res.status, 7))
    q0, dq0, T = _rolling_state(model)
    traj = simulate(Odd(model), q0, dq0, [0.0, 0.5, 1.0], T)
    assert (traj.status, traj.message) == ("failed", "right-hand side failed at t = 0.000000 s: ?")
    assert traj.t_end == 0.0


def test_a_projection_that_cannot_be_made_fails_the_run_with_its_reason(model):
    """A model whose front contact never meets the ground at any pitch (height 1 m, slope
    0): the first projection fails, and the run says why. Planted: the message lost."""
    class Floating(Spy):
        def constraint_residual(self, q, dq):
            return self._model.constraint_residual(q, dq) + np.eye(N_C)[0]

        def constraint_jacobian(self, q):
            D = self._model.constraint_jacobian(q).copy()
            D[0, BETA] = 0.0
            return D
    q0, dq0, T = _rolling_state(model)
    traj = simulate(Floating(model), q0, dq0, [0.0, 0.5], T, constraints="projection")
    assert traj.status == "failed" and traj.t.size == 0 and traj.t_end == 0.0
    assert traj.message.startswith("constraint projection failed: d[rD]_z/dbeta = 0.00e+00 at ")


def test_a_singular_first_output_sample_names_the_grid_start(model):
    """Planted: the grid's second time named, t_arr[-1] read from an empty cut."""
    q0, dq0, T = _rolling_state(model)
    traj = simulate(Spy(model, status_from=0), q0, dq0, [0.5, 0.75, 1.0], T)
    assert (traj.status, traj.message) == ("failed", "singular system at t = 0.500000 s")
    assert traj.t.size == 0 and traj.t_end == 0.5


def test_a_fall_before_the_first_grid_time_keeps_the_start_and_the_fall(model):
    """A grid [0, 10] s and a fall at 0.57 s: the start and the fall itself, nothing else;
    the fall located to brentq's xtol 1e-14 s (theta moves at 2 rad/s there: 2e-14 rad, and
    the interpolant's rounding; measured 1e-15). Planted: the second sample's time compared
    (an index error with a single sample). (brentq at its default xtol, 2e-12 s, still
    converges to 1e-15 here: its last secant steps overshoot the tolerance.)"""
    q = np.zeros(8)
    q[THETA] = 0.4
    s = consistent_state(model, q, np.zeros(8))
    traj = simulate(model, s.q, s.dq, [0.0, 10.0], fall_limit=0.9)
    assert traj.status == "fell" and traj.t.size == 2 and traj.t[0] == 0.0
    assert 0.5 < traj.t[1] < 0.7
    assert abs(traj.q[-1, THETA] - 0.9) < 1e-13


def test_the_output_accelerations_are_those_of_the_run_s_own_constraint_handling(model):
    """With Baumgarte the ddq column is the stabilised one (the constants enter where C is not
    zero): from a start off the velocity constraints, it is the model's forward with (10, 10),
    not the exact one. Planted: the output's accelerations without the constants."""
    q0, dq0, T = _rolling_state(model)
    dq0 = dq0.copy()
    dq0[YC] = 0.05                       # sideways slip of the rear contact: C[2] != 0
    traj = simulate(model, q0, dq0, [0.0, 0.01], T)
    stab = model.forward(traj.q, traj.dq, traj.T, THESIS_BAUMGARTE).ddq
    exact = model.forward(traj.q, traj.dq, traj.T, (0.0, 0.0)).ddq
    np.testing.assert_array_equal(traj.ddq, stab)
    assert np.max(np.abs(stab[0] - exact[0])) > 0.1


def test_wall_time_is_a_duration(model):
    """Planted: perf_counter() + t0 (a clock reading, not a duration)."""
    import time
    q0, dq0, T = _rolling_state(model)
    t0 = time.perf_counter()
    traj = simulate(model, q0, dq0, [0.0, 0.1], T)
    m = inverse_kinematics(model, ROLLING, [0.0, 0.1])
    took = time.perf_counter() - t0
    assert 0 <= traj.timing["wall_seconds"] <= took and 0 <= m.info["wall_seconds"] <= took


def test_an_inverse_kinematics_integration_that_fails_says_so(model):
    """Prescribed rates that blow up at t = 1 (dpsi = 1 / (1 - t)^2): the integration of the
    dependent coordinates cannot pass it (at loose tolerances, so the steps shrink to nothing
    in a few hundred; at 1e-12 that takes a minute and a half). Planted: the message lost."""
    def blowing(t):
        t = np.asarray(t, dtype=float)
        z = np.zeros_like(t)
        rate = 1.0 / (1.0 - np.minimum(t, 1.0 - 1e-300)) ** 2
        return (np.stack([z, z, z], -1), np.stack([z, rate, z], -1), np.stack([z, z, z], -1))
    with pytest.raises(ConstraintSolveError, match=r"^inverse kinematics integration failed: "
                                                   r"Required step size is less than spacing "
                                                   r"between numbers\.$"):
        inverse_kinematics(model, IndependentMotion(blowing), np.linspace(0.0, 2.0, 5),
                           rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("where", ["q0", "dq0"])
def test_a_non_finite_start_of_a_run_is_refused_in_words(model, where):
    """Planted: the message's wording (the contract docs/model.md quotes)."""
    q, dq = np.zeros(8), np.zeros(8)
    (q if where == "q0" else dq)[THETA] = np.nan
    with pytest.raises(ValueError, match=r"^initial state must be finite \(no NaN or inf in q0, "
                                         r"dq0\)$"):
        simulate(model, q, dq, [0.0, 1.0])
