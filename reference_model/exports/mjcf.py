"""The bicycle as MJCF (an XML format for multibody models): the thesis's tree, wheel discs and a ground plane.

    from reference_model.exports.mjcf import MjcfSettings, mjcf_text   # or reference_model.export_mjcf
    text = mjcf_text(params)                                   # the default contact settings
    text = mjcf_text(params, MjcfSettings(timestep=5e-5, solref=(1e-3, 1.0)))

The tree is the URDF's (`reference_model.exports.description`), one joint per coordinate in the thesis's
order, so an MJCF simulator's position/velocity order *is* the thesis's q order (depth-first body order: the rear
wheel's joint psi comes before the frame's beta because rear_wheel is the lean frame's first
child)::

    world -> xc_link (slide x) -> yc_link (slide y) -> yaw (hinge z, phi) -> lean (hinge x, theta)
    lean -> rear_wheel (hinge y, psi, at [0, 0, R_rear])
    lean -> frame (hinge y, beta, at [0, 0, R_rear]) -> fork (hinge z, gamma, at [xa, 0, za])
         -> front_wheel (hinge y, eps, at [x5, 0, z5])

Every body frame has its parent's orientation at zero angle (x forward, y left, z up when
upright) and every joint axis is a unit vector along a body axis with positive sense, so the
joint angles carry the thesis's signs unchanged. The four massive bodies carry ``<inertial>``
with the mass, the CoM in body axes and the full tensor about the CoM (``fullinertia``, so
the products I3xz, I4xz go in as the tensor entry [0, 2] = [2, 0] with no sign change;
the MJCF compiler diagonalises it itself). ``inertiafromgeom="false"``: the wheel geoms add no mass.
The massless links carry a placeholder inertial (`PLACEHOLDER_MASS`: the MJCF compiler refuses a moving
body without mass), which an engine zeroes after compiling.
No armature, damping, stiffness, friction loss or joint limits anywhere.

Contact: each wheel is a cylinder of the wheel's radius with a thin half-width
(``wheel_half_width``; the model's wheels are knife-edge discs), its axis along the body's y
(the axle); the ground is the plane z = 0. Only wheel-plane pairs collide
(contype/conaffinity). The contact parameters (friction cone, condim, solref, solimp, friction
coefficient, noslip iterations, time step, integrator) come from `MjcfSettings` and are
written on the ``<option>`` and on a default class shared by the three geoms, so the file alone
reproduces a run. MJCF's contact is soft and frictional: a rolling cylinder on a plane
approximates the ideal rolling of the disc-contact model (``contact = "disc"``), never exactly,
and never the thesis's fork-axis front contact. The aerodynamic drag and the rider torques are
loads, not part of the file (an engine applies them; the file says so).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

from ..parameters.values import Parameters
from .text import float_text as _num
from .text import vec as _vec

__all__ = [
    "CONDIMS", "CONES", "INTEGRATORS", "MjcfSettings", "PLACEHOLDER_INERTIA", "PLACEHOLDER_MASS",
    "SOLVERS", "massless_links", "mjcf_text",
]

INTEGRATORS = ("Euler", "implicit", "implicitfast", "RK4")
CONES = ("elliptic", "pyramidal")
CONDIMS = (3, 4, 6)           # 1 is frictionless: a wheel would slide sideways freely
SOLVERS = ("Newton", "CG", "PGS")
#: The massless links of the chain (xc_link, yc_link, yaw, lean) carry this mass (kg) and these
#: principal moments (kg m^2): the MJCF compiler refuses a moving body whose mass or any
#: principal moment is below mjMINVAL = 1e-15. At 1e-14 they change M by at most ~1e-14 *
#: (1 + 10 m)^2 ~ 1e-12 kg m^2 absolute at the states the harness uses (|xc|, |yc| <= 10 m)
#: against entries of O(1-100): ~1e-14 relative; an engine can set them to zero after
#: compiling (so its M is the thesis's to round-off).
PLACEHOLDER_MASS = 1e-14
PLACEHOLDER_INERTIA = 1e-14


def _positive(name: str, value, fix: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or value <= 0:
        raise ValueError(f"MJCF setting {name} = {value!r}: must be a positive finite number; "
                         f"fix: {fix}")
    return float(value)


@dataclass(frozen=True)
class MjcfSettings:
    """What an MJCF simulator needs beyond the bicycle's parameters: the contact and the time stepping.

    Defaults: the settings closest to ideal rolling at a 1e-4 s step, found by the contact
    study of `bicycle-xval run` (comparisons/stages/soft_contact.py, with the share the engine
    declares): the slip and the
    trajectory error shrink in proportion to the solref time constant (not with the step
    alone; solimp, impratio, cone, condim, noslip iterations change neither the slip),
    the simulator honours time constants down to two steps, so tc = 2 h; the implicit
    integrator halves the error of implicitfast on stability-psid10 at 0.4 s (1.4e-4
    against 2.6e-4 rad or m) and equals it elsewhere:

    * ``timestep`` (s): the fixed step; ``integrator`` one of `INTEGRATORS`.
    * ``solref`` = (time constant s, damping ratio): the contact's spring-damper in MJCF's
      standard form; the time constant must be at least 2 timesteps to be honoured.
    * ``solimp`` = (dmin, dmax, width m, midpoint, power): the impedance curve.
    * ``friction`` (-): the sliding friction coefficient (torsional and rolling friction are
      zero: the ideal rolling disc resists neither spin about the normal nor rolling).
    * ``cone``: 'elliptic' (the Coulomb cone itself) or 'pyramidal'; ``condim`` 3 (sliding
      friction only), 4 or 6.
    * ``noslip_iterations``: MJCF's post-solver that removes residual slip (0 = off).
    * ``solver``, ``iterations``, ``tolerance``: the constraint solver.
    * ``wheel_half_width`` (m): half the cylinder's length. The model's wheel is a knife edge:
      a leaned cylinder rests on its lower cap's rim, ``wheel_half_width`` beside the disc's
      contact point, which shifts the contact along the axle (measured on the replay's first
      second, thesis-disc: max trajectory error 0.19 at 1e-3 m, 0.024 at 1e-4, 0.0042 at 1e-5,
      0.0020 at 1e-6, 0.0018 at 1e-8, solref 5e-4 s).
    """

    timestep: float = 1e-4
    integrator: str = "implicit"
    solref: tuple[float, float] = (2e-4, 1.0)
    solimp: tuple[float, float, float, float, float] = (0.99, 0.999, 1e-3, 0.5, 2.0)
    friction: float = 2.0
    cone: str = "elliptic"
    condim: int = 3
    noslip_iterations: int = 0
    solver: str = "Newton"
    iterations: int = 100
    tolerance: float = 1e-10
    wheel_half_width: float = 1e-6

    def __post_init__(self):
        """Every field checked; a ValueError names the field, the value and the fix."""
        _positive("timestep", self.timestep, "a time step in s, e.g. 1e-4")
        _choice("integrator", self.integrator, INTEGRATORS)
        _choice("cone", self.cone, CONES)
        _choice("solver", self.solver, SOLVERS)
        if self.condim not in CONDIMS or isinstance(self.condim, bool):
            raise ValueError(f"MJCF setting condim = {self.condim!r}: must be one of "
                             f"{', '.join(map(str, CONDIMS))}; fix: 3 for sliding friction only")
        for name in ("noslip_iterations", "iterations"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise ValueError(f"MJCF setting {name} = {v!r}: must be a non-negative integer; "
                                 f"fix: e.g. {0 if name == 'noslip_iterations' else 100}")
        _positive("friction", self.friction, "a sliding friction coefficient, e.g. 2")
        _positive("tolerance", self.tolerance, "e.g. 1e-10")
        _positive("wheel_half_width", self.wheel_half_width, "a thin disc, e.g. 1e-6 m")
        solref = _floats("solref", self.solref, 2, "(time constant s, damping ratio), e.g. (5e-4, 1)")
        for name, v in zip(("solref time constant", "solref damping ratio"), solref):
            _positive(name, v, "solref = (time constant s, damping ratio), both > 0")
        solimp = _floats("solimp", self.solimp, 5, "(dmin, dmax, width, midpoint, power), e.g. "
                         "(0.99, 0.999, 1e-3, 0.5, 2)")
        dmin, dmax, width, mid, power = solimp
        if not (0 < dmin <= dmax < 1 and width > 0 and 0 < mid < 1 and power >= 1):
            raise ValueError(f"MJCF setting solimp = {self.solimp!r}: needs 0 < dmin <= dmax < 1, "
                             "width > 0, 0 < midpoint < 1, power >= 1; fix: e.g. "
                             "(0.99, 0.999, 1e-3, 0.5, 2)")
        object.__setattr__(self, "solref", solref)
        object.__setattr__(self, "solimp", solimp)
        for f in ("timestep", "friction", "tolerance", "wheel_half_width"):
            object.__setattr__(self, f, float(getattr(self, f)))

    def as_dict(self) -> dict:
        """Plain data (lists for the tuples), for a run's settings."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


def _choice(name: str, value, allowed) -> None:
    if value not in allowed:
        raise ValueError(f"MJCF setting {name} = {value!r}: must be one of {', '.join(allowed)}; "
                         f"fix: e.g. {allowed[0]}")


def _floats(name: str, value, n: int, fix: str) -> tuple[float, ...]:
    try:
        out = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        out = ()
    if len(out) != n or not all(math.isfinite(v) for v in out) \
            or any(isinstance(v, bool) for v in value):
        raise ValueError(f"MJCF setting {name} = {value!r}: must be {n} finite numbers; fix: {fix}")
    return out


def _inertial(p: Parameters, body: int, com) -> str:
    I = p.inertia(body)
    full = (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])   # MJCF order
    return (f'<inertial pos="{_vec(com)}" mass="{_num(getattr(p, f"m{body}"))}" '
            f'fullinertia="{_vec(full)}"/>')


def _placeholder() -> str:
    return (f'<inertial pos="0 0 0" mass="{_num(PLACEHOLDER_MASS)}" '
            f'diaginertia="{_vec([PLACEHOLDER_INERTIA] * 3)}"/>')


def _chain(p: Parameters, w: float, rear_height: bool) -> list[str]:
    """The bodies, nested: the massless links (link, joint, type, axis), then the four bodies."""
    R, Rf = p.R_rear, p.R_front
    links = [("xc_link", "xc", "slide", "1 0 0"), ("yc_link", "yc", "slide", "0 1 0")]
    if rear_height:
        links.append(("zc_link", "zc", "slide", "0 0 1"))
    links += [("yaw", "phi", "hinge", "0 0 1"), ("lean", "theta", "hinge", "1 0 0")]
    out, ind = [], "    "
    for name, joint, kind, axis in links:
        out += [f'{ind}<body name="{name}">',
                f'{ind}  <joint name="{joint}" type="{kind}" axis="{axis}"/>',
                f"{ind}  {_placeholder()}"]
        ind += "  "

    def tyre(name, radius):
        return (f'<geom name="{name}" class="contact" type="cylinder" '
                f'size="{_num(radius)} {_num(w)}" zaxis="0 1 0" contype="1" conaffinity="0"/>')

    out += [f'{ind}<body name="rear_wheel" pos="0 0 {_num(R)}">',
            f'{ind}  <joint name="psi" type="hinge" axis="0 1 0"/>',
            f"{ind}  {_inertial(p, 2, (0, 0, 0))}",
            f"{ind}  {tyre('rear_tyre', R)}",
            f"{ind}</body>",
            f'{ind}<body name="frame" pos="0 0 {_num(R)}">',
            f'{ind}  <joint name="beta" type="hinge" axis="0 1 0"/>',
            f"{ind}  {_inertial(p, 3, (p.x3, 0, p.z3))}",
            f'{ind}  <body name="fork" pos="{_vec((p.xa, 0, p.za))}">',
            f'{ind}    <joint name="gamma" type="hinge" axis="0 0 1"/>',
            f"{ind}    {_inertial(p, 4, (p.dx4, 0, p.dz4))}",
            f'{ind}    <body name="front_wheel" pos="{_vec((p.x5, 0, p.z5))}">',
            f'{ind}      <joint name="eps" type="hinge" axis="0 1 0"/>',
            f"{ind}      {_inertial(p, 5, (0, 0, 0))}",
            f"{ind}      {tyre('front_tyre', Rf)}",
            f"{ind}    </body>",
            f"{ind}  </body>",
            f"{ind}</body>"]
    for _ in links:
        ind = ind[:-2]
        out.append(f"{ind}</body>")
    return out


def massless_links(rear_height: bool = False) -> tuple[str, ...]:
    """The links that carry the placeholder inertial, in tree order."""
    return ("xc_link", "yc_link") + (("zc_link",) if rear_height else ()) + ("yaw", "lean")


def mjcf_text(p: Parameters, settings: MjcfSettings | None = None, *,
              rear_height: bool = False) -> str:
    """The MJCF document of the bicycle ``p`` with the contact and stepping ``settings``.

    ``rear_height=False`` (the export): exactly the thesis's eight joints. ``True`` inserts a
    slide joint ``zc`` (vertical, after ``yc``): the rear contact point's height, which the
    thesis's chain holds at zero by construction. A forward run on MJCF's soft contact needs it:
    without it the rear wheel cannot press into the ground, so its contact has no normal force
    of its own and its friction cone is empty; with it the ground carries the rear wheel
    through the contact, as it does the front one. The joint order is then xc, yc, zc, phi...
    """
    if not isinstance(p, Parameters):
        raise TypeError(f"mjcf_text needs a reference_model.Parameters, got {type(p).__name__}")
    s = MjcfSettings() if settings is None else settings
    if not isinstance(s, MjcfSettings):
        raise TypeError(f"settings must be an MjcfSettings, got {type(s).__name__}")
    w = s.wheel_half_width
    contact_note = ("approximates this model's rolling-disc contact" if p.contact == "disc" else
                    "approximates the rolling-disc contact, NOT this model's thesis fork-axis "
                    "front contact")
    L = [
        "<!--",
        f"  The four-body bicycle '{p.name}' (front contact model '{p.contact}'), exported by",
        "  bicycle-xval from its parameter set. Units SI; gravity -z, g = " + _num(p.g) + " m/s^2.",
        "  Joints follow the thesis's coordinates in order (= the qpos order of an MJCF reader): xc, yc",
        "  (slide), phi, theta, psi, beta, gamma, eps (hinge)" + (
            ", with a slide zc (the rear contact's height,\n  zero in the thesis) after yc"
            if rear_height else "") + ". Inertias are about each body's CoM",
        "  in its body axes (x forward, y left, z up when upright); no armature or damping.",
        "  CONTACT: MJCF's soft frictional contact of a thin cylinder (the wheel) on the plane",
        f"  z = 0; it {contact_note} (both wheels rolling without slip), not",
        "  exactly: a declared model difference. NOT IN THIS FILE: the aerodynamic drag",
        f"  (cv = {_num(p.cv)} kg/m, force -cv |vG3| vG3 at the frame's CoM) and the rider torques",
        "  (single-sided: steer about the fork's z, pedal about the rear wheel's y, anti-roll about",
        "  the frame's x); an engine applies them as loads.",
        *([] if rear_height else [
            "  FOR A FORWARD RUN: in this chain (the thesis's) the rear contact's height is zero by",
            "  construction, so the rear contact carries no normal force and no friction. Insert",
            '  a body with <joint name="zc" type="slide" axis="0 0 1"/> between yc_link and yaw (the',
            "  MJCF-reading engine of bicycle-xval does) to let the ground carry the rear wheel."]),
        "-->",
        f'<mujoco model="bicycle-{p.name}">',
        '  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>',
        f'  <option timestep="{_num(s.timestep)}" gravity="0 0 {_num(-p.g)}" '
        f'integrator="{s.integrator}" cone="{s.cone}" solver="{s.solver}" '
        f'iterations="{s.iterations}" tolerance="{_num(s.tolerance)}" '
        f'noslip_iterations="{s.noslip_iterations}"/>',
        "  <default>",
        '    <joint armature="0" damping="0" stiffness="0" frictionloss="0" limited="false"/>',
        '    <default class="contact">',
        f'      <geom condim="{s.condim}" friction="{_num(s.friction)} 0 0" '
        f'solref="{_vec(s.solref)}" solimp="{_vec(s.solimp)}" margin="0" gap="0"/>',
        "    </default>",
        "  </default>",
        "  <worldbody>",
        '    <geom name="ground" class="contact" type="plane" size="0 0 1" contype="0" '
        'conaffinity="1"/>',
        *_chain(p, w, rear_height),
        "  </worldbody>",
        "</mujoco>",
    ]
    return "\n".join(L) + "\n"
