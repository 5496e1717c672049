"""Self-tests of the independent oracle (tests/oracle.py), without the reference model.

If the oracle were wrong, the physics tests would compare the model against a wrong answer;
these tests pin the oracle to first principles and to itself computed two ways.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import oracle as o
from strategies import coords, finite as _f, rates, states
from thesis_params import THESIS_PARAMS

P = o.params_from(THESIS_PARAMS)

# A generalised geometry (different radii, fork CoM off the steering axis), so that code paths
# the thesis numbers leave at zero (dx4, dz4, R_rear != R_front) are exercised too.
P_GEN = o.params_from({**THESIS_PARAMS, "R_front": 0.35, "dx4": 0.04, "dz4": 0.11,
                       "x5": 0.1, "z5": -0.43})
PARAMS = {"thesis": P, "generalised": P_GEN}


def scale(dq):
    """Typical size of a velocity-level quantity (length scale ~1 m)."""
    return max(1.0, float(np.max(np.abs(dq))))


# --------------------------------------------------------------------------------------------
@given(coords)
@settings(max_examples=40, deadline=None)
def test_rotations_orthonormal_right_handed(q):
    q = np.array(q)
    for name, A in o.rotations(q).items():
        # products of 5 rotations: rounding ~ 5 * few eps
        np.testing.assert_allclose(A.T @ A, np.eye(3), atol=1e-14, err_msg=name)
        assert abs(np.linalg.det(A) - 1.0) < 1e-14, name


def test_elementary_rotations_as_in_thesis():
    a = 0.7
    c, s = np.cos(a), np.sin(a)
    np.testing.assert_array_equal(o.Ry(a), [[c, 0, s], [0, 1, 0], [-s, 0, c]])
    np.testing.assert_array_equal(o.Rx(a), [[1, 0, 0], [0, c, -s], [0, s, c]])
    np.testing.assert_array_equal(o.Rz(a), [[c, -s, 0], [s, c, 0], [0, 0, 1]])
    # right-handed: Rz(90deg) takes x to y, Rx(90deg) takes y to z, Ry(90deg) takes z to x
    np.testing.assert_allclose(o.Rz(np.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-16)
    np.testing.assert_allclose(o.Rx(np.pi / 2) @ [0, 1, 0], [0, 0, 1], atol=1e-16)
    np.testing.assert_allclose(o.Ry(np.pi / 2) @ [0, 0, 1], [1, 0, 0], atol=1e-16)


def test_rotations_complex_orthogonal():
    # with complex angles A^T A = I still holds (plain transpose): needed by the complex step
    q = np.array([0, 0, 0.3 + 1e-3j, -0.4 + 2e-3j, 1.0, 0.1 - 1e-3j, 0.5 + 1e-3j, 2.0 + 1j * 1e-3])
    for name, A in o.rotations(q).items():
        np.testing.assert_allclose(A.T @ A, np.eye(3), atol=1e-14, err_msg=name)


def test_upright_geometry():
    """All angles zero: hubs at the height of their radius; frame points where typed."""
    q = np.zeros(8)
    r = o.positions(P, q)
    np.testing.assert_allclose(r["rG2"], [0, 0, P.R_rear], atol=1e-16)
    np.testing.assert_allclose(r["rG3"], [P.x3, 0, P.R_rear + P.z3], atol=1e-15)
    np.testing.assert_allclose(r["rG5"], [P.xa + P.x5, 0, P.R_rear + P.za + P.z5], atol=1e-15)
    # the thesis geometry puts the front hub at the front radius: rD on the ground at q = 0
    assert abs(r["rD"][2]) < 1e-15
    for contact in o.CONTACTS:
        np.testing.assert_allclose(o.positions(P, q, contact)["rD"],
                                   [P.xa + P.x5, 0, 0], atol=1e-15)


# --------------------------------------------------------------------------------------------
@given(states)
@settings(max_examples=30, deadline=None)
def test_complex_step_velocity_equals_central_difference(state):
    q, dq = state
    h = 1e-6
    for contact in o.CONTACTS:
        cs = o.complex_step(lambda x: o.positions(P, x, contact), q, dq)
        fp = o.positions(P, q + h * dq, contact)
        fm = o.positions(P, q - h * dq, contact)
        for key in cs:
            fd = (fp[key] - fm[key]) / (2 * h)
            # central difference: truncation ~h^2 |dq|^3 ~ 1e-12*8e3, rounding ~eps*10/h ~ 2e-9
            # (positions up to ~10 m): 1e-6 relative to |dq| is far above both.
            np.testing.assert_allclose(cs[key], fd, atol=1e-6 * scale(dq), err_msg=key)


@pytest.mark.parametrize("pname", sorted(PARAMS))
@given(states)
@settings(max_examples=30, deadline=None)
def test_tangent_equals_complex_step(pname, state):
    """The hand-written product rule (used for nested derivatives) equals the complex step."""
    p = PARAMS[pname]
    q, dq = state
    for contact in o.CONTACTS:
        a = o.kinematics(p, q, dq, contact, method="complex-step")
        b = o.kinematics(p, q, dq, contact, method="tangent")
        # both exact; rounding ~ few eps * |dq| * (geometry ~1 m)
        tol = 1e-13 * scale(dq)
        for key in a.v:
            np.testing.assert_allclose(a.v[key], b.v[key], atol=tol, err_msg=key)
        for i in o.BODIES:
            np.testing.assert_allclose(a.wL[i], b.wL[i], atol=tol)
            np.testing.assert_allclose(a.w[i], b.w[i], atol=tol)


@given(states)
@settings(max_examples=30, deadline=None)
def test_angular_velocity_elementary(state):
    """Local angular velocities written out by hand for the first bodies of the chain:
    w_i2 (global) = phi_dot Z + theta_dot x_i2, w2L = Ry(psi)^T [theta_dot, 0, 0]
    + Ai2-local phi part + [0, psi_dot, 0]."""
    q, dq = state
    wL, w = o.angular_velocities(q, dq)
    A = o.rotations(q)
    w_i2 = dq[2] * np.array([0, 0, 1.0]) + dq[3] * A["Ai2"][:, 0]
    tol = 1e-13 * scale(dq)  # rounding of a handful of products
    np.testing.assert_allclose(w[2], w_i2 + dq[4] * A["Ai2"][:, 1], atol=tol)
    np.testing.assert_allclose(w[3], w_i2 + dq[5] * A["Ai2"][:, 1], atol=tol)
    np.testing.assert_allclose(w[4], w[3] + dq[6] * A["A3"][:, 2], atol=tol)
    np.testing.assert_allclose(w[5], w[4] + dq[7] * A["A4"][:, 1], atol=tol)
    for i, n in o.BODY_ROTATION.items():
        np.testing.assert_allclose(A[n] @ wL[i], w[i], atol=tol)


# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("pname", sorted(PARAMS))
@given(coords)
@settings(max_examples=40, deadline=None)
def test_disc_contact_two_ways(pname, q):
    p = PARAMS[pname]
    q = np.array(q)
    closed = o.positions(p, q, "disc")["rD"]
    numeric, _ = o.front_contact_by_minimisation(p, q)
    # both are exact up to rounding of ~10 m coordinates (xc, yc): 1e-10 leaves margin for
    # the root polish (xtol 1e-15 in t)
    np.testing.assert_allclose(closed, numeric, rtol=0, atol=1e-10)
    # and it is never higher than the thesis point (it is the minimum of the rim)
    assert closed[2] <= o.positions(p, q, "thesis")["rD"][2] + 1e-15


def test_rear_contact_is_lowest_point_of_rear_disc():
    rng = np.random.default_rng(1)
    for _ in range(20):
        q = rng.uniform(-1.2, 1.2, 8)
        A = o.rotations(q)
        r = o.positions(P, q)
        a = A["Ai2"][:, 1]
        n = o.K_Z - a[2] * a
        lowest = r["rG2"] - P.R_rear * n / np.linalg.norm(n)
        np.testing.assert_allclose(r["rC"], lowest, atol=1e-14)


@given(_f(-1.2, 1.2), _f(-1.5, 1.5), _f(-np.pi, np.pi), _f(-np.pi, np.pi))
@settings(max_examples=40, deadline=None)
def test_contact_models_agree_when_fork_x_axis_horizontal(theta, gamma, phi, eps):
    s = np.tan(theta) * np.tan(gamma)
    if abs(s) > 0.9:
        theta, gamma, s = theta, 0.0, 0.0
    beta = np.arcsin(s)  # makes A4[2,0] = sin(th) sin(ga) - cos(th) sin(be) cos(ga) = 0
    q = np.array([1.0, -2.0, phi, theta, 0.3, beta, gamma, eps])
    assert abs(o.rotations(q)["A4"][2, 0]) < 1e-14
    for p in PARAMS.values():
        np.testing.assert_allclose(o.positions(p, q, "thesis")["rD"],
                                   o.positions(p, q, "disc")["rD"], atol=1e-14)
        np.testing.assert_allclose(o.constraint_jacobian(p, q, "thesis"),
                                   o.constraint_jacobian(p, q, "disc"), atol=1e-13)


# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("contact", o.CONTACTS)
@pytest.mark.parametrize("w", [5.0, -3.0, 17.0])
def test_straight_upright_rolling_satisfies_constraints(contact, w):
    R = P.R_rear
    assert P.R_front == R
    q = np.array([0.4, -1.3, 0.0, 0.0, 0.8, 0.0, 0.0, -2.1])
    dq = np.array([R * w, 0, 0, 0, w, 0, 0, w])
    # rounding of O(w R) velocities
    np.testing.assert_allclose(o.constraint_residual(P, q, dq, contact), 0, atol=1e-14 * abs(w))
    np.testing.assert_allclose(o.constraint_jacobian(P, q, contact) @ dq, 0, atol=1e-14 * abs(w))
    # heading phi rotates the motion: along (cos phi, sin phi)
    phi = 0.9
    q[2] = phi
    dq2 = np.array([R * w * np.cos(phi), R * w * np.sin(phi), 0, 0, w, 0, 0, w])
    np.testing.assert_allclose(o.constraint_residual(P, q, dq2, contact), 0, atol=1e-14 * abs(w))


def test_straight_rolling_pedal_balances_drag():
    """Thesis scenario 1: Mped = cv (R psi_dot)^2 R holds the speed: ddq = 0."""
    w = 5.0
    R = P.R_rear
    q = np.zeros(8)
    dq = np.array([R * w, 0, 0, 0, w, 0, 0, w])
    np.testing.assert_allclose(o.lagrange_Qv(P, q, dq), 0, atol=1e-12)  # no gyroscopic terms
    for contact in o.CONTACTS:
        ddq, _ = o.forward_acceleration(P, q, dq, (0.0, P.cv * (R * w) ** 2 * R, 0.0), contact)
        np.testing.assert_allclose(ddq, 0, atol=1e-12)  # rounding of a 13x13 solve, |Q| ~ 1


# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("pname", sorted(PARAMS))
@given(states)
@settings(max_examples=15, deadline=None)  # 36 energies a state: as ORACLE_STATES in test_physics
def test_mass_matrix_polarisation(pname, state):
    p = PARAMS[pname]
    q, dq = state
    M = o.mass_matrix(p, q)
    np.testing.assert_array_equal(M, M.T)  # symmetric by construction
    assert np.linalg.eigvalsh(M).min() > 0
    T = o.kinetic_energy(p, q, dq)
    # quadratic form: T = 1/2 dq M dq up to rounding ~eps * 8^2 * max|M| |dq|^2
    assert abs(T - 0.5 * dq @ M @ dq) <= 1e-13 * np.abs(M).max() * scale(dq) ** 2
    # the tangent method gives the same M
    np.testing.assert_allclose(o.mass_matrix(p, q, "tangent"), M, rtol=0,
                               atol=1e-13 * np.abs(M).max())


@pytest.mark.parametrize("pname", sorted(PARAMS))
@given(states)
@settings(max_examples=20, deadline=None)
def test_lagrange_Qv_against_finite_differences(pname, state):
    """-(dM/dt) dq + dT/dq with central differences instead of complex steps."""
    p = PARAMS[pname]
    q, dq = state
    h = 1e-5
    n = max(np.linalg.norm(dq), 1.0)  # unit-ish direction (dq may be 0)
    u = dq / n
    dM = (o.mass_matrix(p, q + h * u) - o.mass_matrix(p, q - h * u)) / (2 * h) * n
    dT = np.array([(o.kinetic_energy(p, q + h * o._unit(j), dq)
                    - o.kinetic_energy(p, q - h * o._unit(j), dq)) / (2 * h) for j in range(8)])
    fd = -dM @ dq + dT
    ref = o.lagrange_Qv(p, q, dq)
    # central differences: truncation h^2 ~ 1e-10, rounding eps*|T|/h ~ 2e-11 relative to the
    # natural scale max|M| |dq|^2 of Qv; 1e-7 covers both with a wide margin
    np.testing.assert_allclose(ref, fd, rtol=0, atol=1e-7 * np.abs(o.mass_matrix(p, q)).max()
                               * scale(dq) ** 2)
    # power identity of Lagrangian mechanics: dq.Qv = -1/2 dq.(dM/dt).dq
    Mdot = o.mass_matrix_rate(p, q, dq)
    assert abs(dq @ ref + 0.5 * dq @ Mdot @ dq) <= 1e-12 * np.abs(Mdot).max() * scale(dq) ** 2 + 1e-9


@pytest.mark.parametrize("contact", o.CONTACTS)
@given(states)
@settings(max_examples=20, deadline=None)
def test_constraint_bias_against_finite_differences(contact, state):
    q, dq = state
    exact = o.constraint_bias(P_GEN, q, dq, contact)
    fd = o.constraint_bias_fd(P_GEN, q, dq, contact)
    # constraint_bias_fd's stated accuracy: ~1e-10 relative to |dq|^2
    np.testing.assert_allclose(exact, fd, rtol=0, atol=1e-9 * scale(dq) ** 2)


@pytest.mark.parametrize("contact", o.CONTACTS)
@given(states)
@settings(max_examples=20, deadline=None)
def test_constraint_rows_are_linear_in_dq(contact, state):
    q, dq = state
    D = o.constraint_jacobian(P, q, contact)
    C = o.constraint_residual(P, q, dq, contact)
    # velocity rows: C[1:] = D[1:] dq exactly up to rounding
    np.testing.assert_allclose(C[1:], D[1:] @ dq, rtol=0, atol=1e-13 * scale(dq))
    # position row: its gradient times dq is d rD_z / dt
    drD = o.position_rates(P, q, dq, contact)["rD"][2]
    assert abs(D[0] @ dq - drD) <= 1e-13 * scale(dq)


def test_gravity_and_drag_first_principles():
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = rng.uniform(-1, 1, 8)
        dq = rng.uniform(-10, 10, 8)
        # gravity: sum of H_i^T [0, 0, -m_i g]
        Qg = sum(o.com_jacobian(P, q, i).T @ np.array([0, 0, -m * P.g])
                 for i, m in o.masses(P).items())
        np.testing.assert_allclose(o.generalized_gravity(P, q), Qg, atol=1e-12)
        # drag dissipates: dq.Qaero = -cv |vG3|^3
        v3 = o.point_velocities(P, q, dq)[3]
        assert np.isclose(dq @ o.drag_force(P, q, dq), -P.cv * np.linalg.norm(v3) ** 3,
                          rtol=1e-12)


def test_rider_torque_power():
    rng = np.random.default_rng(4)
    for _ in range(10):
        q = rng.uniform(-1, 1, 8)
        dq = rng.uniform(-10, 10, 8)
        T = rng.uniform(-5, 5, 3)
        wL, _ = o.angular_velocities(q, dq)
        power = T[0] * wL[4][2] + T[1] * wL[2][1] + T[2] * wL[3][0]
        assert np.isclose(dq @ (o.rider_torque_matrix(q) @ T), power, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("contact", o.CONTACTS)
def test_consistent_state_and_forward_acceleration(contact):
    rng = np.random.default_rng(5)
    for _ in range(5):
        q0 = rng.uniform(-0.6, 0.6, 8)
        q, dq = o.consistent_state(P, q0, rng.uniform(-5, 5, 8), contact)
        np.testing.assert_allclose(o.constraint_residual(P, q, dq, contact), 0, atol=1e-13)
        T = rng.uniform(-2, 2, 3)
        ddq, lam = o.forward_acceleration(P, q, dq, T, contact)
        D = o.constraint_jacobian(P, q, contact)
        b = o.constraint_bias(P, q, dq, contact)
        np.testing.assert_allclose(D @ ddq, -b, atol=1e-10)
        M = o.mass_matrix(P, q)
        Q = o.generalized_forces(P, q, dq, T)
        np.testing.assert_allclose(M @ ddq + D.T @ lam, Q, atol=1e-9 * max(1, np.abs(Q).max()))
