"""Moore's nonlinear Whipple bicycle by Kane's method (sympy.physics.mechanics.KanesMethod).

Coordinates and frames are Moore's (J. K. Moore, "Human control of a bicycle", 2012; the
Autolev ``Whipple.al``), described in `reference_model.moore`: N with z DOWN, yaw q3 about n3,
roll q4 about a1, rear-frame pitch q5 about b2, rear wheel q6 about c2 relative to the frame,
steer q7 about c3 (the steer axis, pointing down), front wheel q8 about e2 relative to the fork;
q1, q2 the rear contact point; speeds u_i = dq_i/dt.

Geometry (Moore's parameters, SI units):

    rear wheel centre do = q1 n1 + q2 n2 - rr b3
    frame CoM         co = do + l1 c1 + l2 c3
    steer-axis point  ce = do + d1 c1
    front wheel centre fo = ce + d2 c3 + d3 e1
    fork CoM          eo = fo + l3 e1 + l4 e3
    front contact     fn = fo + rf g3,  g3 = unit(e2 x (n3 x e2))   (the disc's lowest point)

Inertias are about each body's CoM in its own Moore frame (full diagonal for the wheels,
diagonal plus the xz product for frame and fork).

Loads (all exact in this model): gravity +g n3 on every CoM; aerodynamic drag
``-cv |v_co| v_co`` at the frame's CoM; the rider's torques, each on one body only: steer
``T_dir`` about the fork's UP axis (-e3), pedal ``T_ped`` about the rear wheel's LEFT axis
(-d2), anti-roll ``T_vue`` about the frame's forward axis c1 (the thesis's axes z4, y2, x3).

What is derived (all in Moore's coordinates):

* ``mass``      M (8, 8) and ``forcing`` F (8,) of Kane's equations of the UNCONSTRAINED tree,
  ``M du/dt = F`` (F = generalized active forces + the velocity part of the inertia forces);
* ``constraints`` f (5,): [fn . n3 (height of the front contact, down positive), the n1 and n2
  velocity components of the rear wheel's material point at the rear contact, the same of the
  front wheel's at fn]; ``jacobian`` A (5, 8): row 0 = d f0/dq, rows 1..4 = d f/du (linear in
  u); ``bias`` b (5,) = d(A u)/dt at du/dt = 0 (q' = u).

The constrained equations (Kane's dependent-speed elimination) are formed numerically from
these in `engines.kane.engine`.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp
import sympy.physics.mechanics as me

from .names import MOORE_PARAMETERS, TORQUES

__all__ = ["MOORE_PARAMETERS", "TORQUES", "KaneDerivation", "derive"]


@dataclass(frozen=True)
class KaneDerivation:
    """The symbols and the derived expressions (Moore's coordinates)."""

    q: tuple[sp.Symbol, ...]
    u: tuple[sp.Symbol, ...]
    p: tuple[sp.Symbol, ...]
    T: tuple[sp.Symbol, ...]
    mass: sp.Matrix          # (8, 8)
    forcing: sp.Matrix       # (8, 1)
    constraints: sp.Matrix   # (5, 1)
    jacobian: sp.Matrix      # (5, 8)
    bias: sp.Matrix          # (5, 1)


def derive() -> KaneDerivation:
    """Kane's equations of Moore's Whipple bicycle (tens of seconds; cached by the caller)."""
    t = me.dynamicsymbols._t
    qf = me.dynamicsymbols("q1:9")
    uf = me.dynamicsymbols("u1:9")
    q1, q2, q3, q4, q5, q6, q7, q8 = qf
    P = dict(zip(MOORE_PARAMETERS, sp.symbols(MOORE_PARAMETERS, real=True)))
    Ts = sp.symbols(TORQUES, real=True)

    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (q3, N.z))
    B = A.orientnew("B", "Axis", (q4, A.x))
    C = B.orientnew("C", "Axis", (q5, B.y))
    D = C.orientnew("D", "Axis", (q6, C.y))
    E = C.orientnew("E", "Axis", (q7, C.z))
    F = E.orientnew("F", "Axis", (q8, E.y))
    # angular velocities in terms of the speeds (u = q'), expressed in the body frames
    A.set_ang_vel(N, uf[2] * N.z)
    B.set_ang_vel(A, uf[3] * A.x)
    C.set_ang_vel(B, uf[4] * B.y)
    D.set_ang_vel(C, uf[5] * C.y)
    E.set_ang_vel(C, uf[6] * C.z)
    F.set_ang_vel(E, uf[7] * E.y)
    wC = C.ang_vel_in(N).express(C)
    C.set_ang_vel(N, wC)
    D.set_ang_vel(N, (wC + uf[5] * C.y).express(D))
    wE = (wC + uf[6] * C.z).express(E)
    E.set_ang_vel(N, wE)
    F.set_ang_vel(N, (wE + uf[7] * E.y).express(F))

    O = me.Point("O")
    O.set_vel(N, 0)
    dn = O.locatenew("dn", q1 * N.x + q2 * N.y)
    dn.set_vel(N, uf[0] * N.x + uf[1] * N.y)
    do = dn.locatenew("do", -P["rr"] * B.z)
    do.v2pt_theory(dn, N, B)
    co = do.locatenew("co", P["l1"] * C.x + P["l2"] * C.z)
    co.v2pt_theory(do, N, C)
    ce = do.locatenew("ce", P["d1"] * C.x)
    ce.v2pt_theory(do, N, C)
    fo = ce.locatenew("fo", P["d2"] * C.z + P["d3"] * E.x)
    fo.v2pt_theory(ce, N, E)
    eo = fo.locatenew("eo", P["l3"] * E.x + P["l4"] * E.z)
    eo.v2pt_theory(fo, N, E)
    # front contact: the disc's lowest point
    g3_raw = E.y.cross(N.z.cross(E.y))
    g3 = g3_raw.express(E) / sp.sqrt(1 - (N.z.dot(E.y)) ** 2)
    fn = fo.locatenew("fn", P["rf"] * g3)

    # the unconstrained tree
    def inertia(frame, xx, yy, zz, xz=0):
        return me.inertia(frame, xx, yy, zz, 0, 0, xz)

    bodies = [
        me.RigidBody("rear_wheel", do, D, P["md"], (inertia(D, P["IDxx"], P["IDyy"], P["IDzz"]), do)),
        me.RigidBody("frame", co, C, P["mc"], (inertia(C, P["ICxx"], P["ICyy"], P["ICzz"], P["ICxz"]), co)),
        me.RigidBody("fork", eo, E, P["me"], (inertia(E, P["IExx"], P["IEyy"], P["IEzz"], P["IExz"]), eo)),
        me.RigidBody("front_wheel", fo, F, P["mf"], (inertia(F, P["IFxx"], P["IFyy"], P["IFzz"]), fo)),
    ]
    g = P["g"]
    v_co = co.vel(N)
    speed = sp.sqrt(v_co.dot(v_co))
    loads = [(b.masscenter, b.mass * g * N.z) for b in bodies]
    loads += [
        (co, -P["cv"] * speed * v_co),
        (E, -Ts[0] * E.z),
        (D, -Ts[1] * D.y),
        (C, Ts[2] * C.x),
    ]
    kane = me.KanesMethod(N, q_ind=qf, u_ind=uf,
                          kd_eqs=[qi.diff(t) - ui for qi, ui in zip(qf, uf)])
    kane.kanes_equations(bodies, loads)
    mass = kane.mass_matrix
    forcing = kane.forcing

    # constraints: holonomic height of the front contact, four rolling conditions
    height = fn.pos_from(dn).dot(N.z)
    v_rear = do.vel(N) + D.ang_vel_in(N).cross(dn.pos_from(do))
    v_front = fo.vel(N) + F.ang_vel_in(N).cross(fn.pos_from(fo))
    velocity = sp.Matrix([v_rear.dot(N.x), v_rear.dot(N.y), v_front.dot(N.x), v_front.dot(N.y)])
    qdot = {qi.diff(t): ui for qi, ui in zip(qf, uf)}
    velocity = velocity.subs(qdot)
    u_vec = sp.Matrix(uf)
    q_vec = sp.Matrix(qf)
    grad = sp.Matrix([height]).jacobian(q_vec)
    jac = grad.col_join(velocity.jacobian(u_vec))
    # dD dq = d(A u)/dt at du/dt = 0: one time derivative of A u (q, u functions of t), then
    # q' -> u and u' -> 0. The same as (d(A u)/dq) u, but one pass over each expression instead
    # of eight (measured 13 s -> 4 s of a cold derivation)
    Au = jac * u_vec
    rates = {qi.diff(t): ui for qi, ui in zip(qf, uf)}
    rates.update({ui.diff(t): 0 for ui in uf})
    bias = Au.diff(t).xreplace(rates)

    # plain symbols for printing
    qs = sp.symbols("q1:9", real=True)
    us = sp.symbols("u1:9", real=True)
    plain = dict(zip(uf, us))
    plain.update(zip(qf, qs))

    def flat(M):
        return sp.Matrix(M).xreplace(plain)

    return KaneDerivation(q=qs, u=us, p=tuple(P[k] for k in MOORE_PARAMETERS), T=tuple(Ts),
                          mass=flat(mass), forcing=flat(forcing),
                          constraints=flat(sp.Matrix([height]).col_join(velocity)),
                          jacobian=flat(jac), bias=flat(bias))
