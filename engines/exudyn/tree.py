"""The minimal-coordinate Exudyn build: one ``ObjectKinematicTree`` in the thesis's q order.

    link  joint        parent  offset (in the parent link)   body
    0     PrismaticX   -1      0                              - (massless)  xc
    1     PrismaticY    0      0                              - (massless)  yc
    2     RevoluteZ     1      0                              - (massless)  phi
    3     RevoluteX     2      0                              - (massless)  theta  (link frame = Ai2)
    4     RevoluteY     3      [0, 0, R_rear]                 2 rear wheel, CoM at the joint   psi
    5     RevoluteY     3      [0, 0, R_rear]                 3 frame, CoM at [x3, 0, z3]      beta
    6     RevoluteZ     5      [xa, 0, za]                    4 fork, CoM at [dx4, 0, dz4]     gamma
    7     RevoluteY     6      [x5, 0, z5]                    5 front wheel, CoM at the joint  eps

No joint transformation rotates an axis, so the link frames are exactly the thesis's body
frames (link 4: A2, 5: A3, 6: A4, 7: A5) and each body's inertia tensor goes in as the
parameter file gives it (about the CoM, body axes). Gravity is the tree's own ``gravity``.
Everything is built from the model's `Parameters`.

Contact (rolling without slipping on z = 0), through ``MarkerKinematicTreeRigid`` markers at
the wheel centres:

* rear: ``ObjectJointRollingDisc`` with ``constrainedAxes=[1, 1, 0]``: the tree puts the rear
  hub at height R_rear * cos(theta) above the contact by construction, so the height row is
  identically satisfied and would make the constraint Jacobian singular;
* front, ``disc`` contact (the true lowest point of the disc): ``ObjectJointRollingDisc``
  with all three axes;
* front, ``thesis`` contact (the fork-axis point rD = rG5 - R_front z4, see the model notes):
  Exudyn has no such joint, so it is imposed by two ``ObjectConnectorCoordinateVector``
  constraints on the tree's coordinates with Python user functions: a position-level one for
  [rD]_z = 0 and a velocity-level one for the horizontal velocity of the front wheel's material
  point at rD. The functions evaluate the thesis's kinematics in numpy (``mapping``); Exudyn
  supplies everything else (mass matrix, forces, rear contact, integrator). They run in the
  Newton loop, so this variant is several times slower than the disc contact.

``TreeMassMatrix`` gives Exudyn's mass matrix M(q) of the tree in these coordinates
(``MainSolverStatic.ComputeMassMatrix``), the quantity compared with the reference's M.
"""

from __future__ import annotations

import math

import numpy as np

import exudyn as exu
from exudyn.itemInterface import (MarkerKinematicTreeRigid, MarkerNodeCoordinates, NodeGenericODE2,
                                  NodePointGround, ObjectConnectorCoordinateVector, ObjectGround,
                                  ObjectJointRollingDisc, ObjectKinematicTree, MarkerBodyRigid,
                                  SensorNode,
                                  VObjectJointRollingDisc, VObjectKinematicTree)


N_Q = 8
LINK_REAR, LINK_FRAME, LINK_FORK, LINK_FRONT = 4, 5, 6, 7
JOINT_TYPES = ("PrismaticX", "PrismaticY", "RevoluteZ", "RevoluteX",
               "RevoluteY", "RevoluteY", "RevoluteZ", "RevoluteY")
LINK_PARENTS = (-1, 0, 1, 2, 3, 3, 5, 6)


def tree_description(params) -> dict:
    """The ObjectKinematicTree parameters for the thesis bicycle (see the module docstring)."""
    p = params
    zero3 = np.zeros((3, 3))
    return dict(
        jointTypes=[getattr(exu.JointType, t) for t in JOINT_TYPES],
        linkParents=list(LINK_PARENTS),
        jointTransformations=exu.Matrix3DList([np.eye(3)] * N_Q),
        jointOffsets=exu.Vector3DList([[0.0, 0.0, 0.0]] * 4
                                      + [[0.0, 0.0, p.R_rear], [0.0, 0.0, p.R_rear],
                                         [p.xa, 0.0, p.za], [p.x5, 0.0, p.z5]]),
        linkInertiasCOM=exu.Matrix3DList([zero3] * 4 + [p.inertia(b) for b in (2, 3, 4, 5)]),
        linkCOMs=exu.Vector3DList([[0.0, 0.0, 0.0]] * 5
                                  + [[p.x3, 0.0, p.z3], [p.dx4, 0.0, p.dz4], [0.0, 0.0, 0.0]]),
        linkMasses=[0.0] * 4 + [p.m2, p.m3, p.m4, p.m5],
        gravity=[0.0, 0.0, -p.g],
    )


def add_tree(mbs, params, q0, dq0):
    """Node and ObjectKinematicTree at (q0, dq0); returns (node, object)."""
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * N_Q,
                                       initialCoordinates=[float(v) for v in q0],
                                       initialCoordinates_t=[float(v) for v in dq0],
                                       numberOfODE2Coordinates=N_Q))
    obj = mbs.AddObject(ObjectKinematicTree(nodeNumber=node, **tree_description(params),
                                            visualization=VObjectKinematicTree(show=False)))
    return node, obj


# -- the thesis's fork-axis front contact as user constraints ------------------------------

class ThesisFrontContact:
    """[rD]_z(q) = 0 (position level) and [vD_x, vD_y] = J(q) dq = 0 (velocity level) for the
    thesis's contact point rD = rG5 - R_front z4 (fixed in the fork).

    The rows come from the thesis's kinematics written as joint screws: the velocity of a
    material point P of a body is the sum over the joints of its chain of axis_j x (P - o_j)
    times the joint rate (prismatic: the axis), with o_j a point on joint j's axis:
    xc: e_x, yc: e_y, phi: e_Z through rC, theta: Rz(phi) e_x through rC, beta: y of Ai2
    through rG2, gamma: z3 through rA, eps: y4 through rG5 (front wheel only). The height row is
    the fork's point (d[rD]_z/dq), the velocity rows the front wheel's. The last q is cached:
    Exudyn calls the four user functions several times per Newton iteration at the same q.
    ``jacobian_check`` compares with ``mapping.body_states``."""

    def __init__(self, params):
        p = self.params = params
        self._R = float(p.R_front)
        self._hub = float(p.R_rear)
        self._a = (float(p.xa), 0.0, float(p.za))
        self._f = (float(p.x5), 0.0, float(p.z5))
        self._last_q = None
        self._last = None
        self.calls = 0

    def _rows(self, q):
        self.calls += 1
        # plain floats, cheap to compare: Exudyn passes a list of them (no numpy round trip,
        # ~36 calls a step)
        key = (tuple(q[:N_Q]) if isinstance(q, list)
               else tuple(np.asarray(q, dtype=float)[:N_Q].tolist()))
        if key == self._last_q:
            return self._last
        xc, yc, phi, theta, _, beta, gamma, _ = key
        cf, sf, ct, st = math.cos(phi), math.sin(phi), math.cos(theta), math.sin(theta)
        cb, sb, cg, sg = math.cos(beta), math.sin(beta), math.cos(gamma), math.sin(gamma)
        # columns of Ai2 = Rz(phi) Rx(theta), A3 = Ai2 Ry(beta), A4 = A3 Rz(gamma)
        x1 = (cf, sf, 0.0)
        y2 = (-sf * ct, cf * ct, st)
        z2 = (sf * st, -cf * st, ct)
        x3 = (cb * x1[0] - sb * z2[0], cb * x1[1] - sb * z2[1], -sb * z2[2])
        z3 = (sb * x1[0] + cb * z2[0], sb * x1[1] + cb * z2[1], cb * z2[2])
        x4 = (cg * x3[0] + sg * y2[0], cg * x3[1] + sg * y2[1], cg * x3[2] + sg * y2[2])
        (xa, _, za), (x5, _, z5), R, hub = self._a, self._f, self._R, self._hub
        rG2 = (xc + hub * z2[0], yc + hub * z2[1], hub * z2[2])
        rA = (rG2[0] + xa * x3[0] + za * z3[0], rG2[1] + xa * x3[1] + za * z3[1],
              rG2[2] + xa * x3[2] + za * z3[2])
        # rD = rG5 - R z3 with rG5 = rA + x5 x4 + z5 z3 (z4 = z3: steer about z3)
        rD = (rA[0] + x5 * x4[0] + (z5 - R) * z3[0], rA[1] + x5 * x4[1] + (z5 - R) * z3[1],
              rA[2] + x5 * x4[2] + (z5 - R) * z3[2])
        d = (rD[0] - xc, rD[1] - yc, rD[2])
        e = (rD[0] - rG2[0], rD[1] - rG2[1], rD[2] - rG2[2])
        f = (rD[0] - rA[0], rD[1] - rA[1], rD[2] - rA[2])
        # the columns: e_Z x d (phi), x1 x d (theta), y2 x e (beta), z3 x f (gamma)
        c_phi = (-d[1], d[0], 0.0)
        c_theta = (x1[1] * d[2] - x1[2] * d[1], x1[2] * d[0] - x1[0] * d[2], x1[0] * d[1] - x1[1] * d[0])
        c_beta = (y2[1] * e[2] - y2[2] * e[1], y2[2] * e[0] - y2[0] * e[2], y2[0] * e[1] - y2[1] * e[0])
        c_gamma = (z3[1] * f[2] - z3[2] * f[1], z3[2] * f[0] - z3[0] * f[2], z3[0] * f[1] - z3[1] * f[0])
        # rows over (xc, yc, phi, theta, psi, beta, gamma, eps); eps: y4 x (-R z4) = -R x4
        J_height = np.array([0.0, 0.0, c_phi[2], c_theta[2], 0.0, c_beta[2], c_gamma[2], 0.0])
        J_velocity = np.array([
            [1.0, 0.0, c_phi[0], c_theta[0], 0.0, c_beta[0], c_gamma[0], -R * x4[0]],
            [0.0, 1.0, c_phi[1], c_theta[1], 0.0, c_beta[1], c_gamma[1], -R * x4[1]]])
        self._last_q = key
        # the height row: the fork's point, no eps; also as the 1 x 8 Jacobian Exudyn asks for
        self._last = (rD[2], J_height, J_velocity, J_height.reshape(1, N_Q))
        return self._last

    def jacobian_check(self, q) -> float:
        """max |difference| between these rows and the ones from ``mapping.body_states``."""
        from .mapping import body_states
        q = np.asarray(q, dtype=float)
        h, Jh, Jv, _ = self._rows(q)
        st = body_states(self.params, np.broadcast_to(q, (N_Q, N_Q)), np.eye(N_Q))
        z4 = st["A"][4][0][:, 2]
        rD = st["r"][5][0] - self._R * z4
        Jh_ref = (st["v"][4] + np.cross(st["w"][4], rD - st["r"][4][0]))[:, 2]
        Jv_ref = (st["v"][5] + np.cross(st["w"][5], rD - st["r"][5][0]))[:, :2].T
        return float(max(abs(h - rD[2]), np.abs(Jh - Jh_ref).max(), np.abs(Jv - Jv_ref).max()))

    # Exudyn user functions: (mbs, t, itemNumber, q, q_t, velocityLevel)
    def height(self, mbs, t, itemNumber, q, q_t, velocityLevel):
        h, J, _, _ = self._rows(q)
        if velocityLevel:       # index-2 solvers ask for the time derivative
            return [float(J @ np.asarray(q_t, dtype=float))]
        return [float(h)]

    def height_jacobian(self, mbs, t, itemNumber, q, q_t, velocityLevel):
        return self._rows(q)[3]

    def velocity(self, mbs, t, itemNumber, q, q_t, velocityLevel):
        return list(self._rows(q)[2] @ np.asarray(q_t, dtype=float))

    def velocity_jacobian(self, mbs, t, itemNumber, q, q_t, velocityLevel):
        return self._rows(q)[2]


class TreeBuild:
    """The kinematic tree with its rolling contacts in ``mbs``, started at (q0, dq0).

    ``markers``: rigid markers for loads — 'rear', 'frame', 'fork', 'front' (each at the body's
    joint origin, in body axes) and 'frame_com' (the frame's CoM)."""

    kind = "tree"

    def __init__(self, mbs, params, q0, dq0, contact: str = "disc"):
        if contact not in ("disc", "thesis"):
            raise ValueError(f"unknown front contact {contact!r}")
        p = params
        self.params, self.contact = p, contact
        self.node, self.tree = add_tree(mbs, p, q0, dq0)
        ground = mbs.AddObject(ObjectGround())
        m_ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))

        def link_marker(link, pos=(0.0, 0.0, 0.0)):
            return mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber=self.tree, linkNumber=link,
                                                          localPosition=list(pos)))

        self.markers = {"rear": link_marker(LINK_REAR), "frame": link_marker(LINK_FRAME),
                        "fork": link_marker(LINK_FORK), "front": link_marker(LINK_FRONT),
                        "frame_com": link_marker(LINK_FRAME, (p.x3, 0.0, p.z3)),
                        "ground": m_ground}
        vis = VObjectJointRollingDisc(show=False)
        self.rear_disc = mbs.AddObject(ObjectJointRollingDisc(
            markerNumbers=[m_ground, self.markers["rear"]], constrainedAxes=[1, 1, 0],
            discRadius=p.R_rear, discAxis=[0.0, 1.0, 0.0], visualization=vis))
        self.user_contact = None
        if contact == "disc":
            self.front_disc = mbs.AddObject(ObjectJointRollingDisc(
                markerNumbers=[m_ground, self.markers["front"]], constrainedAxes=[1, 1, 1],
                discRadius=p.R_front, discAxis=[0.0, 1.0, 0.0], visualization=vis))
        else:
            uc = self.user_contact = ThesisFrontContact(p)
            n_ground = mbs.AddNode(NodePointGround())
            m0 = mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=n_ground))
            m1 = mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=self.node))
            mbs.AddObject(ObjectConnectorCoordinateVector(
                markerNumbers=[m0, m1], scalingMarker0=np.zeros((1, N_Q)), velocityLevel=False,
                constraintUserFunction=uc.height, jacobianUserFunction=uc.height_jacobian,
                ))
            mbs.AddObject(ObjectConnectorCoordinateVector(
                markerNumbers=[m0, m1], scalingMarker0=np.zeros((2, N_Q)), velocityLevel=True,
                constraintUserFunction=uc.velocity, jacobianUserFunction=uc.velocity_jacobian,
                ))

    def add_sensors(self, mbs):
        ovt = exu.OutputVariableType
        self._sq = mbs.AddSensor(SensorNode(nodeNumber=self.node, outputVariableType=ovt.Coordinates,
                                            storeInternal=True, writeToFile=False))
        self._sv = mbs.AddSensor(SensorNode(nodeNumber=self.node, outputVariableType=ovt.Coordinates_t,
                                            storeInternal=True, writeToFile=False))

    def theta_now(self, mbs) -> float:
        """The current roll angle (for the stop-at-fall check between steps)."""
        return float(mbs.GetNodeOutput(self.node, exu.OutputVariableType.Coordinates)[3])

    def read(self, mbs, q0=None):
        """(t, q, dq) as stored by the sensors (the tree's coordinates are q, dq directly)."""
        Q = np.atleast_2d(mbs.GetSensorStoredData(self._sq))
        V = np.atleast_2d(mbs.GetSensorStoredData(self._sv))
        n = min(len(Q), len(V))
        if n == 0 or Q.shape[1] != N_Q + 1:
            return np.zeros(0), np.zeros((0, N_Q)), np.zeros((0, N_Q))
        return Q[:n, 0], Q[:n, 1:], V[:n, 1:]


class TreeMassMatrix:
    """Exudyn's mass matrix of the tree (no constraints, no loads) at any q."""

    def __init__(self, params):
        self.SC = exu.SystemContainer()
        self.mbs = self.SC.AddSystem()
        self.node, self.tree = add_tree(self.mbs, params, np.zeros(N_Q), np.zeros(N_Q))
        self.mbs.Assemble()
        settings = exu.SimulationSettings()
        settings.solution.file.write = False
        settings.solution.sensors.active = False
        settings.staticSolver.verboseMode = 0
        self.solver = exu.MainSolverStatic()
        self.solver.InitializeSolver(self.mbs, settings)

    def __call__(self, q) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (N_Q,):
            raise ValueError(f"q must have shape ({N_Q},); got {q.shape}")
        self.mbs.systemData.SetODE2Coordinates([float(v) for v in q],
                                               configuration=exu.ConfigurationType.Current)
        self.solver.ComputeMassMatrix(self.mbs)
        return np.array(self.solver.GetSystemMassMatrix(), dtype=float)[:N_Q, :N_Q]
