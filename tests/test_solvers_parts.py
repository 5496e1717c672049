"""The solvers' parts (reference_model/solvers.py), issue 24, third round: what
tests/test_solvers.py and tests/test_solvers_edges.py left of the forward run's fall
detection, its non-finite cut and its input conversion, and of inverse kinematics' accuracy.

Expected values come from outside the code under test: IEEE rounding worked by hand (a lean
one ulp below the limit that a one-ulp increment puts exactly on it), the steady turn's
closed-form solution (a circle: the model is invariant under a yaw rotation, so every
body-frame rate is constant and the rear contact's velocity turns at the yaw rate), straight
rolling's xc = R_rear psi, the root finder's stated tolerance (xtol 1e-14 s, as
tests/test_solvers.py quotes it) times the lean rate, and numpy's conversion of any real
number to float64. Each test names the planted bug it was seen failing on.
"""

import warnings
from fractions import Fraction

import numpy as np
import pytest

from reference_model import load_model
from reference_model.model import DEP, N_C, N_Q, ForwardResult
from reference_model.solvers import (THETA, IndependentMotion, consistent_state,
                                     dependent_rates, inverse_kinematics, simulate, solve_beta)

XC, YC, PHI, PSI, BETA, GAMMA, EPS = 0, 1, 2, 4, 5, 6, 7


@pytest.fixture(scope="module")
def model():
    return load_model("thesis")


def _rolling_state(model, rate=5.0):
    """Straight rolling at ``rate`` rad/s with the pedal torque that balances the drag: an
    exact equilibrium of the thesis model (tests/test_solvers.py), so xc = R_rear rate t."""
    p = model.params
    v = p.R_rear * rate
    return (np.zeros(8), np.array([v, 0, 0, 0, rate, 0, 0, v / p.R_front]),
            (0.0, p.cv * v ** 2 * p.R_rear, 0.0))


# -- the fall: detection and location ------------------------------------------------------------

class Drift:
    """A duck-typed model in which every coordinate moves at its own constant rate (ddq = 0,
    every constraint satisfied): a lean that creeps at a known speed."""

    def forward(self, q, dq, torques=(0.0, 0.0, 0.0), baumgarte=(0.0, 0.0)):
        shape = np.shape(q)[:-1]
        return ForwardResult(np.zeros(shape + (N_Q,)), np.zeros(shape + (N_C,)),
                             np.zeros(shape or (1,), dtype=np.intc))

    def constraint_residual(self, q, dq):
        return np.zeros(np.shape(q)[:-1] + (N_C,))


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_step_that_ends_exactly_on_the_limit_is_a_fall_recorded_once(side):
    """The lean starts one ulp inside the limit 0.9 rad and creeps one ulp in 1 ms: the
    grid [0, 1 ms] is a single step (the progress says so) whose end is the limit exactly
    (0.9 - ulp plus an increment within 1e-15 of that ulp rounds to 0.9). Reaching the limit
    is a fall, as at the start (>=): status 'fell' at 1 ms, the event row once (the grid's
    last time is the fall itself), |theta| = 0.9 there. Planted: '>' for '>=' in the time
    loop (the run 'completed'), '<=' for '<' before appending the fall (the time twice)."""
    lim, dt = 0.9, 1e-3
    below = np.nextafter(lim, 0.0)
    q, dq = np.zeros(8), np.zeros(8)
    q[THETA], dq[THETA] = side * below, side * (lim - below) / dt
    ends = []
    traj = simulate(Drift(), q, dq, [0.0, dt], constraints="none", fall_limit=lim,
                    progress=ends.append)
    assert ends == [dt]
    assert traj.status == "fell", traj.message
    assert traj.t.tolist() == [0.0, dt] and traj.t_end == dt
    assert traj.q[-1, THETA] == side * lim
    assert traj.message == "|theta| reached the fall limit 0.9000 rad at t = 0.001000 s"


@pytest.fixture(scope="module")
def falls(model):
    """Two topples without stabilisation, leaned 0.4 rad to a limit of 0.9 and 0.6 rad to
    0.7, with every warning they raise recorded."""
    runs = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for theta0, limit in [(0.4, 0.9), (0.6, 0.7)]:
            q = np.zeros(8)
            q[THETA] = theta0
            s = consistent_state(model, q, np.zeros(8))
            runs.append((limit, simulate(model, s.q, s.dq, np.linspace(0.0, 3.0, 31),
                                         constraints="none", fall_limit=limit)))
    return runs, caught


def test_the_fall_row_is_on_the_limit_to_the_root_finder_s_tolerance(falls):
    """The fall time is located on the step's dense output to brentq's xtol 1e-14 s (plus
    4 eps relative): the last row's |theta| is then the limit to |dtheta| (2 xtol) plus a few
    ulps of the angle. These two falls are ones where brentq at its default xtol (2e-12 s)
    stops 2e-13 s and 4e-13 s early, 4e-13 rad short of the limit. Planted: xtol left at its
    default."""
    for limit, traj in falls[0]:
        assert traj.status == "fell", traj.message
        rate = abs(traj.dq[-1, THETA])
        bound = rate * 2 * (1e-14 + 4 * np.finfo(float).eps * traj.t_end) + 4 * np.spacing(limit)
        assert abs(abs(traj.q[-1, THETA]) - limit) <= bound, (limit, traj.q[-1, THETA], bound)
        assert bound < 6e-14


def test_a_falling_run_raises_no_warning(falls):
    """Locating a fall is silent: no DeprecationWarning or other warning reaches the user.
    Planted: np.finfo(None) in brentq's rtol (deprecated by numpy 1.25, to become an error)."""
    runs, caught = falls
    assert all(traj.status == "fell" for _, traj in runs)
    assert [str(w.message) for w in caught] == []


# -- the non-finite cut ----------------------------------------------------------------------------

class NaNBeyond:
    """The thesis model whose mass matrix is NaN once the rear contact is past ``x`` m (a
    user's model outside its valid range): the projection of any state there is NaN."""

    def __init__(self, model, x):
        self._model, self.x = model, x

    def __getattr__(self, name):
        return getattr(self._model, name)

    def mass_matrix(self, q):
        M = self._model.mass_matrix(q)
        return M * np.nan if q[XC] > self.x else M


def test_samples_projected_to_nan_are_cut_at_the_first_one(model):
    """Straight rolling at 1.6 m/s with projection, on a model whose mass matrix is NaN past
    xc = 0.5 m (t = 0.3125 s). At this equilibrium the error estimate vanishes and one step
    spans 0.1 .. 0.5 s, so its projected samples at 0.4 s and 0.5 s are NaN before the step's
    end fails. The run keeps the grid up to 0.3 s, every row finite, and fails naming the last
    good time. Planted: the finiteness checked over the whole array (everything cut), the
    cut left out (NaN rows kept), the time of the first or second kept row in the message,
    the status string."""
    q0, dq0, T = _rolling_state(model)
    t = np.linspace(0.0, 1.0, 11)
    traj = simulate(NaNBeyond(model, 0.5), q0, dq0, t, T, constraints="projection")
    assert (traj.status, traj.message) == ("failed", "state became non-finite after t = "
                                                     "0.300000 s")
    np.testing.assert_array_equal(traj.t, t[:4])
    assert traj.t_end == t[3]
    for name in ("q", "dq", "ddq", "C", "T"):
        a = getattr(traj, name)
        assert a.shape[0] == 4 and np.all(np.isfinite(a)), name
    np.testing.assert_allclose(traj.q[:, XC], 1.6 * t[:4], rtol=0, atol=1e-12)


# -- what a start may be written in ----------------------------------------------------------------

def test_a_run_written_in_exact_fractions_is_the_run_of_their_float_values(model):
    """q0, dq0, the grid and the torques as fractions.Fraction (what a symbolic derivation
    gives): numpy converts each to its float64, so the run is that of those floats to the last
    bit, its times the float grid (0.1 s, not 1/10). The same for the consistent state and the
    dependent rates. Planted: the float64 conversion of q0, dq0, t_eval or the torques dropped
    (object arrays: np.isfinite refuses them, or the output times stay fractions), of q or dq
    in consistent_state, of the independent rates in dependent_rates."""
    q0, dq0, T = _rolling_state(model)
    t = np.array([0.0, 0.1, 0.2])
    ref = simulate(model, q0, dq0, t, T)
    run = simulate(model, [Fraction(x) for x in q0], [Fraction(x) for x in dq0],
                   [Fraction(k, 10) for k in range(3)], [Fraction(x) for x in T])
    assert run.status == ref.status == "completed"
    for name in ("t", "q", "dq", "ddq", "C", "T"):
        a = getattr(run, name)
        assert a.dtype == np.float64, name
        np.testing.assert_array_equal(a, getattr(ref, name), err_msg=name)
    lean = [Fraction(0)] * 3 + [Fraction(1, 5)] + [Fraction(0)] * 2 + [Fraction(3, 10), 0]
    rates = [Fraction(1, 2)] * 8
    want = consistent_state(model, np.array(lean, dtype=float), np.full(8, 0.5))
    got = consistent_state(model, lean, rates)
    np.testing.assert_array_equal(got.q, want.q)
    np.testing.assert_array_equal(got.dq, want.dq)
    np.testing.assert_array_equal(dependent_rates(model, want.q, rates[:3]), want.dq)


def _turn_in_numpy(t):
    """A user's motion written with numpy's functions on t as it comes (no conversion)."""
    z = 0.0 * t
    return (np.stack([0.1 * np.sin(t), 5.0 * t, z], -1),
            np.stack([0.1 * np.cos(t), 5.0 + z, z], -1),
            np.stack([-0.1 * np.sin(t), z, z], -1))


def test_a_grid_written_in_exact_fractions_is_its_float_grid_for_inverse_kinematics(model):
    """The motion's function is handed float64 times whatever the caller wrote (np.sin has no
    loop for a Fraction), and inverse kinematics on a grid of fractions is the motion on the
    float grid, to the last bit. Planted: the float64 conversion in IndependentMotion's call or
    of inverse kinematics' grid dropped."""
    motion = IndependentMotion(_turn_in_numpy)
    grid = [Fraction(k, 10) for k in range(4)]
    t = np.array([0.0, 0.1, 0.2, 0.3])
    for got, want in zip(motion(grid), _turn_in_numpy(t)):
        np.testing.assert_array_equal(got, want)
    ref = inverse_kinematics(model, motion, t)
    m = inverse_kinematics(model, motion, grid)
    assert m.t.dtype == np.float64
    for name in ("t", "q", "dq", "ddq_ind"):
        np.testing.assert_array_equal(getattr(m, name), getattr(ref, name), err_msg=name)


# -- inverse kinematics' accuracy ------------------------------------------------------------------

TH, GA, W = 0.2, 0.3, 5.0   # a steady turn: leaned 0.2 rad, steered 0.3 rad, wheel at 5 rad/s


def _steady_turn(t):
    t = np.asarray(t, dtype=float)
    z = np.zeros_like(t)
    return (np.stack([TH + z, W * t, GA + z], -1), np.stack([z, W + z, z], -1),
            np.stack([z, z, z], -1))


def test_inverse_kinematics_follows_the_steady_turn_s_circle_to_its_tolerance(model):
    """With theta, gamma and dpsi constant the motion is a steady turn: the model is invariant
    under yaw, so beta stays put, phi and eps grow at their initial rates and the rear contact
    runs on a circle, its velocity turning at Omega = dphi:
      xc = (u sin(Omega t) - w (1 - cos(Omega t))) / Omega,
      yc = (w sin(Omega t) + u (1 - cos(Omega t))) / Omega   ((u, w) the start's (dxc, dyc)).
    Over 6 s (nearly half a turn, radius 3.2 m) DOP853 at the default rtol = atol = 1e-12 keeps
    every dependent coordinate within 1e-11 m or rad of it (the tolerance times the circle's
    6.4 m, and some). Planted: the method dropped (RK45 at the same tolerances: 4.5e-11 m)."""
    t = np.linspace(0.0, 6.0, 61)
    q0 = np.zeros(8)
    q0[THETA], q0[GAMMA] = TH, GA
    q0, _ = solve_beta(model, q0)
    d = dependent_rates(model, q0, [0.0, W, 0.0])
    om, u, w = d[PHI], d[XC], d[YC]
    exact = np.zeros((t.size, 8))
    exact[:, XC] = (u * np.sin(om * t) - w * (1 - np.cos(om * t))) / om
    exact[:, YC] = (w * np.sin(om * t) + u * (1 - np.cos(om * t))) / om
    exact[:, PHI] = om * t
    exact[:, BETA] = q0[BETA]
    exact[:, EPS] = d[EPS] * t
    m = inverse_kinematics(model, IndependentMotion(_steady_turn), t)
    assert 3.0 < np.hypot(u, w) / om < 3.4 and om * t[-1] > 3.0     # nearly half a turn
    np.testing.assert_allclose(m.q[:, DEP], exact[:, DEP], rtol=0, atol=1e-11)


# -- a start or a projection that cannot be solved is a failed run, not an exception -----------

class SingularBeyond(NaNBeyond):
    """The reference model, with a zero (singular) mass matrix from xc = x on: the projection's
    solve M^-1 D^T has no answer there (numpy's LinAlgError, a ValueError)."""

    def mass_matrix(self, q):
        M = self._model.mass_matrix(q)
        return np.zeros_like(M) if q[XC] > self.x else M


def test_a_projection_that_numpy_cannot_solve_is_a_failed_run(model):
    """A run that cannot go on is returned as a failed run with its reason (Trajectory.status
    'failed', as for a singular system inside the run), never raised. With projection, the projected start meets a singular mass
    matrix (xc = 0 > -1): numpy's solve raises LinAlgError, which is a ValueError and not an
    ArithmeticError, so the handler that named it in its comment let it through. Seen failing
    (LinAlgError: Singular matrix) before the fix."""
    q0, dq0, T = _rolling_state(model)
    traj = simulate(SingularBeyond(model, -1.0), q0, dq0, [0.0, 0.1], T, constraints="projection")
    assert traj.status == "failed"
    assert traj.message == "constraint projection failed: Singular matrix"
    assert traj.t.size == 0


def test_a_start_that_projects_to_nan_is_a_failed_run_naming_it(model):
    """A mass matrix that is NaN at the start (xc = 0 > -1) projects the start to NaN, which
    scipy's DOP853 refuses in its constructor (ValueError 'must be finite'): the run is failed,
    with the reason in one line, and holds no sample. Seen failing (the ValueError raised out
    of simulate) before the fix."""
    q0, dq0, T = _rolling_state(model)
    traj = simulate(NaNBeyond(model, -1.0), q0, dq0, [0.0, 0.1], T, constraints="projection")
    assert (traj.status, traj.message) == ("failed", "the projected initial state is not finite")
    assert traj.t.size == 0 and traj.q.shape == (0, 8)
