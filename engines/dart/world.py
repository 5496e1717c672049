"""DART's world of a forward run: the bicycle (the run's URDF, with the rear height zc), a
ground box and DART's constraint solver with the chosen collision detector and LCP solver.

The wheels are the URDF's collision cylinders (axis = the axle, radius the wheel's) with their
length set to 2 x ``wheel_half_width``; the ground is a welded 200 m x 200 m x 1 m box whose top
face is z = 0. Why these shapes and this detector (measured on thesis-disc, stability-psid10 to
0.3 s, time step 5e-4 s, dartpy 6.20.0; error = max over q against the reference at 0.3 s):

* ``ode`` (ODE's cylinder-box test, the default): the rear wheel rides hw sin(lean) above the
  ground on its cap's rim (3.2e-7 m at hw = 1e-6 m), the front sinks ~2e-6 m; error 4.3e-4,
  first order in the step (8.5e-4, 4.3e-4, 2.2e-4, 1.1e-4 at 1e-3 ... 1.25e-4 s);
* ``bullet``: the same within 1 % (error 4.3e-4);
* ``fcl``: the rear sinks 3.3e-5 m (FCL's cylinder against a box through its GJK margin) and
  the error does not fall steadily with the step (2.8e-4 here);
* ``dart`` (DART's own detector, no cylinder-box pair of its own): the rear sinks 1.5 mm and
  the error is 1.3e-2 by 0.05 s.

The width matters next: a leaned cylinder rests on its lower cap's rim, beside the disc's
contact point (error 1.07e-3 at hw = 1e-4 m, 4.3e-4 at 1e-6 m).
"""

from __future__ import annotations

import math

import numpy as np

from reference_model.parameters.values import Parameters

from .options import RunSettings
from .skeleton import Coordinates, load_urdf, quiet, run_urdf

import dartpy as dart

__all__ = ["RUN_COORDINATES", "RunWorld", "build_world"]

#: the run skeleton's coordinates: the thesis's with the rear height zc after yc
RUN_COORDINATES = ("xc", "yc", "zc", "phi", "theta", "psi", "beta", "gamma", "eps")
DETECTORS = {"ode": "OdeCollisionDetector", "bullet": "BulletCollisionDetector",
             "fcl": "FCLCollisionDetector", "dart": "DARTCollisionDetector"}
WHEELS = ("rear_wheel", "front_wheel")


class RunWorld:
    """The world, the bicycle's skeleton and its coordinates, the bodies the loads act on."""

    def __init__(self, world, bike, coordinates: Coordinates, params: Parameters):
        self.world, self.bike, self.map = world, bike, coordinates
        body = bike.getBodyNode
        self.rear, self.frame = body("rear_wheel"), body("frame")
        self.fork, self.front = body("fork"), body("front_wheel")
        self.com3 = np.asarray(self.frame.getLocalCOM(), dtype=float)
        self.radius = {"rear_wheel": float(params.R_rear), "front_wheel": float(params.R_front)}
        self.cv = float(params.cv)
        self.W = dart.dynamics.Frame.World()
        self.wheel_shapes = {b: body(b).getShapeNode(0).getName() for b in WHEELS}

    def loads(self, T) -> None:
        """Rider torques about body axes (steer z of the fork, pedal y of the rear wheel,
        anti-roll x of the frame, each on its body alone) and the drag -cv |vG3| vG3 at the
        frame's CoM, as DART external forces for the next step (DART clears them after it)."""
        T0, T1, T2 = T
        self.fork.setExtTorque(np.array([0.0, 0.0, T0]), True)      # in the body's own axes
        self.rear.setExtTorque(np.array([0.0, T1, 0.0]), True)
        # setExtForce replaces the body's whole external wrench (its moment by offset x force),
        # so the frame's force comes first and its torque is added after
        v = self.frame.getLinearVelocity(self.com3, self.W, self.W)
        self.frame.setExtForce(-self.cv * math.sqrt(v @ v) * v, self.com3, False, True)
        self.frame.addExtTorque(np.array([T2, 0.0, 0.0]), True)

    def wheel_contact(self, name: str) -> tuple[float, float]:
        """(slip speed m/s, penetration m) of wheel ``name``'s knife-edge disc at its lowest
        point rG - R n/|n|, n = e_z - (e_z . a) a, a the axle."""
        b = self.bike.getBodyNode(name)
        X = b.getWorldTransform()
        a = X.rotation()[:, 1]
        n = np.array([0.0, 0.0, 1.0]) - a[2] * a
        p = X.translation() - self.radius[name] * n / np.linalg.norm(n)
        v = b.getLinearVelocity(X.rotation().T @ (p - X.translation()), self.W, self.W)
        return float(np.hypot(v[0], v[1])), -float(p[2])

    def normal_forces(self) -> tuple[float, float]:
        """(rear, front) vertical force of the ground on each wheel (N), summed over the
        contacts of the last step (DART's ``Contact.force``, the solved impulse / step)."""
        out = dict.fromkeys(WHEELS, 0.0)
        by_shape = {v: k for k, v in self.wheel_shapes.items()}
        result = self.world.getLastCollisionResult()
        for i in range(result.getNumContacts()):
            c = result.getContact(i)
            for obj, sign in ((c.collisionObject1, 1.0), (c.collisionObject2, -1.0)):
                wheel = by_shape.get(obj.getShapeFrame().getName())
                if wheel is not None:
                    out[wheel] += sign * float(c.force[2])
        return out["rear_wheel"], out["front_wheel"]


def build_world(params: Parameters, s: RunSettings) -> RunWorld:
    """The run's world for settings ``s``."""
    bike = load_urdf(run_urdf(params))      # its gravity is the world's (addSkeleton sets it)
    for b in WHEELS:
        shape = bike.getBodyNode(b).getShapeNode(0)
        shape.getShape().setHeight(2.0 * s.wheel_half_width)
        shape.getDynamicsAspect().setFrictionCoeff(s.friction)
    ground = dart.dynamics.Skeleton("ground")
    _, body = ground.createWeldJointAndBodyNodePair()
    box = body.createShapeNode(dart.dynamics.BoxShape(np.array([200.0, 200.0, 1.0])))
    box.createCollisionAspect()
    box.createDynamicsAspect()
    box.getDynamicsAspect().setFrictionCoeff(s.friction)
    box.setRelativeTranslation(np.array([0.0, 0.0, -0.5]))
    world = dart.simulation.World()
    world.setGravity(np.array([0.0, 0.0, -params.g]))
    world.setTimeStep(s.timestep)
    world.addSkeleton(bike)
    world.addSkeleton(ground)
    solver = world.getConstraintSolver()
    solver.setCollisionDetector(getattr(dart.collision, DETECTORS[s.collision_detector])())
    solver.setSplitImpulseEnabled(s.split_impulse)
    if s.solver == "pgs":        # the secondary (fallback) solver as the only one
        with quiet():            # DART 6.20 warns it ignores this, wrongly: it is set
            solver.setBoxedLcpSolver(solver.getSecondaryBoxedLcpSolver())
    return RunWorld(world, bike, Coordinates.of(bike, RUN_COORDINATES), params)
