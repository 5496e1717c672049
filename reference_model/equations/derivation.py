"""Symbolic derivation of the thesis bicycle, step by step as `Simb_Bicicleta` (thesis ch. 8.1).

The thesis builds, with MATLAB's symbolic toolbox and `simplify`, the Newton-Euler
equations of the four bodies (2 rear wheel, 3 frame + rider, 4 fork/handlebar, 5 front
wheel) projected onto the eight coordinates

    q = [xc, yc, phi, theta, psi, beta, gamma, eps]

(rear contact point, yaw, roll, rear-wheel angle, frame pitch, steer, front-wheel angle).
`simplify` is far too slow in sympy, so this module keeps expressions small by exact
means that need no simplification at all:

* body-local angular velocities come from the chain rule of the rotation sequence,
  ``w_L = sum_k (R_{k+1} ... R_n)^T e_k dq_k``, which *is* ``vee(A^T dA/dt)`` (the thesis's
  definition) with every sin^2 + cos^2 already reduced; global ones likewise;
* the thesis front contact ``rG5 + A5 [R sin eps, 0, -R cos eps]`` is written as the
  identical ``rG5 - R A4 e_z`` (the eps rotation cancels exactly);
* the dynamics is projected in two stages: kinematic quantities (H_i, G_iL, h_i dq,
  g_iL dq, w_iL) are derived as expressions, and M = L^T MM L, Qv = L^T (QQv - MM l dq)
  are written over *placeholder symbols* for their non-zero entries. The code generator
  emits both stages as straight-line code, so the products are never expanded.

The geometry generalises the thesis (see `params.PARAMETER_NAMES`): separate wheel radii,
a steering-axis point A distinct from the fork's centre of mass, and the front hub placed
relative to A. With ``R_rear = R_front = R``, ``xa, za = x4, z4`` and ``dx4 = dz4 = 0`` it is
the thesis exactly. Two front-contact models: ``thesis`` (the rim point along the fork's
-z axis, as published) and ``disc`` (the true lowest point of the front disc).

``gyroscopic=False`` derives a deliberately broken variant without the gyroscopic terms
``-w_iL x (I_i w_iL)`` in Qv (the fault-injection suite, `comparisons/faults.py`, checks that
the engine comparison detects and localizes it); the default is the thesis model.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from ..names import BODIES, BODY_NAMES, COORDINATES, TORQUE_NAMES  # noqa: F401 (re-exported)
from ..parameters.schema import CONTACT_MODELS, PARAMETER_NAMES

__all__ = [
    "BODIES", "BODY_NAMES", "CHAINS", "COORDINATES", "Derivation", "Kinematics",
    "Rx", "Ry", "Rz", "Symbols", "TORQUE_NAMES", "angular_velocity_global",
    "angular_velocity_local", "derive", "front_contact", "inertia_matrix", "make_symbols", "rotation",
]



@dataclass(frozen=True)
class Symbols:
    """The sympy symbols of a derivation: coordinates, rates, parameters, torques."""

    q: tuple[sp.Symbol, ...]
    dq: tuple[sp.Symbol, ...]
    p: tuple[sp.Symbol, ...]
    T: tuple[sp.Symbol, ...]

    def param(self, name: str) -> sp.Symbol:
        return self.p[PARAMETER_NAMES.index(name)]


def make_symbols() -> Symbols:
    q = tuple(sp.Symbol(n, real=True) for n in COORDINATES)
    dq = tuple(sp.Symbol("d_" + n, real=True) for n in COORDINATES)
    p = tuple(sp.Symbol(n, real=True) for n in PARAMETER_NAMES)
    T = tuple(sp.Symbol(n, real=True) for n in TORQUE_NAMES)
    return Symbols(q, dq, p, T)


# -- elementary rotations (right-handed, as the thesis writes them) --------------------

def Rx(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def Ry(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def Rz(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


_ROT = {"x": Rx, "y": Ry, "z": Rz}
_AXIS = {"x": sp.Matrix([1, 0, 0]), "y": sp.Matrix([0, 1, 0]), "z": sp.Matrix([0, 0, 1])}

# Rotation sequence of each body: (axis, coordinate) pairs from the ground outwards.
# Ai2 = A_phi A_theta; A2 = Ai2 A_psi; A3 = Ai2 A_beta; A4 = A3 A_gamma; A5 = A4 A_eps.
CHAINS = {
    "i2": (("z", "phi"), ("x", "theta")),
    2: (("z", "phi"), ("x", "theta"), ("y", "psi")),
    3: (("z", "phi"), ("x", "theta"), ("y", "beta")),
    4: (("z", "phi"), ("x", "theta"), ("y", "beta"), ("z", "gamma")),
    5: (("z", "phi"), ("x", "theta"), ("y", "beta"), ("z", "gamma"), ("y", "eps")),
}


def rotation(chain, qs: dict[str, sp.Symbol]) -> sp.Matrix:
    """A = R_1(q_1) R_2(q_2) ... for a chain of (axis, coordinate) pairs."""
    A = sp.eye(3)
    for axis, name in chain:
        A = A * _ROT[axis](qs[name])
    return A


def angular_velocity_local(chain, qs, dqs) -> sp.Matrix:
    """Body-local angular velocity vee(A^T dA/dt) = sum_k (R_{k+1}...R_n)^T e_k dq_k."""
    w = sp.zeros(3, 1)
    tail = sp.eye(3)  # R_{k+1} ... R_n, built from the outermost rotation inwards
    for axis, name in reversed(chain):
        w += tail.T * _AXIS[axis] * dqs[name]
        tail = _ROT[axis](qs[name]) * tail
    return w


def angular_velocity_global(chain, qs, dqs) -> sp.Matrix:
    """Global angular velocity vee(dA/dt A^T) = sum_k (R_1...R_{k-1}) e_k dq_k."""
    w = sp.zeros(3, 1)
    head = sp.eye(3)
    for axis, name in chain:
        w += head * _AXIS[axis] * dqs[name]
        head = head * _ROT[axis](qs[name])
    return w


def _cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    return a.cross(b)


def _dir_derivative(expr: sp.Matrix, q, dq) -> sp.Matrix:
    """d(expr)/dq . dq, the time derivative at fixed dq (thesis: h = jacobian(H dq, q), h dq)."""
    out = sp.zeros(*expr.shape)
    for qi, dqi in zip(q, dq):
        out += expr.diff(qi) * dqi
    return out


@dataclass
class Kinematics:
    """Kinematic quantities of one body i, as the thesis names them."""

    rG: sp.Matrix        # centre of mass, global (3,)
    H: sp.Matrix         # d rG / dq (3, 8)
    hdq: sp.Matrix       # h_i dq = d(H dq)/dq dq (3,)
    wL: sp.Matrix        # body-local angular velocity (3,)
    GL: sp.Matrix        # d wL / d dq (3, 8)
    gdq: sp.Matrix       # g_iL dq = d wL / dq dq (3,)


@dataclass
class Derivation:
    """Everything the code generator needs for one variant (contact model, gyroscopic terms)."""

    contact: str
    symbols: Symbols
    bodies: dict[int, Kinematics]
    points: dict[str, sp.Matrix]           # rC, rA, rG2..rG5, rD (global)
    C: sp.Matrix                           # constraint residual (5,)
    D: sp.Matrix                           # constraint Jacobian (5, 8)
    bias: sp.Matrix                        # dD dq (5,)
    S: sp.Matrix                           # rider-torque map (8, 3)
    vG3: sp.Matrix                         # frame CoM velocity (3,), for the drag
    placeholders: dict[sp.Symbol, sp.Expr] = field(default_factory=dict)
    M: sp.Matrix | None = None             # over placeholders
    Qv: sp.Matrix | None = None            # over placeholders
    Qgrav: sp.Matrix | None = None
    Qaero: sp.Matrix | None = None
    kinetic: sp.Expr | None = None         # over placeholders
    potential: sp.Expr | None = None
    gyroscopic: bool = True                # False: Qv without -w_iL x I_i w_iL (a fault variant)


def front_contact(contact: str, rG5: sp.Matrix, A4: sp.Matrix, R_front) -> sp.Matrix:
    """Front contact point rD.

    ``thesis``: rG5 + A5 [R sin eps, 0, -R cos eps] = rG5 - R (z axis of A4): the rim point
    straight below the hub along the fork axis; the lowest point only while the fork's x
    axis is horizontal. ``disc``: the true lowest point of the disc, rG5 - R u with u the
    unit vector of the wheel plane closest to +Z: u = (k - (k.a) a) / sqrt(1 - (k.a)^2),
    a = y axis of A4 (the axle).
    """
    if contact == "thesis":
        return rG5 - R_front * A4[:, 2]
    if contact == "disc":
        a = A4[:, 1]
        az = a[2]
        k = sp.Matrix([0, 0, 1])
        return rG5 - R_front * (k - az * a) / sp.sqrt(1 - az**2)
    raise ValueError(f"contact must be one of {CONTACT_MODELS}, got {contact!r}")


def derive(contact: str, gyroscopic: bool = True) -> Derivation:
    """Derive the thesis bicycle for a front-contact model ('thesis' or 'disc').

    ``gyroscopic=False`` drops the gyroscopic terms -w_iL x (I_i w_iL) from Qv (a fault
    variant for the fault-injection suite; everything else is unchanged)."""
    if contact not in CONTACT_MODELS:
        raise ValueError(f"contact must be one of {CONTACT_MODELS}, got {contact!r}")
    sy = make_symbols()
    qs = dict(zip(COORDINATES, sy.q))
    dqs = dict(zip(COORDINATES, sy.dq))
    P = {n: s for n, s in zip(PARAMETER_NAMES, sy.p)}
    q, dq = sp.Matrix(sy.q), sp.Matrix(sy.dq)

    # -- rotations and positions (Simb_Bicicleta: Vectores de posicion) -----------------
    A = {k: rotation(c, qs) for k, c in CHAINS.items()}
    rC = sp.Matrix([qs["xc"], qs["yc"], 0])
    rG2 = rC + A["i2"] * sp.Matrix([0, 0, P["R_rear"]])
    rG3 = rG2 + A[3] * sp.Matrix([P["x3"], 0, P["z3"]])
    rA = rG2 + A[3] * sp.Matrix([P["xa"], 0, P["za"]])
    rG4 = rA + A[4] * sp.Matrix([P["dx4"], 0, P["dz4"]])
    rG5 = rA + A[4] * sp.Matrix([P["x5"], 0, P["z5"]])
    rD = front_contact(contact, rG5, A[4], P["R_front"])
    rG = {2: rG2, 3: rG3, 4: rG4, 5: rG5}

    # -- per-body kinematics: H, h dq, wL, GL, g dq --------------------------------------
    bodies: dict[int, Kinematics] = {}
    for i in BODIES:
        H = rG[i].jacobian(q)
        vG = H * dq
        wL = angular_velocity_local(CHAINS[i], qs, dqs)
        GL = wL.jacobian(dq)
        bodies[i] = Kinematics(
            rG=rG[i], H=H, hdq=_dir_derivative(vG, sy.q, sy.dq), wL=wL, GL=GL,
            gdq=_dir_derivative(wL, sy.q, sy.dq),
        )

    # -- contact velocities of material points and constraints --------------------------
    w2 = angular_velocity_global(CHAINS[2], qs, dqs)
    w5 = angular_velocity_global(CHAINS[5], qs, dqs)
    vC = bodies[2].H * dq + _cross(w2, rC - rG2)
    vD = bodies[5].H * dq + _cross(w5, rD - rG5)
    C = sp.Matrix([rD[2], vC[0], vC[1], vD[0], vD[1]])
    Dz = sp.Matrix([rD[2]]).jacobian(q)
    Dv = sp.Matrix([vC[0], vC[1], vD[0], vD[1]]).jacobian(dq)
    D = Dz.col_join(Dv)
    Ddq = D * dq
    bias = _dir_derivative(Ddq, sy.q, sy.dq)

    # -- rider torques: S = [G4L(3,:)' G2L(2,:)' G3L(1,:)'] -----------------------------
    S = bodies[4].GL[2, :].T.row_join(bodies[2].GL[1, :].T).row_join(bodies[3].GL[0, :].T)

    der = Derivation(
        contact=contact, symbols=sy, bodies=bodies,
        points={"rC": rC, "rA": rA, "rG2": rG2, "rG3": rG3, "rG4": rG4, "rG5": rG5, "rD": rD},
        C=C, D=D, bias=bias, S=S, vG3=bodies[3].H * dq, gyroscopic=bool(gyroscopic),
    )
    _project_dynamics(der, P)
    return der


def inertia_matrix(i: int, P) -> sp.Matrix:
    """Body inertia about the CoM in body axes (thesis I2..I5; xz is the tensor entry)."""
    xz = P.get(f"I{i}xz", 0)
    return sp.Matrix([[P[f"I{i}xx"], 0, xz], [0, P[f"I{i}yy"], 0], [xz, 0, P[f"I{i}zz"]]])


def _placeholder(der: Derivation, name: str, expr: sp.Expr) -> sp.Expr:
    """A symbol standing for a non-zero kinematic entry (zeros stay literal zeros)."""
    if expr == 0:
        return sp.Integer(0)
    if expr.is_Symbol or expr.is_Number:
        return expr
    s = sp.Symbol(name, real=True)
    der.placeholders[s] = expr
    return s


def _ph_matrix(der: Derivation, name: str, M: sp.Matrix) -> sp.Matrix:
    return sp.Matrix(M.rows, M.cols,
                     lambda r, c: _placeholder(der, f"{name}_{r}{c}" if M.cols > 1 else f"{name}_{r}",
                                               M[r, c]))


def _project_dynamics(der: Derivation, P: dict) -> None:
    """Newton-Euler of the four bodies projected with L (thesis: M = L'MM L, Qv = L'(QQv - MM l dq)).

    Written body by body, which is the same sum without forming the 24x24 MM:
      M     = sum_i m_i H_i^T H_i + G_iL^T I_i G_iL
      Qv    = sum_i -m_i H_i^T (h_i dq) + G_iL^T (-w_iL x I_i w_iL - I_i g_iL dq)
              (without the gyroscopic -w_iL x I_i w_iL when der.gyroscopic is False)
      Qgrav = sum_i H_i^T [0, 0, -m_i g]
      Qaero = -cv |vG3| H3^T vG3
    """
    n = len(der.symbols.q)
    M = sp.zeros(n, n)
    Qv = sp.zeros(n, 1)
    Qgrav = sp.zeros(n, 1)
    kinetic = sp.Integer(0)
    potential = sp.Integer(0)
    g = P["g"]
    dq = sp.Matrix(der.symbols.dq)
    for i in BODIES:
        b = der.bodies[i]
        m = P[f"m{i}"]
        I = inertia_matrix(i, P)
        H = _ph_matrix(der, f"H{i}", b.H)
        GL = _ph_matrix(der, f"G{i}L", b.GL)
        hdq = _ph_matrix(der, f"h{i}dq", b.hdq)
        gdq = _ph_matrix(der, f"g{i}dq", b.gdq)
        wL = _ph_matrix(der, f"w{i}L", b.wL)
        vG = _ph_matrix(der, f"vG{i}", b.H * dq)
        zG = _placeholder(der, f"zG{i}", b.rG[2])
        M += m * (H.T * H) + GL.T * I * GL
        gyro = -_cross(wL, I * wL) if der.gyroscopic else sp.zeros(3, 1)
        Qv += -m * (H.T * hdq) + GL.T * (gyro - I * gdq)
        Qgrav += -m * g * H[2, :].T
        kinetic += sp.Rational(1, 2) * (m * (vG.T * vG)[0, 0] + (wL.T * I * wL)[0, 0])
        potential += m * g * zG
    H3 = _ph_matrix(der, "H3", der.bodies[3].H)
    vG3 = _ph_matrix(der, "vG3", der.vG3)
    speed3 = sp.sqrt((vG3.T * vG3)[0, 0])
    der.M = M
    der.Qv = Qv
    der.Qgrav = Qgrav
    der.Qaero = -P["cv"] * speed3 * (H3.T * vG3)
    der.kinetic = kinetic
    der.potential = potential
