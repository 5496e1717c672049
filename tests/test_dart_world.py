"""DART's world of a forward run (engines/dart/world.py), read back from DART itself and held
to physics: every run setting reaches DART's world (its gravity, time step, collision detector,
boxed LCP solver and split impulse, the wheels' cylinders and friction, the ground box), the
run world's bodies are the model's, the knife-edge disc's slip and depth are the reference's
contact-point velocity and height, and the ground's normal forces on a bicycle standing still
carry its weight, split between the wheels by the moment balance about a contact point,
whichever of the two collision objects DART lists first. Each test names the planted bugs
(mutmut's survivors of the module's first measurement) it fails on.

Cost: about 0.2 s (a world builds in 2-3 ms; the at-rest tests step a few times).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from reference_model import load_model

dart = pytest.importorskip("dartpy")

from engines.dart.options import RunSettings  # noqa: E402
from engines.dart.world import RUN_COORDINATES, build_world  # noqa: E402
from standing import static_split  # noqa: E402

#: every option away from its default (options.py's DEFAULTS), so that a setting dropped on the
#: way to DART's world shows as DART's default or ours
SETTINGS = RunSettings(timestep=2.5e-4, collision_detector="bullet", friction=0.7, solver="pgs",
                       wheel_half_width=1e-3, split_impulse=True)
#: standard gravity (CGPM 1901), not DART's default 9.81, so a world left at DART's default shows
G0 = 9.80665
BODIES = {"rear_wheel": "m2", "frame": "m3", "fork": "m4", "front_wheel": "m5"}


@pytest.fixture(scope="module")
def disc():
    return load_model("thesis-disc")


@pytest.fixture(scope="module")
def bench():
    """The benchmark bicycle (different wheel radii, 0.3 m rear and 0.35 m front, Meijaard et
    al. 2007, Table 1) with standard gravity."""
    return load_model("benchmark").params.replace(g=G0)


@pytest.fixture(scope="module")
def tuned(bench):
    """The run world of the benchmark bicycle with every setting away from its default."""
    return build_world(bench, SETTINGS)


@pytest.fixture(scope="module")
def default(disc):
    return build_world(disc.params, RunSettings())


def _ground(rw):
    """The world's skeleton that is not the bicycle's (found without its name)."""
    others = [rw.world.getSkeleton(i) for i in range(rw.world.getNumSkeletons())]
    others = [s for s in others if s.getName() != rw.bike.getName()]
    assert len(others) == 1
    return others[0]


def test_every_setting_reaches_darts_world(tuned, bench):
    """DART's world read back through its own getters, every setting away from its default:
    gravity (0, 0, -g) on the world and the bicycle; the step; the collision detector; split
    impulse on; PGS as the primary boxed LCP solver (options.py: "projected Gauss-Seidel
    alone"); each wheel a CylinderShape of its wheel's radius and length 2 x wheel_half_width
    (the module's docstring), the friction coefficient on both wheels and the ground. Exact:
    each is a stored value read back. Fails when the cylinder's length is not twice the
    half-width, when split impulse is left at DART's default (off), when the pgs choice is
    tested against a misspelt name or inverted, or when the primary solver is set to
    nothing (DART refuses a null solver with a warning and keeps Dantzig)."""
    world, bike = tuned.world, tuned.bike
    assert np.array_equal(world.getGravity(), [0.0, 0.0, -G0])
    assert np.array_equal(bike.getGravity(), [0.0, 0.0, -G0])
    assert world.getTimeStep() == 2.5e-4
    solver = world.getConstraintSolver()
    assert solver.getCollisionDetector().getType() == "bullet"
    assert solver.isSplitImpulseEnabled() is True
    assert solver.getBoxedLcpSolver().getType() == "PgsBoxedLcpSolver"
    for body, radius in (("rear_wheel", bench.R_rear), ("front_wheel", bench.R_front)):
        node = bike.getBodyNode(body)
        assert node.getNumShapeNodes() == 1
        shape_node = node.getShapeNode(0)
        shape = shape_node.getShape()
        assert shape.getType() == "CylinderShape"
        assert shape.getRadius() == radius
        assert shape.getHeight() == 2.0 * 1e-3
        assert shape_node.getDynamicsAspect().getFrictionCoeff() == 0.7
    box = _ground(tuned).getBodyNode(0).getShapeNode(0)
    assert box.getDynamicsAspect().getFrictionCoeff() == 0.7


def test_the_default_settings_give_dantzig_with_pgs_as_its_fallback(default):
    """At the defaults (options.py: "Dantzig's pivoting (exact, with PGS as its fallback)"),
    DART's constraint solver keeps Dantzig as the primary boxed LCP solver and PGS as the
    secondary, split impulse is off and the detector is ODE's; the step is 5e-4 s. Fails when
    the pgs test is inverted (PGS would replace Dantzig at the default)."""
    solver = default.world.getConstraintSolver()
    assert solver.getBoxedLcpSolver().getType() == "DantzigBoxedLcpSolver"
    assert solver.getSecondaryBoxedLcpSolver().getType() == "PgsBoxedLcpSolver"
    assert solver.isSplitImpulseEnabled() is False
    assert solver.getCollisionDetector().getType() == "ode"
    assert default.world.getTimeStep() == 5e-4


@pytest.mark.parametrize("detector", ["ode", "bullet", "fcl", "dart"])
def test_each_detector_option_is_darts_detector_of_that_name(disc, detector):
    """Each collision_detector value builds DART's detector of that name (its getType)."""
    rw = build_world(disc.params, RunSettings(collision_detector=detector))
    assert rw.world.getConstraintSolver().getCollisionDetector().getType() == detector


def test_the_ground_is_a_welded_200_m_box_whose_top_face_is_z_0(default):
    """The module's docstring: "a welded 200 m x 200 m x 1 m box whose top face is z = 0";
    every run starts at xc = yc = 0 (each forward scenario's initial state), so the box is
    centred there: 100 m of ground every way (a 6.28 s scenario at 8.5 m/s covers 53 m).
    Read back: one body on a weld joint, one BoxShape, its world-frame extent from DART's
    pose and size, exact (sums of binary fractions). Fails when a side is 201 m, the box 2 m
    deep (its top face then at z = +0.5 m), or the box shifted 1 m along x or y."""
    ground = _ground(default)
    assert ground.getNumBodyNodes() == 1 and ground.getNumDofs() == 0
    assert ground.getRootJoint().getType() == "WeldJoint"
    node = ground.getBodyNode(0).getShapeNode(0)
    assert node.getShape().getType() == "BoxShape"
    assert node.hasCollisionAspect()
    X = node.getWorldTransform()
    half = np.asarray(node.getShape().getSize()) / 2.0
    corners = np.array([X.translation() + X.rotation() @ (half * np.array(s))
                        for s in itertools.product((-1.0, 1.0), repeat=3)])
    assert np.array_equal(corners.min(axis=0), [-100.0, -100.0, -1.0])
    assert np.array_equal(corners.max(axis=0), [100.0, 100.0, 0.0])


def test_the_run_worlds_bodies_are_the_models(tuned, bench):
    """RunWorld's bodies (rear, frame, fork, front) are DART's bodies of those names with the
    model's masses m2..m5; the frame's local CoM is (x3, 0, z3) (the thesis's frame CoM in the
    frame's axes, as the Drake adapter writes it); the radii and cv are the parameters'; the
    coordinates are RUN_COORDINATES. Exact: stored values. Fails when a body is looked up by
    a misspelt name (DART returns None)."""
    rw = tuned
    for attr, (name, mass) in zip(("rear", "frame", "fork", "front"), BODIES.items()):
        node = getattr(rw, attr)
        assert node is not None and node.getName() == name
        assert node.getMass() == getattr(bench, mass)
    assert np.array_equal(rw.com3, [bench.x3, 0.0, bench.z3])
    assert rw.radius == {"rear_wheel": bench.R_rear, "front_wheel": bench.R_front}
    assert rw.cv == bench.cv
    assert rw.map.names == RUN_COORDINATES


def test_wheel_contact_is_the_references_contact_point_velocity_and_depth(default, disc):
    """At random states (lean and steer up to 1 rad, rates up to 3 /s, the rear height zc and
    its rate free), each wheel's (slip, penetration) against the reference model: the slip is
    the horizontal speed of the wheel's material point at the disc's lowest point, which the
    reference's constraint residual holds as (vC_x, vC_y) rear and (vD_x, vD_y) front
    (docs/engines.md: C = [rD_z, vC_x, vC_y, vD_x, vD_y]); the depth below the ground is -zc
    at the rear (the reference's rear contact is at z = 0 and zc lifts the whole chain) and
    -(zc + rD_z) at the front. Round-off: speeds of a few m/s, heights below 1 m (measured
    4e-16). Fails when the slip takes the y or z component twice or the vertical one, or when
    the penetration's sign is flipped (a lifted wheel would read as sunk)."""
    rw, model = default, disc
    rng = np.random.default_rng(7)
    for q, dq, zc, dzc in zip(rng.uniform(-1, 1, (6, 8)), rng.uniform(-3, 3, (6, 8)),
                              rng.uniform(-1e-2, 1e-2, 6), rng.uniform(-1, 1, 6)):
        rw.bike.setPositions(rw.map.to_dart(np.insert(q, 2, zc)))
        rw.bike.setVelocities(rw.map.to_dart(np.insert(dq, 2, dzc)))
        C = np.asarray(model.constraint_residual(q, dq), dtype=float).ravel()
        rear, front = rw.wheel_contact("rear_wheel"), rw.wheel_contact("front_wheel")
        assert rear == pytest.approx((np.hypot(C[1], C[2]), -zc), rel=0, abs=1e-13)
        assert front == pytest.approx((np.hypot(C[3], C[4]), -(zc + C[0])), rel=0, abs=1e-13)


def _standing(model, settings, wheel_second=False):
    """A run world with the bicycle upright and still on the ground (q = 0, zc = 0), with the
    ground added to the world first when ``wheel_second``."""
    rw = build_world(model.params, settings)
    if wheel_second:
        rw.world.removeSkeleton(rw.bike)
        rw.world.addSkeleton(rw.bike)
    rw.bike.setPositions(np.zeros(9))
    rw.bike.setVelocities(np.zeros(9))
    return rw


def test_no_contact_no_normal_force(disc):
    """docs/engines.md: the normal forces are "zero at t = 0, before any step" and zero once a
    wheel has lifted off: before a step DART has no collision result, and a bicycle 5 cm above
    the ground has no contact after one (it falls g h^2 = 2.5e-6 m). Exact zeros. Fails when
    a wheel's sum starts from anything but 0."""
    rw = _standing(disc, RunSettings())
    assert rw.normal_forces() == (0.0, 0.0)
    rw.bike.setPositions(rw.map.to_dart(np.insert(np.zeros(8), 2, 0.05)))
    rw.world.step()
    assert rw.world.getLastCollisionResult().getNumContacts() == 0
    assert rw.normal_forces() == (0.0, 0.0)


def test_at_rest_the_normal_forces_are_the_weight_split_by_the_moment_balance(disc):
    """The bicycle upright and still on the ground at the defaults (ODE's detector, Dantzig):
    after three steps the rear and front normal forces are the static split of its weight
    (582.2 N and 245.2 N of 827.4 N on thesis-disc; `static_split`). Each wheel is here the
    first collision object of its contacts (checked), whose force DART's Contact.force is
    ("Contact force acting on bodyNode1", dart/collision/Contact.hpp). Bound 1e-5 relative:
    DART's contact is rigid up to its error reduction, which leaves the still bicycle moving
    ~1e-8 m/s (measured 4.6e-8 relative after the first step); a 1 N error is 1.7e-3 of the
    rear force. Fails when a wheel's sum does not start from zero, or takes the force with
    the wrong sign."""
    rw = _standing(disc, RunSettings())
    for _ in range(3):
        rw.world.step()
    result = rw.world.getLastCollisionResult()
    assert result.getNumContacts() > 0
    wheels = {rw.wheel_shapes[w] for w in ("rear_wheel", "front_wheel")}
    for i in range(result.getNumContacts()):
        assert result.getContact(i).collisionObject1.getShapeFrame().getName() in wheels
    rear, front = rw.normal_forces()
    expected = static_split(disc)
    assert rear == pytest.approx(expected[0], rel=1e-5)
    assert front == pytest.approx(expected[1], rel=1e-5)


def test_the_normal_force_does_not_depend_on_which_object_dart_lists_first(disc):
    """DART's Contact.force acts on the first collision object and its opposite on the second
    (dart/collision/Contact.hpp); which one a wheel is depends on the detector: Bullet lists
    the skeleton added first first, so with the ground added before the bicycle each wheel is
    the second object (checked) and the force on it is -Contact.force. The normal forces are
    still the static split of the weight (`static_split`). Bound 1e-3 relative: Bullet's
    contact leaves the split 1e-4 off the static one (measured after 6 steps: Bullet finds the
    rear contact only once the wheel has sunk, 2e-6 m after the first step, and its error
    reduction is still pushing the wheel out), and a wrong sign is off
    by 100 % or more. Fails when the second object's force is taken with the first's sign
    (the normal forces negative) or doubled."""
    rw = _standing(disc, RunSettings(collision_detector="bullet"), wheel_second=True)
    for _ in range(6):
        rw.world.step()
    result = rw.world.getLastCollisionResult()
    assert result.getNumContacts() > 0
    wheels = {rw.wheel_shapes[w] for w in ("rear_wheel", "front_wheel")}
    for i in range(result.getNumContacts()):
        assert result.getContact(i).collisionObject2.getShapeFrame().getName() in wheels
    rear, front = rw.normal_forces()
    expected = static_split(disc)
    assert rear == pytest.approx(expected[0], rel=1e-3)
    assert front == pytest.approx(expected[1], rel=1e-3)
