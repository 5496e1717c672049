"""The redundant-coordinate Exudyn build: four free rigid bodies, three revolute joints, two
rolling discs.

* Bodies 2..5 (rear wheel, frame + rider, fork, front wheel): ``mbs.CreateRigidBody`` with
  Euler-parameter nodes at each CoM, the reference rotation equal to the thesis's body
  rotation A_i at the initial state, so the body axes are the thesis's body axes and the
  inertia tensors go in as the parameter file gives them (about the CoM). Initial CoM
  velocities and angular velocities from the thesis's kinematics (``mapping.body_states``).
* Joints (``mbs.CreateRevoluteJoint``, global frame at the initial state): frame–rear wheel
  at the rear hub about the wheel axis, frame–fork at the steering-axis point about z3,
  fork–front wheel at the front hub about the wheel axis.
* Contact: ``ObjectJointRollingDisc`` for each wheel against a ground marker, all three axes
  (here the rear height is a real constraint). Exudyn's disc touches the ground at the
  **true lowest point of the disc**, so this build realises the ``disc`` contact model only;
  the thesis's fork-axis point would need user constraints on Euler parameters (not built).

Its trajectories come back to q, dq through ``mapping`` (rotation matrices -> angles,
unwrapped; angular velocities -> rates by the linear map). With generalized-alpha (index 3)
the joints hold at position level but only to O(h^2) at velocity level (about 8e-5 rad/s
across the rear hub at h = 1e-3 in the first 0.5 s of stability-psid10), and dq, read from
the angular velocities and the rear hub velocity, inherits that: the reference's constraint
rows on the mapped states are O(h^2), not round-off as on the tree. The rear contact height
(a velocity-level row of Exudyn's disc) drifts too; ``hub_height_drift`` reports it.
"""

from __future__ import annotations

import numpy as np

import exudyn as exu
from exudyn.itemInterface import (MarkerBodyRigid, ObjectGround, ObjectJointRollingDisc, SensorBody,
                                  VObjectJointRollingDisc)
from exudyn.rigidBodyUtilities import RigidBodyInertia

from .mapping import BODIES, body_states, poses_to_q, unwrap_angles, velocities_to_dq

N_Q = 8
_E_Y, _E_Z = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])


class RedundantBuild:
    """Rigid bodies + joints + rolling discs in ``mbs``, started at (q0, dq0).

    ``markers``: rigid markers at each body's CoM ('rear', 'frame', 'fork', 'front'; body
    axes), 'frame_com' (= 'frame') and 'ground'."""

    kind = "redundant"
    hub_height_drift = None

    def __init__(self, mbs, params, q0, dq0, contact: str = "disc"):
        if contact != "disc":
            raise ValueError("the redundant Exudyn build has only the rolling-disc contact "
                             "(true lowest point of the disc); use the tree build for the thesis "
                             "contact")
        p = self.params = params
        self.contact = contact
        st = body_states(p, np.asarray(q0, dtype=float), np.asarray(dq0, dtype=float))
        self.bodies = {}
        for b in BODIES:
            inertia = RigidBodyInertia(mass=getattr(p, f"m{b}"), inertiaTensor=p.inertia(b),
                                       com=[0.0, 0.0, 0.0])
            self.bodies[b] = mbs.CreateRigidBody(
                name=f"body{b}", referencePosition=list(st["r"][b]),
                referenceRotationMatrix=np.array(st["A"][b]),
                initialVelocity=list(st["v"][b]), initialAngularVelocity=list(st["w"][b]),
                inertia=inertia, gravity=[0.0, 0.0, -p.g],
                nodeType=exu.NodeType.RotationEulerParameters, show=False)
        B = self.bodies
        A3, A4 = st["A"][3], st["A"][4]
        self.joints = {
            "rear hub": mbs.CreateRevoluteJoint(itemNumbers=[B[3], B[2]], position=list(st["r"][2]),
                                                axis=list(st["Ai2"] @ _E_Y), useGlobalFrame=True,
                                                show=False),
            "steer": mbs.CreateRevoluteJoint(itemNumbers=[B[3], B[4]], position=list(st["rA"]),
                                             axis=list(A3 @ _E_Z), useGlobalFrame=True, show=False),
            "front hub": mbs.CreateRevoluteJoint(itemNumbers=[B[4], B[5]], position=list(st["r"][5]),
                                                 axis=list(A4 @ _E_Y), useGlobalFrame=True,
                                                 show=False),
        }
        ground = mbs.AddObject(ObjectGround())
        m_ground = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
        mk = {b: mbs.AddMarker(MarkerBodyRigid(bodyNumber=B[b], localPosition=[0.0, 0.0, 0.0]))
              for b in BODIES}
        self.markers = {"rear": mk[2], "frame": mk[3], "fork": mk[4], "front": mk[5],
                        "frame_com": mk[3], "ground": m_ground}
        vis = VObjectJointRollingDisc(show=False)
        self.discs = [mbs.AddObject(ObjectJointRollingDisc(
            markerNumbers=[m_ground, mk[b]], constrainedAxes=[1, 1, 1], discRadius=R,
            discAxis=[0.0, 1.0, 0.0], visualization=vis))
            for b, R in ((2, p.R_rear), (5, p.R_front))]

    def add_sensors(self, mbs):
        ovt = exu.OutputVariableType
        self._sensors = {}
        for b in BODIES:
            kinds = [("A", ovt.RotationMatrix), ("w", ovt.AngularVelocity)]
            if b == 2:
                kinds += [("r", ovt.Position), ("v", ovt.Velocity)]
            for key, var in kinds:
                self._sensors[key, b] = mbs.AddSensor(SensorBody(
                    bodyNumber=self.bodies[b], outputVariableType=var, storeInternal=True,
                    writeToFile=False))

    def theta_now(self, mbs) -> float:
        """The current roll angle from the frame's rotation matrix (A3[2, 1] = sin(theta))."""
        A = mbs.GetObjectOutputBody(self.bodies[3], exu.OutputVariableType.RotationMatrix,
                                    localPosition=[0.0, 0.0, 0.0])
        return float(np.arcsin(np.clip(A[7], -1.0, 1.0)))

    def read(self, mbs, q0=None):
        """(t, q, dq) mapped from the stored body poses and velocities; angles unwrapped and
        shifted by whole turns to start at q0's."""
        data = {k: np.atleast_2d(mbs.GetSensorStoredData(s)) for k, s in self._sensors.items()}
        n = min(len(d) for d in data.values())
        if n == 0 or any(d.shape[1] < 2 for d in data.values()):
            return np.zeros(0), np.zeros((0, N_Q)), np.zeros((0, N_Q))
        t = data["r", 2][:n, 0]
        A = {b: data["A", b][:n, 1:10].reshape(n, 3, 3) for b in BODIES}
        w = {b: data["w", b][:n, 1:4] for b in BODIES}
        q = poses_to_q(self.params, data["r", 2][:n, 1:4], A[2], A[3], A[4], A[5])
        # the rear contact height is a velocity-level constraint in Exudyn's disc: the hub's
        # height above R_rear cos(theta) drifts (xc, yc ignore it); kept as a diagnostic
        self.hub_height_drift = float(np.abs(data["r", 2][:n, 3]
                                             - self.params.R_rear * np.cos(q[:, 3])).max())
        q = unwrap_angles(q, q0)
        dq = velocities_to_dq(self.params, q, data["v", 2][:n, 1:4], w[2], w[3], w[4], w[5])
        return t, q, dq
