"""Moore's Whipple bicycle assembled from SymBRiM's published parts, its equations formed by
sympy's KanesMethod on SymBRiM's bodies and in the Kane engine's form (`KaneDerivation`).

The parts (SymBRiM 0.1, `symbrim`): `WhippleBicycle` in its default convention ``moore``
(`WhippleBicycleMoore`: Moore's q1..q8, speeds u = dq/dt, ground frame z DOWN), the rigid
frames `RigidRearFrame` / `RigidFrontFrame` (conventions ``moore``: Moore's d1, l1, l2 and
d2, d3, l3, l4), two `KnifeEdgeWheel` (each a disc of radius r; SymBRiM's wheel inertia is
axisymmetric, izz = ixx, and is given a third moment here: `_third_moment`),
`NonHolonomicTire` contacts and a `FlatGround` (normal -z). A
`ToroidalWheel` in front (crown radius ``tr`` > 0) is the option of `derive(front_crown=True)`:
its contact point is the torus's lowest point, not the disc's.

SymBRiM's model gives the tree: its `System`'s bodies, its joints' kinematics, and SymBRiM's
contact points (`NonHolonomicTire.contact_point`). What this module adds, as the Kane engine
does on its own tree (`engines.kane.derivation`):

* the loads that SymBRiM does not model: gravity through SymBRiM's own
  `System.apply_uniform_gravity`, the frame's drag ``-cv |v_co| v_co``, the rider's three
  torques, each on one body only (steer about the fork's up axis, pedal about the rear
  wheel's left axis, anti-roll about the frame's forward axis);
* Kane's equations of the UNCONSTRAINED tree (all eight speeds independent);
* the constraint rows in the harness's order and form: the height of the front contact
  point along the ground's z (down), then the n1, n2 velocity components of each wheel's
  material point at SymBRiM's contact point, their Jacobians and their time derivative.

SymBRiM's own constraint equations (`System.holonomic_constraints`,
`nonholonomic_constraints`) are not used for the rows: they are the same conditions in
another basis (its contact points are the ones used here). The rows' agreement with the
reference's, and SymBRiM's body points with the reference's, are tests/test_symbrim.py's.
"""

from __future__ import annotations

import sympy as sp
import sympy.physics.mechanics as me

from ..kane.derivation import KaneDerivation
from ..kane.names import MOORE_PARAMETERS, TORQUES

__all__ = ["EXTRA_PARAMETERS", "build_bicycle", "derive", "parameter_symbols"]

#: Parameters after Moore's: the front tyre's crown (transverse) radius (0 without the option).
EXTRA_PARAMETERS: tuple[str, ...] = ("tr",)


def build_bicycle(front_crown: bool = False):
    """SymBRiM's Whipple bicycle, its objects, kinematics, loads and constraints defined."""
    import symbrim as sb
    bike = sb.WhippleBicycle("bicycle")
    bike.front_frame = sb.RigidFrontFrame("front_frame")
    bike.rear_frame = sb.RigidRearFrame("rear_frame")
    bike.rear_wheel = sb.KnifeEdgeWheel("rear_wheel")
    bike.front_wheel = (sb.ToroidalWheel if front_crown else sb.KnifeEdgeWheel)("front_wheel")
    bike.rear_tire = sb.NonHolonomicTire("rear_tire")
    bike.front_tire = sb.NonHolonomicTire("front_tire")
    bike.ground = sb.FlatGround("ground")
    bike.define_connections()
    bike.define_objects()
    bike.define_kinematics()
    bike.define_loads()
    bike.define_constraints()
    for wheel in (bike.rear_wheel, bike.front_wheel):
        _third_moment(wheel)
    return bike


def _third_moment(wheel) -> None:
    """SymBRiM's wheels are axisymmetric (izz = ixx); the harness's bicycles need not be (the
    conformance suite's general bicycle has three distinct wheel moments), so each wheel's
    body gets its own izz, the tensor otherwise SymBRiM's (ixx, iyy about its CoM, in its
    frame). With izz = ixx it is SymBRiM's wheel exactly."""
    body = wheel.body
    I = body.central_inertia.to_matrix(body.frame)
    izz = sp.Symbol(f"{wheel.name}_izz")
    body.central_inertia = me.inertia(body.frame, I[0, 0], I[1, 1], izz)


def _inertia(body, i: int, j: int):
    return body.central_inertia.to_matrix(body.frame)[i, j]


def parameter_symbols(bike, front_crown: bool = False) -> dict[str, sp.Expr]:
    """Moore's parameter names -> SymBRiM's symbols (mass, inertia, geometry), plus the loads'
    own (g, cv) and the crown radius."""
    rw, fw = bike.rear_wheel.body, bike.front_wheel.body
    rf, ff = bike.rear_frame.body, bike.front_frame.body
    s = {
        "rr": bike.rear_wheel.radius, "rf": bike.front_wheel.radius,
        "d1": bike.rear_frame.symbols["d1"], "l1": bike.rear_frame.symbols["l1"],
        "l2": bike.rear_frame.symbols["l2"],
        "d2": bike.front_frame.symbols["d2"], "d3": bike.front_frame.symbols["d3"],
        "l3": bike.front_frame.symbols["l3"], "l4": bike.front_frame.symbols["l4"],
        "mc": rf.mass, "md": rw.mass, "me": ff.mass, "mf": fw.mass,
        "IDxx": _inertia(rw, 0, 0), "IDyy": _inertia(rw, 1, 1), "IDzz": _inertia(rw, 2, 2),
        "ICxx": _inertia(rf, 0, 0), "ICyy": _inertia(rf, 1, 1), "ICzz": _inertia(rf, 2, 2),
        "ICxz": _inertia(rf, 0, 2),
        "IExx": _inertia(ff, 0, 0), "IEyy": _inertia(ff, 1, 1), "IEzz": _inertia(ff, 2, 2),
        "IExz": _inertia(ff, 0, 2),
        "IFxx": _inertia(fw, 0, 0), "IFyy": _inertia(fw, 1, 1), "IFzz": _inertia(fw, 2, 2),
        "g": sp.Symbol("g", real=True), "cv": sp.Symbol("cv", real=True),
        "tr": bike.front_wheel.transverse_radius if front_crown else sp.Symbol("tr", real=True),
    }
    return s


def derive(front_crown: bool = False) -> KaneDerivation:
    """The five matrices of `KaneDerivation` from SymBRiM's bicycle (Moore's coordinates)."""
    t = me.dynamicsymbols._t
    bike = build_bicycle(front_crown)
    system = bike.to_system()
    P = parameter_symbols(bike, front_crown)
    Ts = sp.symbols(TORQUES, real=True)
    N = bike.ground.frame
    qf, uf = list(bike.q), list(bike.u)
    system.apply_uniform_gravity(P["g"] * N.z)          # N.z points down (FlatGround "-z")
    qdot = {qi.diff(t): ui for qi, ui in zip(qf, uf)}
    # SymBRiM sets each wheel centre's velocity with the rolling condition already in it
    # (contact point at rest: `InContactTire._define_kinematics`), valid on the constraint
    # manifold only; the unconstrained tree needs every point's velocity from its position
    origin = bike.ground.origin
    for body in system.bodies:
        point = body.masscenter
        point.set_vel(N, point.pos_from(origin).dt(N).xreplace(qdot))

    rear_frame, fork = bike.rear_frame.body, bike.front_frame.body
    rear_wheel, front_wheel = bike.rear_wheel.body, bike.front_wheel.body
    v_co = rear_frame.masscenter.vel(N).xreplace(qdot)
    speed = sp.sqrt(v_co.dot(v_co))
    loads = list(system.loads) + [
        me.Force(rear_frame.masscenter, -P["cv"] * speed * v_co),
        me.Torque(fork.frame, -Ts[0] * fork.frame.z),
        me.Torque(rear_wheel.frame, -Ts[1] * rear_wheel.frame.y),
        me.Torque(rear_frame.frame, Ts[2] * rear_frame.frame.x),
    ]
    kane = me.KanesMethod(N, q_ind=qf, u_ind=uf,
                          kd_eqs=[ui - qi.diff(t) for qi, ui in zip(qf, uf)])
    kane.kanes_equations(list(system.bodies), loads)

    rear_contact = bike.rear_tire.contact_point
    front_contact = bike.front_tire.contact_point
    height = front_contact.pos_from(rear_contact).dot(N.z)

    def slip(wheel, contact):
        v = wheel.masscenter.vel(N) + wheel.frame.ang_vel_in(N).cross(
            contact.pos_from(wheel.masscenter))
        return [v.dot(N.x), v.dot(N.y)]

    velocity = sp.Matrix(slip(rear_wheel, rear_contact) + slip(front_wheel, front_contact))
    velocity = velocity.xreplace(qdot)
    u_vec, q_vec = sp.Matrix(uf), sp.Matrix(qf)
    jac = sp.Matrix([height]).jacobian(q_vec).col_join(velocity.jacobian(u_vec))
    rates = dict(qdot)
    rates.update({ui.diff(t): 0 for ui in uf})
    bias = (jac * u_vec).diff(t).xreplace(rates)

    qs = sp.symbols("q1:9", real=True)
    us = sp.symbols("u1:9", real=True)
    plain = dict(zip(uf, us))
    plain.update(zip(qf, qs))
    names = MOORE_PARAMETERS + EXTRA_PARAMETERS
    ps = sp.symbols(names, real=True)
    plain.update({P[k]: s for k, s in zip(names, ps)})

    def flat(M):
        return sp.Matrix(M).xreplace(plain)

    der = KaneDerivation(q=qs, u=us, p=ps, T=tuple(Ts), mass=flat(kane.mass_matrix),
                         forcing=flat(kane.forcing),
                         constraints=flat(sp.Matrix([height]).col_join(velocity)),
                         jacobian=flat(jac), bias=flat(bias))
    known = set(qs) | set(us) | set(ps) | set(Ts)
    for field in ("mass", "forcing", "constraints", "jacobian", "bias"):
        stray = getattr(der, field).free_symbols - known
        if stray:
            raise RuntimeError(f"SymBRiM's {field} has symbols outside Moore's parameters: "
                               f"{sorted(map(str, stray))}")
    return der
