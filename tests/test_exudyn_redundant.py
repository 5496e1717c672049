"""The redundant-coordinate Exudyn build (engines/exudyn/redundant.py) taken apart: what it puts
into Exudyn's system (markers, joints, sensors), the roll angle it reads each step
(``theta_now``) and the minimal coordinates it maps its stored poses back to (``read``).

The engine's runs (tests/test_exudyn.py) check the build end to end against the reference; here
each piece is checked where a run cannot see it: the build's attributes and markers a caller
uses, a read before any step or after a run that failed at its first step, the angles' whole
turns, the rear hub height diagnostic, a lean of exactly 90 degrees, and the files a run leaves.

Expected values: the reference model's own points (``Model.points``) and the given state, the
body rotations written here from docs/engines.md ("Orientation and geometry"), and Exudyn's own
API read back (its marker and object outputs, its sensors). The bicycle is the general disc
bicycle (tests/conftest.py: unequal wheels, a fork CoM off the steering axis), so that a marker
or a joint on the wrong body cannot hide behind thesis-disc's symmetries. The state is one
leaned, steered, rolling state made consistent by the reference (``consistent_state``), with
the yaw, the rear wheel angle and the front wheel angle whole turns away from (-pi, pi].
"""

from __future__ import annotations

import os

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from exudyn.itemInterface import SensorBody  # noqa: E402

from engines.exudyn.engine import quiet  # noqa: E402
from exudyn_checks import H, rotations, settings, solve  # noqa: E402
from engines.exudyn.redundant import RedundantBuild  # noqa: E402
from reference_model.solvers import consistent_state  # noqa: E402

STEPS = 20               # 0.02 s: enough samples for the read-back checks, milliseconds to run
TWO_PI = 2 * np.pi
#: xc, yc, phi, theta, psi, beta (solved), gamma, eps: leaned 0.3 rad, steered 0.5 rad; phi,
#: psi and eps a whole turn outside (-pi, pi], where Exudyn's rotation matrices cannot say so
Q_GIVEN = (0.4, -0.3, 0.5 + TWO_PI, 0.3, 1.0 + TWO_PI, 0.0, 0.5, -0.7 - TWO_PI)
#: the independent rates theta', psi', gamma' (rad/s): rolling forward at ~1.6 m/s
DQ_IND = (0.2, 5.0, -0.3)
E_Y, E_Z = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def state(general_disc):
    """The given state projected onto the disc bicycle's constraints by the reference."""
    dq = np.zeros(8)
    dq[[3, 4, 6]] = DQ_IND
    cs = consistent_state(general_disc, np.array(Q_GIVEN), dq)
    assert abs(cs.q[5]) > 1e-3            # a pitched frame: A3 differs from A_lean
    return cs.q, cs.dq


@pytest.fixture(scope="module")
def run(general_disc, state, tmp_path_factory):
    """One build (default contact), Exudyn's outputs before the run, STEPS steps of
    generalized-alpha in an empty working folder, and the read-back; plus two sensors of the
    test's own (the rear hub's position, the frame's rotation matrix) for a second reading."""
    q0, dq0 = state
    folder = tmp_path_factory.mktemp("exudyn-redundant-run")
    here = os.getcwd()
    os.chdir(folder)
    try:
        with quiet():
            SC = exu.SystemContainer()
            mbs = SC.AddSystem()
            build = RedundantBuild(mbs, general_disc.params, q0, dq0)
            build.add_sensors(mbs)
            ovt = exu.OutputVariableType
            own = {key: mbs.AddSensor(SensorBody(bodyNumber=build.bodies[b], outputVariableType=var,
                                                 storeInternal=True, writeToFile=False))
                   for key, b, var in (("r2", 2, ovt.Position), ("A3", 3, ovt.RotationMatrix))}
            mbs.Assemble()
            before = {"theta": build.theta_now(mbs), "read": build.read(mbs, q0)}
            solve(mbs, settings(STEPS))
            after = build.read(mbs, q0)
            wrapped = build.read(mbs)
        files = sorted(p.name for p in folder.rglob("*"))
    finally:
        os.chdir(here)
    return {"SC": SC, "mbs": mbs, "build": build, "before": before, "read": after,
            "wrapped": wrapped, "files": files,
            "own": {k: np.asarray(mbs.GetSensorStoredData(s)) for k, s in own.items()}}


def test_the_default_contact_is_the_disc_and_the_thesis_contact_is_refused_with_the_fix(
        general_disc, run, state):
    """Built without a contact argument (the fixture), the build is the rolling-disc one
    (``contact == 'disc'``, the only contact Exudyn's ObjectJointRollingDisc realises: module
    docstring); asked for the thesis's fork-axis contact it refuses with one line that says what
    it has and where the thesis contact is (the tree build). Fails when the default is not
    'disc' (every default build refused), when ``contact`` is not recorded, or when the message
    is lost or reworded."""
    assert run["build"].contact == "disc"
    mbs = exu.SystemContainer().AddSystem()
    with pytest.raises(ValueError) as err:
        RedundantBuild(mbs, general_disc.params, *state, contact="thesis")
    assert str(err.value) == ("the redundant Exudyn build has only the rolling-disc contact (true "
                              "lowest point of the disc); use the tree build for the thesis "
                              "contact")


def test_markers_are_the_body_coms_in_body_axes_and_the_ground_origin(general_disc, run, state):
    """The class docstring's markers: 'rear', 'frame', 'fork', 'front' at each body's CoM in
    its body axes, 'frame_com' the same marker as 'frame', 'ground' on the ground. Expected:
    the reference's CoMs rG2..rG5 (``Model.points``) and the rotations A2..A5 of
    docs/engines.md, against Exudyn's own marker outputs at the initial state; the ground
    marker at the global origin, on the ground plane z = 0 (docs/engines.md). Round-off only
    (Exudyn takes positions as given and Euler parameters from the matrices): 1e-12. Fails when
    a key is renamed or points at another body's marker, or a marker sits off the CoM or off the
    ground origin."""
    mbs, build = run["mbs"], run["build"]
    q0, _ = state
    pts, A = general_disc.points(q0), rotations(q0)
    ovt = exu.OutputVariableType
    assert set(build.markers) == {"rear", "frame", "fork", "front", "frame_com", "ground"}
    for key, b in (("rear", 2), ("frame", 3), ("fork", 4), ("front", 5)):
        m = build.markers[key]
        assert int(mbs.GetMarker(m)["bodyNumber"]) == int(build.bodies[b]), key
        # the initial state is Exudyn's reference configuration: read it there
        r = mbs.GetMarkerOutput(m, ovt.Position, configuration=exu.ConfigurationType.Reference)
        R = mbs.GetMarkerOutput(m, ovt.RotationMatrix,
                                configuration=exu.ConfigurationType.Reference)
        np.testing.assert_allclose(r, pts[f"rG{b}"], rtol=0, atol=1e-12, err_msg=key)
        np.testing.assert_allclose(np.reshape(R, (3, 3)), A[b], rtol=0, atol=1e-12, err_msg=key)
    assert build.markers["frame_com"] == build.markers["frame"]
    ground = mbs.GetMarkerOutput(build.markers["ground"], ovt.Position)
    np.testing.assert_allclose(ground, [0.0, 0.0, 0.0], rtol=0, atol=0)


def test_joints_join_the_documented_bodies_at_the_hubs_and_the_steering_axis(
        general_disc, run, state):
    """``joints``, by name, as the module docstring lists them: 'rear hub' joins frame and
    rear wheel at the rear hub about the wheel axis (A_lean e_y), 'steer' frame and fork at the
    steering-axis point rA about z3 (A3 e_z), 'front hub' fork and front wheel at the front hub
    about the front axle (A4 e_y). Expected: the reference's points rG2, rA, rG5 and the
    docs' rotations; read back from Exudyn: each joint's markers, their bodies, global
    positions and z axes (marker rotation times the joint's rotationMarker: an
    ObjectJointRevoluteZ turns about that z). Round-off (1e-12). Fails when a joint is renamed,
    joins other bodies, or sits at another point or axis."""
    mbs, build = run["mbs"], run["build"]
    q0, _ = state
    pts, A = general_disc.points(q0), rotations(q0)
    ovt, ref = exu.OutputVariableType, exu.ConfigurationType.Reference
    expected = {"rear hub": ({3, 2}, pts["rG2"], A["lean"] @ E_Y),
                "steer": ({3, 4}, pts["rA"], A[3] @ E_Z),
                "front hub": ({4, 5}, pts["rG5"], A[4] @ E_Y)}
    assert set(build.joints) == set(expected)
    for name, (bodies, point, axis) in expected.items():
        joint = mbs.GetObject(build.joints[name])
        assert joint["objectType"] == "JointRevoluteZ", name
        markers = joint["markerNumbers"]
        on = {int(mbs.GetMarker(m)["bodyNumber"]) for m in markers}
        assert on == {int(build.bodies[b]) for b in bodies}, name
        for m, turn in zip(markers, (joint["rotationMarker0"], joint["rotationMarker1"])):
            np.testing.assert_allclose(mbs.GetMarkerOutput(m, ovt.Position, configuration=ref),
                                       point, rtol=0, atol=1e-12, err_msg=name)
            R = np.reshape(mbs.GetMarkerOutput(m, ovt.RotationMatrix, configuration=ref), (3, 3))
            np.testing.assert_allclose(R @ np.asarray(turn) @ E_Z, axis, rtol=0, atol=1e-12,
                                       err_msg=name)


def test_a_read_before_any_step_is_empty_with_the_documented_widths(run):
    """Before the solver has stored anything (Exudyn gives a (0, 0) array per sensor), ``read``
    returns t (0,), q (0, 8), dq (0, 8): no samples, and the widths the engine stacks and slices
    by. Fails when the empty result has a row or another shape."""
    t, q, dq = run["before"]["read"]
    assert t.shape == (0,) and q.shape == (0, 8) and dq.shape == (0, 8)


def test_the_samples_start_at_the_given_state_in_its_own_turns(run, state):
    """Read after the run: one sample per step on t = k h, the first equal to the state the
    build started from, the yaw phi, the rear wheel angle psi and the front wheel angle eps
    included, which lie a whole turn outside (-pi, pi] (``read(mbs, q0)`` shifts each angle
    series by whole turns to start at q0's: its docstring); without q0 the same series comes
    back wrapped (within pi of zero at the start), exactly 2 pi k away. Round-off: the start
    passes through Euler parameters and back (seen 2e-16 on q, 9e-16 on dq), so 1e-12. Fails
    when q0 is not handed to the unwrapping (the angles start wrapped)."""
    q0, dq0 = state
    t, q, dq = run["read"]
    assert q.shape == dq.shape == (STEPS + 1, 8)
    np.testing.assert_allclose(t, H * np.arange(STEPS + 1), rtol=0, atol=1e-12)
    np.testing.assert_allclose(q[0], q0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(dq[0], dq0, rtol=0, atol=1e-12)
    _, q_wrapped, _ = run["wrapped"]
    assert np.abs(q_wrapped[0, 2:]).max() <= np.pi
    turns = (q - q_wrapped)[:, 2:] / TWO_PI
    np.testing.assert_allclose(turns, [[1, 0, 1, 0, 0, -1]] * (STEPS + 1), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(q[:, :2], q_wrapped[:, :2])


def test_hub_height_drift_is_the_rear_hubs_height_error_over_the_run(general_disc, run):
    """``hub_height_drift`` after a read: max over the samples of |z_hub - R_rear cos(theta)|,
    the rear hub's distance from where the rear contact puts it (docs/engines.md: rG2 = rC +
    A_lean [0, 0, R_rear], whose height is R_rear cos(theta)); Exudyn's disc holds that height
    only at velocity level, so it drifts (module docstring). Expected: the same maximum from
    the test's own sensors (the rear wheel body's position and the frame's rotation matrix,
    theta = arcsin A3[2, 1] from A3's third row [-cos(theta) sin(beta), sin(theta),
    cos(theta) cos(beta)]), to 1e-14 m (two round-off readings of a height ~0.3 m); and it is
    an O(h^2) drift, not an offset: below 1e-6 m after 20 steps (seen 4e-9). At a lean of
    0.3 rad and psi = 1 rad, R_rear/cos(theta), R_rear cos(psi) or z_hub + R_rear cos(theta)
    are off by 1e-2 m or more. Fails on a wrong sign, a division, another angle or no value."""
    build, own = run["build"], run["own"]
    drift = build.hub_height_drift
    assert isinstance(drift, float)
    z_hub = own["r2"][:, 3]
    theta = np.arcsin(np.clip(own["A3"][:, 1 + 7], -1.0, 1.0))
    expected = np.abs(z_hub - general_disc.params.R_rear * np.cos(theta)).max()
    assert abs(drift - expected) < 1e-14, (drift, expected)
    assert drift < 1e-6


def test_theta_now_is_the_frames_roll_angle(run, state):
    """``theta_now`` (the engine's per-step fall check) at the initial state: the given lean
    0.3 rad (round-off through Euler parameters: 1e-12); after the run, theta from the test's
    own sensor of the frame at the last step (the same matrix entry: equal to 1e-15). The state
    is steered (gamma = 0.5) and pitched, so the fork's matrix gives another angle (its [2, 1]
    entry is sin(theta) cos(gamma) + cos(theta) sin(beta) sin(gamma): 0.27 rad here). Fails when
    the angle is read from another body."""
    q0, _ = state
    assert abs(run["before"]["theta"] - q0[3]) < 1e-12
    last = run["own"]["A3"][-1, 1 + 7]
    assert abs(run["build"].theta_now(run["mbs"]) - np.arcsin(last)) < 1e-15


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_theta_now_lying_on_its_side_is_plus_or_minus_a_right_angle(general_disc, sign):
    """The bicycle on its side, theta = +-pi/2 exactly, at several yaws and frame pitches: the
    frame's A3[2, 1] = sin(theta) computed by Exudyn from Euler parameters comes out up to
    4e-16 beyond +-1 (seen at phi = 0.3, beta = 0, both signs), where arcsin gives NaN;
    ``theta_now`` must still return +-pi/2 (to 3e-8: arcsin's slope at 1 turns the
    matrix entry's 2e-16 round-off into sqrt(2 * 2.2e-16) = 2.1e-8 rad). Fails when the
    clipping to [-1, 1] loses either bound or widens it."""
    for phi in (0.0, 0.3, 1.0, np.pi / 3):
        for beta in (0.0, 0.1, 0.3):
            q = np.zeros(8)
            q[[2, 3, 5]] = phi, sign * np.pi / 2, beta
            mbs = exu.SystemContainer().AddSystem()
            with quiet():
                build = RedundantBuild(mbs, general_disc.params, q, np.zeros(8))
                mbs.Assemble()
            theta = build.theta_now(mbs)
            assert abs(theta - sign * np.pi / 2) < 3e-8, (phi, beta, theta)


def test_a_run_that_fails_at_its_first_step_reads_back_its_start(general_disc, state):
    """Newton given one iteration to an unreachable 1e-300 tolerance: SolveDynamic raises
    SolverError at the first step, and the sensors hold only the initial sample (Exudyn stores
    it before stepping). ``read`` must return that one sample: t = [0] and the given state (the
    engine then reports the failed run from it), to round-off (1e-12, as above). Fails when a
    one-sample record is taken for an empty one."""
    q0, dq0 = state
    mbs = exu.SystemContainer().AddSystem()
    with quiet():
        build = RedundantBuild(mbs, general_disc.params, q0, dq0)
        build.add_sensors(mbs)
        mbs.Assemble()
        with pytest.raises(exu.SolverError):
            solve(mbs, settings(STEPS, newton_tolerance=1e-300, newton_iterations=1))
    t, q, dq = build.read(mbs, q0)
    np.testing.assert_array_equal(t, [0.0])
    np.testing.assert_allclose(q, [q0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(dq, [dq0], rtol=0, atol=1e-12)


def test_a_run_writes_no_files(run):
    """engines/exudyn/engine.py's docstring: "no solution or sensor files". The run was made in
    an empty working folder with the solution file off (the engine's setting): the build's
    sensors must leave nothing there either, while storing the run internally. Fails when a
    sensor is given a file to write (Exudyn 1.13 writes none for a sensor without a
    ``fileName``, whatever its ``writeToFile`` says, so the flag alone cannot fail here)."""
    assert run["files"] == []
    t, _, _ = run["read"]
    assert t.size == STEPS + 1             # the sensors did store the run, internally
