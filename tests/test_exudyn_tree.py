"""The minimal-coordinate Exudyn build (engines/exudyn/tree.py) taken apart: what it puts into
Exudyn's system (the kinematic tree's markers, the rolling discs, the thesis contact's two
coordinate constraints), the thesis contact's user functions as Exudyn calls them, their cache
and call count, the self-check ``jacobian_check``, the read-back of a run, and the mass-matrix
helper ``TreeMassMatrix``'s guards and silence.

The engine's runs and terms (tests/test_exudyn.py) check the build end to end against the
reference; here each piece is checked where a run or a term cannot see it: a marker's absolute
position (the whole bicycle lifted by a constant leaves M, the forces and every run unchanged),
the contact rows at the upright straight states where the contact points line up with the
global axes to the last bit, the velocity-level branch only an index-2 solver asks for, the
counters and the cache, a read before any step or after a run that failed at its first step,
and the files and console output.

Expected values: the reference model's own points, residuals and constraint Jacobian
(``Model.points``, ``constraint_residual``, ``constraint_jacobian``: written independently of
the tree's joint screws), the body rotations written here from docs/engines.md ("Orientation
and geometry"), the given state, and Exudyn's own API read back (its marker, node and object
outputs). The bicycle is the general bicycle (tests/conftest.py: unequal wheels, a fork CoM off
the steering axis, every inertia entry distinct) with the thesis's fork-axis front contact, so
that the user constraints are in the build and a marker on the wrong link cannot hide behind
thesis-disc's symmetries; the default (disc) build uses the general disc bicycle.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

exu = pytest.importorskip("exudyn")

from engines import load_engine  # noqa: E402
from engines.exudyn.engine import quiet  # noqa: E402
from exudyn_checks import H, random_states, rotations, settings, solve  # noqa: E402
from engines.exudyn.tree import ThesisFrontContact, TreeBuild, TreeMassMatrix  # noqa: E402
from reference_model.solvers import consistent_state  # noqa: E402

STEPS = 20               # 0.02 s: enough samples for the read-back checks, milliseconds to run
#: xc, yc, phi, theta, psi, beta (solved), gamma, eps: leaned 0.3 rad, steered 0.5 rad
Q_GIVEN = (0.4, -0.3, 0.5, 0.3, 1.0, 0.0, 0.5, -0.7)
#: the independent rates theta', psi', gamma' (rad/s): rolling forward at ~1.6 m/s
DQ_IND = (0.2, 5.0, -0.3)
#: the rows of the reference's D (and C) that the thesis contact's user functions give:
#: 0 the height [rD]_z, 3 and 4 the front wheel's horizontal contact velocity
HEIGHT, FRONT = 0, [3, 4]
#: round-off between two exact formulations of the same rows (test_exudyn.py's figure)
ROUND_OFF = 1e-12


@pytest.fixture(scope="module")
def state(general):
    """The given state projected onto the thesis-contact bicycle's constraints by the
    reference."""
    dq = np.zeros(8)
    dq[[3, 4, 6]] = DQ_IND
    cs = consistent_state(general, np.array(Q_GIVEN), dq)
    assert abs(cs.q[5]) > 1e-3            # a pitched frame: A3 differs from A_lean
    return cs.q, cs.dq


@pytest.fixture(scope="module")
def run(general, state, tmp_path_factory):
    """One thesis-contact build, Exudyn's outputs before the run, STEPS steps of
    generalized-alpha in an empty working folder, and the read-back."""
    q0, dq0 = state
    folder = tmp_path_factory.mktemp("exudyn-tree-run")
    here = os.getcwd()
    os.chdir(folder)
    try:
        with quiet():
            SC = exu.SystemContainer()
            mbs = SC.AddSystem()
            build = TreeBuild(mbs, general.params, q0, dq0, contact="thesis")
            build.add_sensors(mbs)
            mbs.Assemble()
            before = build.read(mbs, q0)
            solve(mbs, settings(STEPS))
            after = build.read(mbs, q0)
        files = sorted(p.name for p in folder.rglob("*"))
    finally:
        os.chdir(here)
    return {"SC": SC, "mbs": mbs, "build": build, "before": before, "read": after,
            "files": files}


@pytest.fixture(scope="module")
def disc_build(general_disc, state):
    """The build with the default front contact (no ``contact`` argument), assembled."""
    q0, dq0 = state
    with quiet():
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        build = TreeBuild(mbs, general_disc.params, q0, dq0)
        mbs.Assemble()
    return {"SC": SC, "mbs": mbs, "build": build}


# -- what the build puts into Exudyn's system ------------------------------------------------

def test_the_default_contact_is_the_disc_on_both_wheels_and_an_unknown_one_is_refused(
        general_disc, disc_build, state):
    """Built without a ``contact`` argument the build is the rolling-disc one (module
    docstring): ``contact == 'disc'``, no user constraints, and two ObjectJointRollingDisc read
    back from Exudyn: the rear one (radius R_rear) with constrainedAxes [1, 1, 0] (its height
    row is identically satisfied by the tree), the front one (R_front) with all three, both on
    the ground marker and the wheel's marker, axle along the body y. Asked for a contact it
    does not know, it refuses with one line naming it. Expected: the module docstring, the
    general disc bicycle's radii (0.34 m and 0.30 m: unequal, so swapped discs show). Fails
    when the default is not 'disc' (every default build refused), a disc sits on the wrong
    wheel or radius, or the refusal loses its message."""
    mbs, build = disc_build["mbs"], disc_build["build"]
    p = general_disc.params
    assert build.contact == "disc" and build.user_contact is None
    for obj, marker, radius, axes in ((build.rear_disc, "rear", p.R_rear, [1, 1, 0]),
                                      (build.front_disc, "front", p.R_front, [1, 1, 1])):
        disc = mbs.GetObject(obj)
        assert disc["objectType"] == "JointRollingDisc"
        assert [int(m) for m in disc["markerNumbers"]] == [int(build.markers["ground"]),
                                                           int(build.markers[marker])]
        assert list(disc["constrainedAxes"]) == axes, marker
        assert disc["discRadius"] == radius
        np.testing.assert_array_equal(disc["discAxis"], [0.0, 1.0, 0.0])
    with pytest.raises(ValueError) as err:
        TreeBuild(exu.SystemContainer().AddSystem(), p, *state, contact="flat")
    assert str(err.value) == "unknown front contact 'flat'"


def test_the_thesis_contact_is_a_position_and_a_velocity_level_coordinate_constraint(run):
    """The ``thesis`` contact (module docstring): no front disc, but two
    ObjectConnectorCoordinateVector on the tree's node, the first at position level with one
    row (the height [rD]_z), the second at velocity level with two (vD_x, vD_y), each with the
    ``ThesisFrontContact`` user functions; the rear disc as in the disc build. Read back from
    Exudyn's objects. Fails when the levels are swapped or dropped (a velocity-level height
    would let the height drift as in Exudyn's disc), a row count is wrong, or the functions are
    not the build's."""
    mbs, build = run["mbs"], run["build"]
    uc = build.user_contact
    assert build.contact == "thesis" and isinstance(uc, ThesisFrontContact)
    assert not hasattr(build, "front_disc")
    assert list(mbs.GetObject(build.rear_disc)["constrainedAxes"]) == [1, 1, 0]
    connectors = [mbs.GetObject(k) for k in range(mbs.systemData.NumberOfObjects())
                  if mbs.GetObject(k)["objectType"] == "ConnectorCoordinateVector"]
    assert [c["velocityLevel"] for c in connectors] == [False, True]
    assert [np.shape(c["scalingMarker0"]) for c in connectors] == [(1, 8), (2, 8)]
    assert [c["constraintUserFunction"]["function"] for c in connectors] == [uc.height,
                                                                            uc.velocity]
    assert [c["jacobianUserFunction"]["function"] for c in connectors] == [uc.height_jacobian,
                                                                          uc.velocity_jacobian]


def test_markers_are_the_joint_origins_in_body_axes_and_the_ground_origin(general, run, state):
    """The class docstring's markers: 'rear' and 'frame' at their joint origin, the rear hub
    rG2; 'fork' at the steering-axis point rA; 'front' at the front hub rG5; 'frame_com' at the
    frame's CoM rG3; each in its body's axes (A2, A3, A4, A5, A3); 'ground' at the global
    origin, on the ground plane z = 0. Expected: the reference's points (``Model.points``) and
    the rotations of docs/engines.md, against Exudyn's marker outputs at the initial state.
    Round-off only (Exudyn composes the same rotations and offsets): 1e-12. Fails when a key
    points at another link, a marker sits off its point, or the tree's base is offset (a
    constant lift of the whole bicycle changes no mass matrix, force or run, only where the
    markers are: where a position-dependent load would act)."""
    mbs, build = run["mbs"], run["build"]
    q0, _ = state
    pts, A = general.points(q0), rotations(q0)
    ovt = exu.OutputVariableType
    expected = {"rear": (pts["rG2"], A[2]), "frame": (pts["rG2"], A[3]), "fork": (pts["rA"], A[4]),
                "front": (pts["rG5"], A[5]), "frame_com": (pts["rG3"], A[3])}
    assert set(build.markers) == set(expected) | {"ground"}
    for key, (point, rotation) in expected.items():
        m = build.markers[key]
        assert int(mbs.GetMarker(m)["objectNumber"]) == int(build.tree), key
        r = mbs.GetMarkerOutput(m, ovt.Position, configuration=exu.ConfigurationType.Initial)
        R = mbs.GetMarkerOutput(m, ovt.RotationMatrix, configuration=exu.ConfigurationType.Initial)
        np.testing.assert_allclose(r, point, rtol=0, atol=1e-12, err_msg=key)
        np.testing.assert_allclose(np.reshape(R, (3, 3)), rotation, rtol=0, atol=1e-12,
                                   err_msg=key)
    ground = mbs.GetMarkerOutput(build.markers["ground"], ovt.Position)
    np.testing.assert_allclose(ground, [0.0, 0.0, 0.0], rtol=0, atol=0)


# -- the thesis contact's user functions -------------------------------------------------------

def test_the_contact_rows_on_upright_straight_states_along_the_axes_are_the_references(general):
    """The height and the rows of D for [rD]_z, vD_x, vD_y at the upright straight states:
    heading along x (phi = 0: the linearisation point, where the front contact's y equals the
    rear contact's to the last bit) and heading along y (phi = pi/2 at xc = 3 m: the
    x-offset of the front contact, a few 1e-17 m from cos(pi/2), vanishes against xc in
    floating point, so the contact points' x are equal to the last bit). Expected: the
    reference's residual and constraint Jacobian (an independent formulation), to round-off
    (1e-12). Fails when a joint-screw column divides where it multiplies (0/0 raises there)
    or takes the wrong component of the contact arm."""
    uc = ThesisFrontContact(general.params)
    for phi, xc, yc in ((0.0, 2.0, -1.5), (np.pi / 2, 3.0, -2.0)):
        q = np.array([xc, yc, phi, 0.0, 0.7, 0.0, 0.0, 0.3])
        q = consistent_state(general, q, np.zeros(8)).q          # the upright pitch beta
        h, J_height, J_velocity, J_1x8 = uc._rows(list(q))
        D = general.constraint_jacobian(q)
        assert abs(h - general.constraint_residual(q, np.zeros(8))[HEIGHT]) < ROUND_OFF
        np.testing.assert_allclose(J_height, D[HEIGHT], rtol=0, atol=ROUND_OFF)
        np.testing.assert_allclose(J_1x8, D[[HEIGHT]], rtol=0, atol=ROUND_OFF)
        np.testing.assert_allclose(J_velocity, D[FRONT], rtol=0, atol=ROUND_OFF)


def test_the_user_functions_give_the_reference_rows_in_exudyns_calling_convention(general):
    """The four user functions called as Exudyn calls them ((mbs, t, itemNumber, q, q_t,
    velocityLevel), q and q_t as lists of floats), at states off the constraints (so nothing is
    zero by consistency): ``height`` gives [rD_z] at position level and its time derivative
    [D_0 dq] at velocity level (what an index-2 solver asks: the class docstring), one float
    in a list; ``height_jacobian`` the 1 x 8 row D_0; ``velocity`` the two contact velocities
    [vD_x, vD_y] = D_{3,4} dq; ``velocity_jacobian`` the 2 x 8 rows D_{3,4}. Expected: the
    reference's ``constraint_residual`` and ``constraint_jacobian``, to round-off (1e-12
    relative to the rows' size; dq up to 20 rad/s makes the velocities ~10 m/s). Fails when
    the velocity-level branch returns the height or drops q_t, or a row or shape is wrong."""
    uc = ThesisFrontContact(general.params)
    qs, dqs, _ = random_states(10, seed=31)
    for q, dq in zip(qs, dqs):
        D = general.constraint_jacobian(q)
        C = general.constraint_residual(q, dq)
        args = (None, 0.0, 0, list(q), list(dq))
        position, rate = uc.height(*args, False), uc.height(*args, True)
        assert len(position) == len(rate) == 1 and isinstance(rate[0], float)
        assert abs(position[0] - C[HEIGHT]) < ROUND_OFF
        scale = max(1.0, abs(D[HEIGHT] @ dq))
        assert abs(rate[0] - D[HEIGHT] @ dq) < ROUND_OFF * scale
        J = uc.height_jacobian(*args, False)
        assert np.shape(J) == (1, 8)
        np.testing.assert_allclose(J, D[[HEIGHT]], rtol=0, atol=ROUND_OFF)
        v = uc.velocity(*args, True)
        assert len(v) == 2
        np.testing.assert_allclose(v, C[FRONT], rtol=0, atol=ROUND_OFF * max(1.0, *np.abs(C)))
        np.testing.assert_allclose(uc.velocity_jacobian(*args, True), D[FRONT], rtol=0,
                                   atol=ROUND_OFF)


def test_an_index2_run_asks_the_heights_time_derivative_and_holds_the_height(
        general, state, monkeypatch):
    """``TrapezoidalIndex2`` (the engine's 'trapezoidal' solver) asks every constraint at
    velocity level: the height function is called only with velocityLevel=True (class
    docstring: "index-2 solvers ask for the time derivative"), and the run must still hold the
    contact: over 20 steps the reference's residual on the read states stays at the
    velocity rows' Newton tolerance (1e-10, seen 7e-12) and the height, held through its
    derivative only, drifts by the scheme's local error (seen 9e-10; bound 1e-7, while a
    height left free falls ~g t^2 / 2 = 2e-3 m in 0.02 s). Expected: the reference's
    ``constraint_residual``. Fails when the velocity-level branch returns the height instead of
    its derivative, or is never reached."""
    q0, dq0 = state
    levels = []
    height = ThesisFrontContact.height

    def recording(self, mbs, t, itemNumber, q, q_t, velocityLevel):
        levels.append(bool(velocityLevel))
        return height(self, mbs, t, itemNumber, q, q_t, velocityLevel)

    monkeypatch.setattr(ThesisFrontContact, "height", recording)
    with quiet():
        mbs = exu.SystemContainer().AddSystem()
        build = TreeBuild(mbs, general.params, q0, dq0, contact="thesis")
        build.add_sensors(mbs)
        mbs.Assemble()
        solve(mbs, settings(STEPS), solver="TrapezoidalIndex2")
    assert levels and all(levels)
    t, q, dq = build.read(mbs, q0)
    assert t.size == STEPS + 1
    C = general.constraint_residual(q, dq)
    assert np.abs(C[:, 1:]).max() < 1e-9
    assert np.abs(C[:, HEIGHT]).max() < 1e-7


def test_calls_counts_every_evaluation_and_the_last_q_is_cached(general):
    """``calls`` (the engine's timing 'user_constraint_calls') starts at 0 and counts each
    user-function evaluation, cached or not: four functions called once each at one q make 4,
    three more evaluations at that q 7, two more (another q, then the first again) 9. The
    last q is cached (class docstring: Exudyn calls the
    four functions several times per Newton iteration at the same q): at the same q, given as
    a list as Exudyn passes it or as an array, the same row objects come back (no
    recomputation); another q gives that q's rows (the reference's, to round-off), and the
    first q again its own. Fails when the count starts at 1, steps by 2 or backwards, is reset
    instead of incremented, or the cache is never filled (every call recomputes)."""
    uc = ThesisFrontContact(general.params)
    assert uc.calls == 0
    (qa, qb), (dqa, _), _ = random_states(2, seed=32)
    a = (None, 0.0, 0, list(qa), list(dqa))
    J_height = uc.height_jacobian(*a, False)
    J_velocity = uc.velocity_jacobian(*a, False)
    uc.height(*a, False)
    uc.velocity(*a, False)
    assert uc.calls == 4
    assert uc.height_jacobian(*a, False) is J_height
    assert uc._rows(np.array(qa)) is uc._rows(list(qa))
    assert uc.calls == 7
    np.testing.assert_allclose(uc.velocity_jacobian(None, 0.0, 0, list(qb), None, False),
                               general.constraint_jacobian(qb)[FRONT], rtol=0, atol=ROUND_OFF)
    np.testing.assert_allclose(uc.velocity_jacobian(*a, False), J_velocity, rtol=0, atol=0)
    assert uc.calls == 9


def test_jacobian_check_reports_each_rows_difference(general):
    """``jacobian_check`` (max |difference| between the joint-screw rows and the ones from
    ``mapping.body_states``): round-off on the real rows (1e-12), and, with the rows replaced
    by planted copies that differ in one place only, that difference: 1e-6 on the height, 2e-6
    on one entry of the height row, 3e-6 on one entry of a velocity row, each reported to
    round-off. Expected: the planted amounts. Fails when the check leaves the height, the
    height row or the velocity rows out of its maximum (a wrong row would then pass)."""
    uc = ThesisFrontContact(general.params)
    q = random_states(1, seed=33)[0][0]
    assert uc.jacobian_check(q) < ROUND_OFF
    h, J_height, J_velocity, J_1x8 = (np.copy(x) for x in uc._rows(q))
    e_gamma = np.eye(8)[6]
    for planted, delta in (((h + 1e-6, J_height, J_velocity), 1e-6),
                           ((h, J_height + 2e-6 * e_gamma, J_velocity), 2e-6),
                           ((h, J_height, J_velocity + 3e-6 * np.outer([0, 1], e_gamma)), 3e-6)):
        uc._rows = lambda q, planted=planted: (*planted, J_1x8)
        assert abs(uc.jacobian_check(q) - delta) < ROUND_OFF, delta


# -- the read-back -------------------------------------------------------------------------------

def test_a_read_before_any_step_is_empty_with_the_documented_widths(run):
    """Before the solver has stored anything (Exudyn gives a (0, 0) array per sensor), ``read``
    returns t (0,), q (0, 8), dq (0, 8): no samples, and the widths the engine stacks and
    slices by. Fails when the empty result has a row or another shape."""
    t, q, dq = run["before"]
    assert t.shape == (0,) and q.shape == (0, 8) and dq.shape == (0, 8)


def test_the_samples_start_at_the_given_state_and_end_at_exudyns_coordinates(general, run, state):
    """Read after the run: one sample per step on t = k h; the tree's coordinates are q, dq
    directly (the class docstring), so the first sample is the given state exactly and the
    last one Exudyn's current node coordinates and velocities (read back through
    ``GetNodeOutput``), exactly; on every sample the thesis contact holds: the reference's
    residual stays at the Newton tolerance (1e-10; seen 7e-12), a bound 1e-9. Fails when the
    time column is taken for a coordinate, q and dq are swapped, or a sample is dropped."""
    q0, dq0 = state
    mbs, build = run["mbs"], run["build"]
    t, q, dq = run["read"]
    assert q.shape == dq.shape == (STEPS + 1, 8)
    np.testing.assert_allclose(t, H * np.arange(STEPS + 1), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(q[0], q0)
    np.testing.assert_array_equal(dq[0], dq0)
    ovt = exu.OutputVariableType
    np.testing.assert_array_equal(q[-1], mbs.GetNodeOutput(build.node, ovt.Coordinates))
    np.testing.assert_array_equal(dq[-1], mbs.GetNodeOutput(build.node, ovt.Coordinates_t))
    assert np.abs(general.constraint_residual(q, dq)).max() < 1e-9


def test_a_run_that_fails_at_its_first_step_reads_back_its_start(general, state):
    """Newton given one iteration to an unreachable 1e-300 tolerance: SolveDynamic raises
    SolverError at the first step, and the sensors hold only the initial sample (Exudyn stores
    it before stepping). ``read`` must return that one sample: t = [0] and the given state
    exactly (the engine then reports the failed run from it). Fails when a one-sample record is
    taken for an empty one."""
    q0, dq0 = state
    mbs = exu.SystemContainer().AddSystem()
    with quiet():
        build = TreeBuild(mbs, general.params, q0, dq0, contact="thesis")
        build.add_sensors(mbs)
        mbs.Assemble()
        with pytest.raises(exu.SolverError):
            solve(mbs, settings(STEPS, newton_tolerance=1e-300, newton_iterations=1))
    t, q, dq = build.read(mbs, q0)
    np.testing.assert_array_equal(t, [0.0])
    np.testing.assert_array_equal(q, [q0])
    np.testing.assert_array_equal(dq, [dq0])


def test_a_run_writes_no_files(run):
    """engines/exudyn/engine.py's docstring: "no solution or sensor files". The run was made in
    an empty working folder with the solution file off (the engine's setting): the build's
    sensors must leave nothing there either, while storing the run internally. Fails when a
    sensor is given a file to write (Exudyn 1.13 writes none for a sensor without a
    ``fileName``, whatever its ``writeToFile`` says, so the flag alone cannot fail here)."""
    assert run["files"] == []
    t, _, _ = run["read"]
    assert t.size == STEPS + 1             # the sensors did store the run, internally


# -- the mass matrix helper -----------------------------------------------------------------------

def test_the_mass_matrix_refuses_a_state_of_the_wrong_shape_with_the_shape(general):
    """``TreeMassMatrix`` takes one state q (8,); anything else is refused before it reaches
    Exudyn (whose SetODE2Coordinates may crash on a wrong size: its own docstring) with one
    line giving the expected and the given shape, also through the engine's ``mass_matrix``
    (which hands it a 1-D q as given, and adds where it was called on a second line). Expected:
    the shapes given. Fails when the check is lost or its message is."""
    with quiet():
        tm = TreeMassMatrix(general.params)
    for bad in (np.zeros(7), np.zeros((1, 8)), np.zeros(9)):
        with pytest.raises(ValueError) as err:
            tm(bad)
        assert str(err.value) == f"q must have shape (8,); got {bad.shape}"
    eng = load_engine("exudyn", general, build="tree")
    with pytest.raises(ValueError) as err:
        eng.mass_matrix(np.zeros(7))
    assert str(err.value).splitlines()[0] == "q must have shape (8,); got (7,)"


def test_the_mass_matrix_helper_writes_no_file_and_prints_nothing(general, tmp_path, monkeypatch,
                                                                  capfd):
    """Built and evaluated outside the engine's ``quiet()`` in an empty working folder,
    ``TreeMassMatrix`` leaves no file (Exudyn's static solver, initialised with the solution
    file on, writes solution/coordinatesSolution.txt) and writes nothing to the console (with
    its verbose mode above 0 it prints its banner): engines/exudyn/engine.py's docstring,
    "verbose modes 0; no solution or sensor files". And it still gives the reference's M
    (round-off, 1e-12 relative, as tests/test_exudyn.py). Fails when the solution file or the
    static solver's verbosity is switched on."""
    monkeypatch.chdir(tmp_path)
    capfd.readouterr()
    q = random_states(1, seed=34)[0][0]
    M = TreeMassMatrix(general.params)(q)
    out, err = capfd.readouterr()
    assert (out, err) == ("", "")
    assert sorted(p.name for p in tmp_path.rglob("*")) == []
    M_ref = general.mass_matrix(q)
    assert np.abs(M - M_ref).max() < 1e-12 * np.abs(M_ref).max()
