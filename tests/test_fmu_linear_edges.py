"""The fmu engine's roll/steer linearization (engines/fmu/linear.py) on hand-made systems, no
FMU: its functions take the constraint residual, its Jacobian D, dD . dq and the state
derivatives' Jacobian-vector product as callables, so each edge is checked where the answer is
known in closed form.

* `upright_state`: Newton on the front contact's height for the pitch beta (a height
  R sin(beta - b0) with its root b0 written here), the rear wheel's rate v / R_rear and the
  dependent rates on D dq = 0 (the velocity constraints, checked as such); its refusals (a
  slope that vanishes, a height that never reaches zero) whole.
* `tangents`: on a random D and dD . dq, each tangent keeps the constraints to first order as
  the module docstring derives them, checked by the constraints themselves: the height row
  D[0] . dq_dir = 0 and, along the tangent, d(D dq) = (dD . dq_dir) dq0 + D d(dq) = 0. At
  upright on a real bicycle D[0, theta] = D[0, gamma] = 0 by symmetry (tests/test_fmu_linear.py
  says so), so a wrong beta component is invisible there and needs a D without that symmetry.
* `roll_steer_eigenvalues`: two decoupled oscillators (roll 2 rad/s, steer 1 rad/s), whose
  eigenvalues +-2i, +-1i are known; the steady-motion check at the docstring's bound 1e-8 of
  g + (v / R_rear)^2 R_rear (below, at and above it); the refusal of speeds that are not a finite
  1-D array, whole.

Written from the survivors of `make mutants` on the module; about 0.05 s (4x4 and 5x5 numpy
solves only).
"""

from __future__ import annotations

import numpy as np
import pytest

from engines.fmu.linear import roll_steer_eigenvalues, tangents, upright_state
from reference_model.linearize import LinearizationError

#: docs/model.md's coordinate order: xc yc phi theta psi beta gamma eps
XC, YC, PHI, THETA, PSI, BETA, GAMMA, EPS = range(8)
DEP = [XC, YC, PHI, BETA, EPS]       # the dependent coordinates (module docstring)
#: a wheel radius of the thesis bicycle's size (m) and the pitch root of the height used here
R = 0.3
B0 = 0.2


def _d_matrix(seed: int) -> np.ndarray:
    """A random 5x8 constraint Jacobian with a well-conditioned dependent block (its diagonal
    raised) and no zero entry, so that every column and row matters."""
    rng = np.random.default_rng(seed)
    D = rng.uniform(0.5, 1.5, size=(5, 8)) * rng.choice([-1.0, 1.0], size=(5, 8))
    D[np.arange(5), DEP] += 4.0 * np.sign(D[np.arange(5), DEP])
    return D


# -- the steady motion ------------------------------------------------------------------------

def test_upright_state_solves_the_pitch_and_the_dependent_rates():
    """The front contact's height R sin(beta - b0) (m) has its root at beta = b0 = 0.2 rad; D's
    height row is its gradient (R cos(beta - b0) in beta), the other rows random. Newton lands
    on b0 to 1e-13 rad (the height tolerance 1e-14 m over the slope R = 0.3 m/rad is 3e-14 rad,
    plus sin's rounding near 0, ~1e-17); theta, gamma and every other coordinate stay 0; the
    rear wheel turns at v / R_rear exactly (one division); the rates satisfy the velocity
    constraints D(q0) dq0 = 0 to 1e-13 of |D| |dq0| (a 5x5 solve, ~10 eps times its condition
    ~10). Fails when the Newton step multiplies by the slope instead of dividing (then 50
    iterations do not converge and it raises)."""
    D0 = _d_matrix(7)

    def residual(q, dq):
        return np.array([R * np.sin(q[BETA] - B0), 0.0, 0.0, 0.0, 0.0])

    def jacobian(q):
        D = D0.copy()
        D[0] = 0.0
        D[0, BETA] = R * np.cos(q[BETA] - B0)
        return D

    v, R_rear = 5.0, 0.35
    q0, dq0 = upright_state(residual, jacobian, v, R_rear)
    assert abs(q0[BETA] - B0) <= 1e-13
    assert np.all(np.delete(q0, BETA) == 0.0)
    assert dq0[PSI] == v / R_rear and dq0[THETA] == 0.0 and dq0[GAMMA] == 0.0
    D = jacobian(q0)
    assert np.max(np.abs(D @ dq0)) <= 1e-13 * np.max(np.abs(D)) * np.max(np.abs(dq0))
    assert np.max(np.abs(dq0[DEP])) > 1.0       # the rates are really solved for, not zero


def test_a_height_at_the_newton_tolerance_is_on_the_ground():
    """The tolerance _NEWTON_TOL = 1e-14 m is, as its comment says, the front contact's height
    at the solved pitch: a height of exactly 1e-14 m at beta = 0 is accepted there, beta left
    at 0 (an inclusive tolerance, as every bound of this project). Fails when the test is
    strict (then Newton steps on a height that cannot drop further, 50 times, and raises)."""
    q0, dq0 = upright_state(lambda q, dq: np.array([1e-14, 0.0, 0.0, 0.0, 0.0]),
                            lambda q: _d_matrix(3), 2.0, 0.3)
    assert np.all(q0 == 0.0) and dq0[PSI] == 2.0 / 0.3


def test_a_pitch_that_does_not_move_the_front_contact_is_refused():
    """d[rD]_z/dbeta = 0 at upright with the contact off the ground: the front contact does
    not fix the pitch; one line naming the derivative and what to check. Fails when the
    refusal loses its message (or Newton divides by zero)."""
    D = _d_matrix(3)
    D[0, BETA] = 0.0
    with pytest.raises(LinearizationError) as err:
        upright_state(lambda q, dq: np.array([0.01, 0.0, 0.0, 0.0, 0.0]), lambda q: D, 2.0, 0.3)
    assert str(err.value) == ("d[rD]_z/dbeta vanishes at upright: the front contact does not fix "
                              "the frame pitch; check the geometry")


def test_a_height_that_never_reaches_zero_stops_after_fifty_newton_steps():
    """A front contact 1 m above the ground whatever the pitch (slope 1 m/rad in the Jacobian,
    as a height output that ignores beta while D says otherwise): Newton does not converge, and
    the line says so with the iteration count and the last height 1.00e+00 m. Fails when the
    message is lost."""
    D = _d_matrix(3)
    D[0, BETA] = 1.0
    with pytest.raises(LinearizationError) as err:
        upright_state(lambda q, dq: np.array([1.0, 0.0, 0.0, 0.0, 0.0]), lambda q: D, 2.0, 0.3)
    assert str(err.value) == ("Newton on [rD]_z = 0 for the pitch beta did not converge in 50 "
                              "iterations (height 1.00e+00 m)")


# -- the tangents -----------------------------------------------------------------------------

def test_each_tangent_keeps_the_constraints_to_first_order():
    """A random D and dD . dq (linear in the direction: a random 5x8x8 tensor H, dD . d =
    H @ d) with no symmetry, at a random dq0. Per the module docstring: theta's and gamma's
    tangents change that coordinate by 1 and beta by -D[0, k] / D[0, beta], nothing else of q,
    which keeps the front contact's height, D[0] . dq_dir = 0; along every tangent the
    velocity constraints stay to first order, (dD . dq_dir) dq0 + D d(dq) = 0 (the product
    rule on D(q) dq = 0), with the independent rates unchanged but the one moved; d_theta's and
    d_gamma's move no coordinate. Checked to 1e-12 of the terms' size (5x5 solves, condition
    ~10). Fails when beta's component takes the wrong sign, multiplies by D[0, beta] or reads
    another row of D (all invisible at a real bicycle's upright, where D[0, theta] =
    D[0, gamma] = 0), or when a tangent's dependent rates miss dD . dq or D's column."""
    D = _d_matrix(11)
    rng = np.random.default_rng(12)
    H = rng.normal(size=(5, 8, 8))
    dq0 = rng.normal(size=8)
    q0 = rng.normal(size=8) * 0.1

    def along(q, d):
        assert np.array_equal(q, q0)
        return H @ d

    T = tangents(lambda q: D, along, q0, dq0)
    assert T.shape == (4, 16)
    for k, j in enumerate((THETA, GAMMA)):
        want = np.zeros(8)
        want[j], want[BETA] = 1.0, -D[0, j] / D[0, BETA]
        assert np.array_equal(T[k, :8], want)
        assert abs(D[0] @ T[k, :8]) <= 1e-14 * np.max(np.abs(D[0]))
        assert T[k, 8 + THETA] == T[k, 8 + PSI] == T[k, 8 + GAMMA] == 0.0
        first_order = (H @ T[k, :8]) @ dq0 + D @ T[k, 8:]
        assert np.max(np.abs(first_order)) <= 1e-12 * np.max(np.abs((H @ T[k, :8]) @ dq0))
    for k, j in enumerate((THETA, GAMMA), start=2):
        assert np.all(T[k, :8] == 0.0)
        other = GAMMA if j == THETA else THETA
        assert T[k, 8 + j] == 1.0 and T[k, 8 + PSI] == 0.0 and T[k, 8 + other] == 0.0
        assert np.max(np.abs(D @ T[k, 8:])) <= 1e-12 * np.max(np.abs(D))


# -- the eigenvalues and the steady-motion check ----------------------------------------------

G, R_REAR, V = 8.0, 0.5, 4.0
#: the docstring's acceleration scale g + (v / R_rear)^2 R_rear: 8 + 64 * 0.5 = 40 m/s^2 exactly
SCALE = G + (V / R_REAR) ** 2 * R_REAR


def _oscillators(ddq_size: float) -> dict:
    """Two decoupled oscillators: dd_theta = -4 theta, dd_gamma = -gamma (f's Jacobian is J;
    D's independent columns are zero, so the tangents are the unit vectors and A is J's
    [theta, gamma, d_theta, d_gamma] block), a linear contact height D[0] . q (zero at q = 0)
    and the steady motion's accelerations ``ddq_size`` in one entry (a stand-in for drag)."""
    D = _d_matrix(5)
    D[:, [THETA, PSI, GAMMA]] = 0.0
    J = np.zeros((16, 16))
    J[np.arange(8), 8 + np.arange(8)] = 1.0          # d/dt q = dq
    J[8 + THETA, THETA], J[8 + GAMMA, GAMMA] = -4.0, -1.0
    ddq = np.zeros(8)
    ddq[EPS] = -ddq_size
    return dict(jvp=lambda q, dq, ds: J @ ds, derivatives=lambda q, dq: ddq,
                residual=lambda q, dq: D @ q, jacobian=lambda q: D,
                along=lambda q, d: np.zeros((5, 8)), R_rear=R_REAR, g=G)


@pytest.mark.parametrize("fraction", [0.0, 0.5, 1.0])
def test_accelerations_up_to_the_bound_are_a_steady_motion(fraction):
    """Accelerations of 0, 0.5 and exactly 1 times 1e-8 of the docstring's scale g + (v /
    R_rear)^2 R_rear = 40 m/s^2 (all exact binary numbers here) pass the check, and the
    eigenvalues are the oscillators' +-2i, +-1i (frequencies 2 and 1 rad/s: sqrt(4), sqrt(1)),
    sorted as sort_eigenvalues (larger |imag| first, +imag first), to 1e-12 (a 4x4
    eigenproblem's rounding, ~1e-15). Fails when the scale uses v^2 R_rear or v / v / R_rear
    (16 or 10 m/s^2: then half the bound is refused), when the bound divides by the scale, or
    when the bound is exclusive."""
    got = roll_steer_eigenvalues(speeds=V, **_oscillators(fraction * 1e-8 * SCALE))
    assert got.shape == (1, 4) and got.dtype == complex
    assert np.max(np.abs(got[0] - np.array([2j, -2j, 1j, -1j]))) <= 1e-12


def test_accelerations_over_the_bound_are_refused_naming_drag():
    """Twice the bound (8e-7 m/s^2 at 4 m/s): no steady motion; the line names the speed, the
    largest acceleration, drag as the likely cause and the fix. Fails when the line is lost."""
    with pytest.raises(LinearizationError) as err:
        roll_steer_eigenvalues(speeds=[V], **_oscillators(2e-8 * SCALE))
    assert str(err.value) == (
        "upright straight running at 4 m/s is not a steady motion of this engine (accelerations "
        "up to 8.00e-07 there; drag cv > 0?); fix: linearize a model without drag, "
        "model.params.replace(cv=0.0)")


@pytest.mark.parametrize("speeds, shown", [([[1.0, 2.0]], "[[1.0, 2.0]]"),
                                           ([4.0, float("nan")], "[4.0, nan]"),
                                           ([4.0, None], "[4.0, None]"),
                                           (float("inf"), "inf")])
def test_speeds_that_are_not_a_finite_1d_array_are_refused(speeds, shown):
    """The docstring's contract: a finite speed or a 1-D array of them. A 2-D array (finite), a
    NaN or infinite speed and a missing one (None, read as NaN) are each a plain ValueError
    quoting what was given (not LinearizationError, its subclass: nothing was linearized).
    Fails when either condition alone is enough to pass (or-to-and), when None reaches numpy
    as an object (then a TypeError from isfinite), or when the line is lost."""
    with pytest.raises(ValueError) as err:
        roll_steer_eigenvalues(speeds=speeds, **_oscillators(0.0))
    assert type(err.value) is ValueError
    assert str(err.value) == f"speeds must be a finite speed or a 1-D array of them (m/s); got {shown}"
