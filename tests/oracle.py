"""An independent numerical oracle of the thesis bicycle: kinematics, energy, constraints.

Plain numpy, written from the model's description (docs/model.md, after the thesis's MATLAB
listing, chapter 8) and its parameter names, WITHOUT looking at the reference model's code.
The reference model derives everything symbolically (sympy) and the Newton-Euler way; this
oracle instead

* evaluates positions and rotation matrices numerically, straight from the definitions;
* differentiates them numerically with the complex step, f'(x) dx = Im f(x + i h dx) / h with
  h = 1e-30, which has no subtractive cancellation and is exact to machine precision for the
  analytic functions used here (trig functions, products, one square root);
* gets the mass matrix from the kinetic energy by polarisation, the velocity-dependent forces
  from Lagrange's equations, gravity from the potential energy: a second, energy-based
  formulation rather than the thesis's Newton-Euler projection.

Coordinates: q = [xc, yc, phi, theta, psi, beta, gamma, eps] (thesis order).

Two ways to get time derivatives
--------------------------------
``method="complex-step"`` (the default for real q): d/dt f(q) along dq = Im f(q + i h dq) / h.
It needs a REAL base point q.

``method="tangent"``: the same derivatives by the product rule, written out by hand
(dR(a)/dt = R(a) K a_dot for an elementary rotation with axis matrix K). It works for complex q
too, so a second derivative can be taken by one more complex step on top of it: that is how
``constraint_bias``, ``lagrange_Qv`` and ``mass_matrix_rate`` stay exact to machine precision
instead of resorting to finite differences. ``tests/test_oracle.py`` checks that the two
methods agree to ~1e-15 on real states. With ``method=None`` the tangent method is chosen
exactly when q or dq is complex.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import SimpleNamespace

import numpy as np

PARAMETER_NAMES = (
    "R_rear", "R_front",
    "x3", "z3",
    "xa", "za",
    "dx4", "dz4",
    "x5", "z5",
    "m2", "m3", "m4", "m5",
    "I2xx", "I2yy", "I2zz",
    "I3xx", "I3yy", "I3zz", "I3xz",
    "I4xx", "I4yy", "I4zz", "I4xz",
    "I5xx", "I5yy", "I5zz",
    "g",
    "cv",
)
COORDINATES = ("xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps")
NQ = 8
BODIES = (2, 3, 4, 5)
CONTACTS = ("thesis", "disc")
CS_STEP = 1e-30  # complex step; any h << sqrt(eps) gives machine-precision derivatives
K_Z = np.array([0.0, 0.0, 1.0])


# --------------------------------------------------------------------------------------------
# parameters
# --------------------------------------------------------------------------------------------
def params_from(obj) -> SimpleNamespace:
    """Parameters with attribute access, from a mapping or any object with the attributes.

    Accepts the reference model's ``Parameters`` dataclass, a dict, or a namespace. Only the
    names of docs/model.md are read; each is converted to a float.
    """
    values = {}
    for name in PARAMETER_NAMES:
        if isinstance(obj, Mapping):
            if name not in obj:
                raise KeyError(f"parameter {name!r} missing")
            values[name] = float(obj[name])
        else:
            if not hasattr(obj, name):
                raise AttributeError(f"parameter {name!r} missing on {type(obj).__name__}")
            values[name] = float(getattr(obj, name))
    return SimpleNamespace(**values)


def inertia_matrices(p) -> dict[int, np.ndarray]:
    """Body inertia tensors about the CoM, body axes. I3, I4 carry the xz product entry."""
    return {
        2: np.diag([p.I2xx, p.I2yy, p.I2zz]),
        3: np.array([[p.I3xx, 0.0, p.I3xz], [0.0, p.I3yy, 0.0], [p.I3xz, 0.0, p.I3zz]]),
        4: np.array([[p.I4xx, 0.0, p.I4xz], [0.0, p.I4yy, 0.0], [p.I4xz, 0.0, p.I4zz]]),
        5: np.diag([p.I5xx, p.I5yy, p.I5zz]),
    }


def masses(p) -> dict[int, float]:
    return {2: p.m2, 3: p.m3, 4: p.m4, 5: p.m5}


# --------------------------------------------------------------------------------------------
# small helpers
# --------------------------------------------------------------------------------------------
def _dtype(*xs):
    return np.result_type(float, *[np.asarray(x).dtype for x in xs])


def _is_complex(*xs) -> bool:
    return any(np.iscomplexobj(x) for x in xs)


def _as_vec(q, n=NQ):
    q = np.asarray(q)
    if q.shape != (n,):
        raise ValueError(f"expected shape ({n},), got {q.shape}")
    return q


def _real(x, what):
    x = np.asarray(x)
    if np.iscomplexobj(x):
        raise TypeError(f"complex step needs a real {what}; use method='tangent'")
    return x.astype(float)


def _unit(j, n=NQ):
    e = np.zeros(n)
    e[j] = 1.0
    return e


def vee(W):
    """[W32, W13, W21] (1-based), the vector of a skew-symmetric matrix."""
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


def _cs_map(out, h=CS_STEP):
    """Im(.)/h applied to an array or to every value of a (nested) dict."""
    if isinstance(out, dict):
        return {k: _cs_map(v, h) for k, v in out.items()}
    return np.imag(out) / h


def complex_step(f, x, dx, h=CS_STEP):
    """Directional derivative d/ds f(x + s dx) at s = 0, by the complex step (x, dx real)."""
    x = _real(x, "base point")
    dx = _real(dx, "direction")
    return _cs_map(f(x + 1j * h * dx), h)


def complex_step_jacobian(f, x, h=CS_STEP):
    """Columns d f / d x_j by the complex step; f returns an array."""
    x = _real(x, "base point")
    cols = [np.imag(f(x + 1j * h * _unit(j, x.size))) / h for j in range(x.size)]
    return np.stack(cols, axis=-1)


# --------------------------------------------------------------------------------------------
# rotations
# --------------------------------------------------------------------------------------------
def Rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=_dtype(a))


def Ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], dtype=_dtype(a))


def Rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=_dtype(a))


# skew matrices of the axes: d/da R_axis(a) = R_axis(a) @ K_axis
K_X = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
K_Y = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
K_ZM = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])

# (coordinate index, elementary rotation, its axis matrix)
_ELEMENTARY = {
    "phi": (2, Rz, K_ZM),
    "theta": (3, Rx, K_X),
    "psi": (4, Ry, K_Y),
    "beta": (5, Ry, K_Y),
    "gamma": (6, Rz, K_ZM),
    "eps": (7, Ry, K_Y),
}


def rotations(q) -> dict[str, np.ndarray]:
    """Ai2 = Rz(phi) Rx(theta); A2 = Ai2 Ry(psi); A3 = Ai2 Ry(beta); A4 = A3 Rz(gamma);
    A5 = A4 Ry(eps). Columns are the body axes in global coordinates."""
    q = _as_vec(q)
    R = {name: rot(q[j]) for name, (j, rot, _) in _ELEMENTARY.items()}
    Ai2 = R["phi"] @ R["theta"]
    A3 = Ai2 @ R["beta"]
    A4 = A3 @ R["gamma"]
    return {"Ai2": Ai2, "A2": Ai2 @ R["psi"], "A3": A3, "A4": A4, "A5": A4 @ R["eps"]}


def rotation_rates(q, dq) -> dict[str, np.ndarray]:
    """dA/dt of every matrix of ``rotations`` along dq, by the product rule (tangent method).

    Works for complex q and dq."""
    q, dq = _as_vec(q), _as_vec(dq)
    R, dR = {}, {}
    for name, (j, rot, K) in _ELEMENTARY.items():
        R[name] = rot(q[j])
        dR[name] = R[name] @ K * dq[j]
    Ai2 = R["phi"] @ R["theta"]
    dAi2 = dR["phi"] @ R["theta"] + R["phi"] @ dR["theta"]
    dA2 = dAi2 @ R["psi"] + Ai2 @ dR["psi"]
    A3 = Ai2 @ R["beta"]
    dA3 = dAi2 @ R["beta"] + Ai2 @ dR["beta"]
    A4 = A3 @ R["gamma"]
    dA4 = dA3 @ R["gamma"] + A3 @ dR["gamma"]
    dA5 = dA4 @ R["eps"] + A4 @ dR["eps"]
    return {"Ai2": dAi2, "A2": dA2, "A3": dA3, "A4": dA4, "A5": dA5}


BODY_ROTATION = {2: "A2", 3: "A3", 4: "A4", 5: "A5"}


# --------------------------------------------------------------------------------------------
# positions
# --------------------------------------------------------------------------------------------
def _check_contact(contact):
    if contact not in CONTACTS:
        raise ValueError(f"contact must be one of {CONTACTS}, got {contact!r}")


def front_contact(p, rG5, A4, contact="thesis"):
    """Front contact point.

    thesis: rD = rG5 - R_front * (z axis of the fork), the rim point "below" the hub along z4.
    disc:   the lowest point of the front disc (plane normal a = y axis of the fork):
            rD = rG5 - R_front (k - (k.a) a) / sqrt(1 - (k.a)^2), k = global Z.
    """
    _check_contact(contact)
    if contact == "thesis":
        return rG5 - p.R_front * A4[:, 2]
    a = A4[:, 1]
    ka = a[2]
    n = K_Z - ka * a
    return rG5 - p.R_front * n / np.sqrt(1.0 - ka * ka)


def front_contact_rate(p, drG5, A4, dA4, contact="thesis"):
    """d rD/dt of the geometric contact point (tangent method; complex-safe)."""
    _check_contact(contact)
    if contact == "thesis":
        return drG5 - p.R_front * dA4[:, 2]
    a, da = A4[:, 1], dA4[:, 1]
    ka, dka = a[2], da[2]
    n = K_Z - ka * a
    dn = -dka * a - ka * da
    norm = np.sqrt(1.0 - ka * ka)
    dnorm = -ka * dka / norm
    return drG5 - p.R_front * (dn / norm - n * dnorm / norm**2)


def front_contact_by_minimisation(p, q, n_samples=20001):
    """The lowest point of the front disc found numerically (a second, independent way).

    The rim is rG5 + R_front (cos t e1 + sin t e3), e1, e3 = x and z axes of the front wheel
    (A5). Its height is sampled on a fine grid over [-pi, pi), the best sample bracketed and
    refined with scipy's bounded minimiser, then polished by a root of dz/dt in a small
    bracket: a minimiser alone only locates t to ~sqrt(machine eps) ~ 1e-8 because z is flat
    at its minimum, while the point itself is wanted to ~1e-12.
    """
    from scipy.optimize import brentq, minimize_scalar

    q = _real(q, "state")
    A = rotations(q)
    rG5 = positions(p, q)["rG5"]
    e1, e3 = A["A5"][:, 0], A["A5"][:, 2]
    R = p.R_front

    def z(t):
        return rG5[2] + R * (np.cos(t) * e1[2] + np.sin(t) * e3[2])

    def dz(t):
        return R * (-np.sin(t) * e1[2] + np.cos(t) * e3[2])

    ts = np.linspace(-np.pi, np.pi, n_samples)
    k = int(np.argmin(z(ts)))
    dt = ts[1] - ts[0]
    res = minimize_scalar(z, bounds=(ts[k] - dt, ts[k] + dt), method="bounded",
                          options={"xatol": 1e-12})
    t = res.x
    w = 1e-6
    if dz(t - w) < 0.0 < dz(t + w):
        t = brentq(dz, t - w, t + w, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    return rG5 + R * (np.cos(t) * e1 + np.sin(t) * e3), t


def _frame_points(p, q, A):
    xc, yc = q[0], q[1]
    dt = _dtype(q)
    rC = np.array([xc, yc, 0.0], dtype=dt)
    rG2 = rC + A["Ai2"] @ np.array([0.0, 0.0, p.R_rear])
    rA = rG2 + A["A3"] @ np.array([p.xa, 0.0, p.za])
    rG3 = rG2 + A["A3"] @ np.array([p.x3, 0.0, p.z3])
    rG4 = rA + A["A4"] @ np.array([p.dx4, 0.0, p.dz4])
    rG5 = rA + A["A4"] @ np.array([p.x5, 0.0, p.z5])
    return {"rC": rC, "rG2": rG2, "rA": rA, "rG3": rG3, "rG4": rG4, "rG5": rG5}


def positions(p, q, contact="thesis") -> dict[str, np.ndarray]:
    """rC, rG2 (rear hub), rA (steering-axis point), rG3, rG4, rG5 (front hub), rD (front
    contact of the chosen model). Complex-safe."""
    q = _as_vec(q)
    A = rotations(q)
    r = _frame_points(p, q, A)
    r["rD"] = front_contact(p, r["rG5"], A["A4"], contact)
    return r


def position_rates(p, q, dq, contact="thesis") -> dict[str, np.ndarray]:
    """Time derivatives of ``positions`` along dq by the product rule (complex-safe).

    For rD this is the rate of the GEOMETRIC contact point, not a material velocity."""
    q, dq = _as_vec(q), _as_vec(dq)
    A = rotations(q)
    dA = rotation_rates(q, dq)
    dt = _dtype(q, dq)
    v = {}
    v["rC"] = np.array([dq[0], dq[1], 0.0], dtype=dt)
    v["rG2"] = v["rC"] + dA["Ai2"] @ np.array([0.0, 0.0, p.R_rear])
    v["rA"] = v["rG2"] + dA["A3"] @ np.array([p.xa, 0.0, p.za])
    v["rG3"] = v["rG2"] + dA["A3"] @ np.array([p.x3, 0.0, p.z3])
    v["rG4"] = v["rA"] + dA["A4"] @ np.array([p.dx4, 0.0, p.dz4])
    v["rG5"] = v["rA"] + dA["A4"] @ np.array([p.x5, 0.0, p.z5])
    v["rD"] = front_contact_rate(p, v["rG5"], A["A4"], dA["A4"], contact)
    return v


# --------------------------------------------------------------------------------------------
# velocities
# --------------------------------------------------------------------------------------------
def _choose(method, *xs):
    if method is None:
        return "tangent" if _is_complex(*xs) else "complex-step"
    if method not in ("tangent", "complex-step"):
        raise ValueError(f"unknown method {method!r}")
    return method


def kinematics(p, q, dq, contact="thesis", method=None) -> SimpleNamespace:
    """Everything at once: positions r, rotations A, point rates v (same keys as r), and the
    angular velocities of bodies 2..5: body-local wL[i] = vee(A_i^T dA_i/dt), global
    w[i] = A_i wL[i]."""
    method = _choose(method, q, dq)
    q, dq = _as_vec(q), _as_vec(dq)
    r = positions(p, q, contact)
    A = rotations(q)
    if method == "complex-step":
        v = complex_step(lambda x: positions(p, x, contact), q, dq)
        dA = complex_step(rotations, q, dq)
    else:
        v = position_rates(p, q, dq, contact)
        dA = rotation_rates(q, dq)
    wL, w = {}, {}
    for i, name in BODY_ROTATION.items():
        wL[i] = vee(A[name].T @ dA[name])
        w[i] = A[name] @ wL[i]
    return SimpleNamespace(r=r, A=A, v=v, dA=dA, wL=wL, w=w)


def point_velocities(p, q, dq, method=None) -> dict[int, np.ndarray]:
    """Velocities of the centres of mass G2..G5."""
    k = kinematics(p, q, dq, method=method)
    return {i: k.v[f"rG{i}"] for i in BODIES}


def angular_velocities(q, dq, method=None):
    """(wL, w): body-local and global angular velocities of bodies 2..5 (dicts by body)."""
    method = _choose(method, q, dq)
    q, dq = _as_vec(q), _as_vec(dq)
    A = rotations(q)
    dA = complex_step(rotations, q, dq) if method == "complex-step" else rotation_rates(q, dq)
    wL = {i: vee(A[n].T @ dA[n]) for i, n in BODY_ROTATION.items()}
    w = {i: A[BODY_ROTATION[i]] @ wL[i] for i in BODIES}
    return wL, w


# --------------------------------------------------------------------------------------------
# energy and mass matrix
# --------------------------------------------------------------------------------------------
def kinetic_energy(p, q, dq, method=None):
    """T = sum_i 1/2 m_i vGi.vGi + 1/2 wiL.(I_i wiL), bodies 2..5 (complex-safe with
    the tangent method; uses plain transposes, no conjugates)."""
    k = kinematics(p, q, dq, method=method)
    I = inertia_matrices(p)
    m = masses(p)
    T = 0.0
    for i in BODIES:
        vG = k.v[f"rG{i}"]
        T = T + 0.5 * m[i] * (vG @ vG) + 0.5 * (k.wL[i] @ (I[i] @ k.wL[i]))
    return T


def potential_energy(p, q):
    """V = sum_i m_i g z_Gi (complex-safe)."""
    r = positions(p, q)
    m = masses(p)
    return sum(m[i] * p.g * r[f"rG{i}"][2] for i in BODIES)


def mass_matrix(p, q, method=None):
    """M by polarisation of the quadratic form T(q, .): M_ii = 2 T(e_i),
    M_ij = T(e_i + e_j) - T(e_i) - T(e_j). Exact for a quadratic form up to rounding
    (~ a few eps * max|M|)."""
    q = _as_vec(q)
    dt = _dtype(q)
    M = np.zeros((NQ, NQ), dtype=dt)
    Ti = [kinetic_energy(p, q, _unit(i), method) for i in range(NQ)]
    for i in range(NQ):
        M[i, i] = 2.0 * Ti[i]
        for j in range(i + 1, NQ):
            M[i, j] = M[j, i] = kinetic_energy(p, q, _unit(i) + _unit(j), method) - Ti[i] - Ti[j]
    return M


def mass_matrix_rate(p, q, dq):
    """dM/dt = d/ds M(q + s dq) at s = 0: complex step on top of the tangent method (exact)."""
    q = _real(q, "state")
    dq = _real(dq, "rate")
    return np.imag(mass_matrix(p, q + 1j * CS_STEP * dq, method="tangent")) / CS_STEP


def kinetic_energy_gradient(p, q, dq):
    """dT/dq at fixed dq (partial derivative), complex step on top of the tangent method."""
    q = _real(q, "state")
    dq = _real(dq, "rate")
    return np.array([np.imag(kinetic_energy(p, q + 1j * CS_STEP * _unit(j), dq, "tangent"))
                     / CS_STEP for j in range(NQ)])


def lagrange_Qv(p, q, dq):
    """The velocity-dependent generalised inertia forces from Lagrange's equations:
    d/dt(M dq) - dT/dq = Q  =>  M ddq = Q + Qv with Qv = -(dM/dt) dq + dT/dq.
    Exact to machine precision (two complex steps on analytic functions)."""
    return -mass_matrix_rate(p, q, dq) @ np.asarray(dq, float) + kinetic_energy_gradient(p, q, dq)


# --------------------------------------------------------------------------------------------
# applied forces
# --------------------------------------------------------------------------------------------
def generalized_gravity(p, q):
    """Qgrav = -dV/dq (complex step)."""
    q = _real(q, "state")
    return -complex_step_jacobian(lambda x: np.atleast_1d(potential_energy(p, x)), q)[0]


def com_jacobian(p, q, body):
    """H_i = d rGi / dq (3x8), complex step."""
    return complex_step_jacobian(lambda x: positions(p, x)[f"rG{body}"], q)


def drag_force(p, q, dq):
    """Qaero = -cv |vG3| H3^T vG3 (drag on body 3 only)."""
    H3 = com_jacobian(p, q, 3)
    vG3 = H3 @ np.asarray(dq, float)
    return -p.cv * np.sqrt(vG3 @ vG3) * (H3.T @ vG3)


def rider_torque_matrix(q):
    """S (8x3) with dq.(S T) = Mdir [w4L]_z + Mped [w2L]_y + Mvue [w3L]_x: column j of S^T is
    the angular-velocity component at dq = e_j (they are linear in dq)."""
    q = _real(q, "state")
    S = np.zeros((NQ, 3))
    for j in range(NQ):
        wL, _ = angular_velocities(q, _unit(j))
        S[j] = [wL[4][2], wL[2][1], wL[3][0]]
    return S


# --------------------------------------------------------------------------------------------
# constraints
# --------------------------------------------------------------------------------------------
def contact_velocities(p, q, dq, contact="thesis", method=None):
    """Material-point velocities at the contacts: vC = vG2 + w2 x (rC - rG2) (rear wheel),
    vD = vG5 + w5 x (rD - rG5) (front wheel); w2, w5 global."""
    k = kinematics(p, q, dq, contact, method)
    vC = k.v["rG2"] + np.cross(k.w[2], k.r["rC"] - k.r["rG2"])
    vD = k.v["rG5"] + np.cross(k.w[5], k.r["rD"] - k.r["rG5"])
    return vC, vD


def constraint_residual(p, q, dq, contact="thesis"):
    """C = [rD_z, vC_x, vC_y, vD_x, vD_y]."""
    rD = positions(p, q, contact)["rD"]
    vC, vD = contact_velocities(p, q, dq, contact)
    return np.array([rD[2], vC[0], vC[1], vD[0], vD[1]])


def constraint_jacobian(p, q, contact="thesis"):
    """D (5x8): row 0 = d rD_z / dq (complex step per coordinate); rows 1..4 =
    d(vC_x, vC_y, vD_x, vD_y)/d dq, i.e. column j = contact velocities at dq = e_j."""
    q = _real(q, "state")
    D = np.zeros((5, NQ))
    D[0] = complex_step_jacobian(lambda x: positions(p, x, contact)["rD"][2:3], q)[0]
    for j in range(NQ):
        vC, vD = contact_velocities(p, q, _unit(j), contact, method="complex-step")
        D[1:, j] = [vC[0], vC[1], vD[0], vD[1]]
    return D


def _D_dq(p, q, dq, contact):
    """D(q) dq evaluated without numerical differentiation in q, so q may be complex:
    [d rD_z/dt, vC_x, vC_y, vD_x, vD_y] by the tangent method."""
    drD = position_rates(p, q, dq, contact)["rD"]
    vC, vD = contact_velocities(p, q, dq, contact, method="tangent")
    return np.array([drD[2], vC[0], vC[1], vD[0], vD[1]])


def constraint_bias(p, q, dq, contact="thesis"):
    """dD dq = d/ds [D(q + s dq) dq] at s = 0 (so that D ddq + dD dq = 0).

    Accuracy: machine precision (relative ~1e-15 of |dq|^2 times the geometry scale). D(q) dq
    is evaluated by the hand-written product rule (tangent method), which accepts complex q,
    and the outer derivative is one complex step with h = 1e-30 -- no finite difference
    anywhere. ``constraint_bias_fd`` is a 4th-order central-difference cross-check of it.
    """
    q = _real(q, "state")
    dq = _real(dq, "rate")
    return np.imag(_D_dq(p, q + 1j * CS_STEP * dq, dq, contact)) / CS_STEP


def constraint_bias_fd(p, q, dq, contact="thesis", h=1e-3):
    """Cross-check of ``constraint_bias``: 4th-order central difference in s of
    D(q + s u) dq |dq| with u = dq/|dq| and D from ``constraint_jacobian`` (complex step).
    Accuracy ~1e-10 relative to |dq|^2 (truncation h^4/30 |f^(5)| ~ 3e-14, rounding
    ~ eps/h ~ 2e-13, times the derivative scale of the geometry)."""
    q = _real(q, "state")
    dq = _real(dq, "rate")
    n = np.linalg.norm(dq)
    if n == 0.0:
        return np.zeros(5)
    u = dq / n

    def f(s):
        return constraint_jacobian(p, q + s * u, contact) @ dq

    d = (f(-2 * h) - 8 * f(-h) + 8 * f(h) - f(2 * h)) / (12 * h)
    return n * d


# --------------------------------------------------------------------------------------------
# forward dynamics (for cross-checks of the model's forward_acceleration)
# --------------------------------------------------------------------------------------------
def generalized_forces(p, q, dq, torques=(0.0, 0.0, 0.0)):
    """Qv + Qgrav + Qaero + S T, all from the oracle."""
    return (lagrange_Qv(p, q, dq) + generalized_gravity(p, q) + drag_force(p, q, dq)
            + rider_torque_matrix(q) @ np.asarray(torques, float))


def forward_acceleration(p, q, dq, torques=(0.0, 0.0, 0.0), contact="thesis"):
    """ddq from [M D^T; D 0] [ddq; lambda] = [Q; -dD dq] (no Baumgarte stabilisation).
    Returns (ddq, lambda)."""
    M = mass_matrix(p, q)
    D = constraint_jacobian(p, q, contact)
    Q = generalized_forces(p, q, dq, torques)
    b = constraint_bias(p, q, dq, contact)
    K = np.zeros((NQ + 5, NQ + 5))
    K[:NQ, :NQ] = M
    K[:NQ, NQ:] = D.T
    K[NQ:, :NQ] = D
    sol = np.linalg.solve(K, np.concatenate([Q, -b]))
    return sol[:NQ], sol[NQ:]


def consistent_state(p, q, dq, contact="thesis", free=5):
    """Make (q, dq) satisfy the constraints: Newton on q[free] (default beta) for rD_z = 0,
    then dq projected orthogonally onto the null space of D. Raises if Newton fails."""
    q = np.array(q, dtype=float)
    for _ in range(50):
        z = positions(p, q, contact)["rD"][2]
        dz = constraint_jacobian(p, q, contact)[0, free]
        step = z / dz
        q[free] -= step
        if abs(step) < 1e-14:  # quadratic convergence: the next step would be rounding
            break
    else:
        raise RuntimeError("consistent_state: Newton on rD_z did not converge")
    D = constraint_jacobian(p, q, contact)
    dq = np.asarray(dq, float)
    dq = dq - D.T @ np.linalg.solve(D @ D.T, D @ dq)
    return q, dq
