"""The Drake engine: its terms against the reference (exact, on the three models), the
conventions its plant needs (the welded root, gravity left out of Drake's inverse dynamics, the
coordinate mapping, checked against the reference's body positions), and a short forward run on
Drake's own contact against physical laws and the reference (the conformance suite,
comparisons/conformance, checks the terms on five models and the runs against the reference;
its expected failures are engines/drake/conformance_xfails.txt).

Cost: ~1 s to import pydrake (once per process), a few ms per plant, ~0.1 s for the terms at
20 states on three models, ~0.6 s for the contact run (0.1 s simulated, 200 steps).
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pydrake")

from comparisons.judgments.terms import compare_terms, random_states   # noqa: E402
from comparisons.judgments.convergence import reference_run            # noqa: E402
from comparisons.judgments.tolerances import load_tolerances           # noqa: E402
from comparisons.stages.soft_contact import ideal_normal_forces         # noqa: E402
from engines import CapabilityError, EngineError, EngineUsageError, load_engine   # noqa: E402
from engines.drake import DrakeEngine                                  # noqa: E402
from engines.drake.plant import BODY_LINKS, Mapping, terms_plant       # noqa: E402
from reference_model import COORDINATES, load_model                    # noqa: E402
from reference_model.scenarios import SCENARIOS, initial_state        # noqa: E402

TOLERANCES = load_tolerances()
MODELS = ("thesis", "thesis-disc", "benchmark")


@pytest.fixture(scope="module")
def pairs():
    """(reference, Drake) on each of the three models, built once for the module."""
    out = {}
    for name in MODELS:
        model = load_model(name)
        out[name] = (load_engine("reference", model), DrakeEngine(model))
    return out


@pytest.mark.parametrize("name", MODELS)
def test_every_term_agrees_with_the_reference_at_random_states(pairs, name):
    """M, inverse dynamics, gravity, forces, D, dD dq and the constrained ddq at 20 random
    states (lean to 1.2 rad, steer to 1.55 rad, rates to 30 rad/s) within tolerances.toml's
    round-off tolerances (1e-12 relative for M, gravity and D; 1e-10 for the forces and dD dq;
    1e-9 for ddq): the reference's generated C and Drake's tree algorithms are independent
    formulations of the same equations. (Measured on 200 states: 2.8e-15 at most, ddq 8e-14.)"""
    ref, drk = pairs[name]
    results = compare_terms(ref, drk, random_states(20, seed=7), TOLERANCES)
    assert {r.quantity for r in results} == set(DrakeEngine.capabilities) - {"simulate", "eigenvalues"}
    bad = [r.describe() for r in results if not r.passed]
    assert not bad, bad


@pytest.mark.parametrize("name", MODELS)
def test_the_constraint_residual_away_from_the_constraints_is_the_references(pairs, name):
    """C(q, dq) (height of the front contact point, horizontal velocities of both wheels'
    material points at their contacts) at random states, which violate the constraints: the
    terms above are compared on D and dD dq, which do not show a swapped or repeated row of C
    (it is zero at consistent states). The reference's constraint_residual is its own
    generated code; 1e-12 relative to the largest entry, as for D (round-off of both)."""
    ref, drk = pairs[name]
    st = random_states(20, seed=11)
    mine = np.asarray(drk.constraint_residual(st.q, st.dq))
    theirs = np.asarray(ref.model.constraint_residual(st.q, st.dq)).reshape(mine.shape)
    assert np.abs(theirs).max(axis=0).min() > 1e-3       # every row is away from zero somewhere
    assert np.abs(mine - theirs).max() <= 1e-12 * np.abs(theirs).max()


def test_inverse_dynamics_takes_gravity_out_of_drakes(pairs):
    """Drake's CalcInverseDynamics leaves gravity (a force element) out: at rest with no
    acceleration it returns zero, while the thesis's M ddq - Qv - Qgrav is -Qgrav there, the
    torque that holds the bicycle against gravity. The engine subtracts Drake's tau_g; the
    expected value is the reference's own Qgrav (its generated C), and at a moving state the
    engine's result differs from Drake's raw one by exactly that Qgrav."""
    ref, drk = pairs["thesis-disc"]
    s = random_states(5, seed=3)
    for q, dq, ddq in zip(s.q, s.dq, s.ddq):
        drk._set(q)
        raw_rest = drk.plant.CalcInverseDynamics(drk.context, np.zeros(8), drk._no_forces)
        assert np.abs(raw_rest).max() == 0.0
        Qgrav = ref.gravity(q)
        scale = np.abs(Qgrav).max()
        assert np.abs(drk.inverse_dynamics(q, np.zeros(8), np.zeros(8)) + Qgrav).max() \
            <= 1e-12 * scale
        drk._set(q, dq)
        raw = drk.mapping.v_from_drake(
            drk.plant.CalcInverseDynamics(drk.context, drk.mapping.v_to_drake(ddq),
                                          drk._no_forces))
        assert np.abs(raw - drk.inverse_dynamics(q, dq, ddq) - Qgrav).max() <= 1e-10 * max(
            scale, np.abs(raw).max())


def test_the_urdf_root_is_welded_or_drake_adds_a_free_joint():
    """The export's tree starts at the link 'ground'; Drake floats an unwelded root on a
    6-dof quaternion joint (7 positions, 6 velocities). Welded, the plant has the thesis's 8
    one-dof joints; unwelded the mapping refuses it, naming the sizes."""
    params = load_model("thesis").params
    plant, mapping = terms_plant(params)
    assert (plant.num_positions(), plant.num_velocities()) == (8, 8)
    assert mapping.names == COORDINATES
    with pytest.raises(EngineError, match="nq = 15, nv = 14"):
        terms_plant(params, weld_root=False)


def test_the_coordinate_mapping_puts_the_bodies_where_the_reference_does(pairs):
    """A second route to the mapping than the terms: at random states, set through the
    mapping, Drake's bodies stand where the reference's geometry puts them (its generated
    points: hubs rG2, rG5, CoMs rG3, rG4 from the parameters' offsets in body axes), to
    round-off (positions of order 1 m: 1e-12 m). A mapping with two coordinates swapped
    (planted below) moves them by centimetres or more."""
    ref_model = load_model("benchmark")
    _, drk = pairs["benchmark"]
    p = ref_model.params
    offsets = {2: (0.0, 0.0, 0.0), 3: (p.x3, 0.0, p.z3), 4: None, 5: (0.0, 0.0, 0.0)}
    s = random_states(10, seed=11)
    points = ref_model.points(s.q)

    def worst(mapping):
        err = 0.0
        for i, q in enumerate(s.q):
            drk.plant.SetPositions(drk.context, mapping.q_to_drake(q))
            for b, key in ((2, "rG2"), (3, "rG3"), (5, "rG5")):
                X = drk.plant.EvalBodyPoseInWorld(drk.context,
                                                  drk.plant.GetBodyByName(BODY_LINKS[b]))
                at = X.translation() + X.rotation().matrix() @ np.array(offsets[b])
                err = max(err, np.abs(at - points[key][i]).max())
        return err

    assert worst(drk.mapping) <= 1e-12
    swapped = list(drk.mapping.q_index)
    swapped[COORDINATES.index("theta")], swapped[COORDINATES.index("phi")] = \
        swapped[COORDINATES.index("phi")], swapped[COORDINATES.index("theta")]
    assert worst(Mapping(COORDINATES, tuple(swapped), drk.mapping.v_index)) > 1e-2


def test_thesis_contact_has_terms_but_no_forward_runs(pairs):
    _, drk = pairs["thesis"]
    assert "simulate" not in drk.capabilities
    with pytest.raises(CapabilityError, match="cannot simulate model 'thesis'.*use a disc-contact"):
        drk.simulate(SCENARIOS["check-forward"])


@pytest.mark.parametrize("options, field", [
    ({"approximation": "sapp"}, "approximation"), ({"time_step": -1e-3}, "time_step"),
    ({"contact_model": "soft"}, "contact_model"), ({"stiction_tolerance": "x"}, "stiction_tolerance"),
])
def test_a_bad_option_is_a_one_line_usage_error_naming_it(options, field):
    with pytest.raises(EngineUsageError) as info:
        DrakeEngine(load_model("thesis-disc"), **options)
    text = str(info.value)
    assert field in text and "fix:" in text and "\n" not in text


def test_a_step_that_misses_the_output_grid_is_refused(pairs):
    _, drk = pairs["thesis-disc"]
    with pytest.raises(EngineUsageError, match="time_step = 0.003 s must divide"):
        drk.simulate(SCENARIOS["stability-psid10"], t_end=0.05, time_step=3e-3)


def test_a_short_contact_run_carries_the_weight_and_stays_near_the_reference(pairs):
    """stability-psid10 on thesis-disc for 0.1 s (200 steps) at the defaults, against physical
    laws and the reference:

    * the ground carries the bicycle as ideal rolling needs: each wheel's normal force is the
      one the reference's ideal rolling needs along its own run (`soft_contact.
      ideal_normal_forces`: the front from its constraint multiplier, the rear from the
      vertical balance of the four bodies by central differences), within 0.5 % of the
      weight sum m_i g (measured 0.1 N of 827 N: the soft contact's departures are of the order
      of the slip and the sink). The run starts with the wheels just touching, so the springs
      (1e8 N/m, the static sink 5.5e-6 m) settle first: samples from 0.02 s on;
    * the wheels sink by about the static load over the stiffness (at most 2e-5 m: 1e-3 of the
      wheel radius would already change the rolling radius visibly) and slip by at most
      5e-3 m/s (measured ~1e-3: the slip is first order in the step, ~2 x h m/s per s);
    * the run stays within 1e-3 (rad or m) of the reference up to 0.1 s (measured 1.4e-4: a slip
      of 1e-3 m/s for 0.1 s moves a contact by 1e-4 m; 1e-3 is ten times that, well below the
      0.05 of [trajectory_conformance]).

    Planted: the wheels' cylinders left on Drake's cylinder axis (z) instead of turned onto the
    axle (y): each wheel lies flat and the run fails (TAMSI does not converge at 0.0965 s)."""
    model = load_model("thesis-disc")
    _, drk = pairs["thesis-disc"]
    sc = SCENARIOS["stability-psid10"]
    traj = drk.simulate(sc, t_end=0.1)
    assert traj.status == "completed", traj.message
    ref = reference_run(model, sc, t_end=0.2)   # past the run: interior differences below
    n = traj.t.size
    assert np.allclose(traj.t, ref.t[:n])
    p = model.params
    weight = p.g * (p.m2 + p.m3 + p.m4 + p.m5)
    D = traj.diagnostics
    settled = traj.t >= 0.02
    rear, front = ideal_normal_forces(model, ref)
    for got, ideal in ((D["normal_force_rear"], rear), (D["normal_force_front"], front)):
        assert np.abs(got[settled] - ideal[:n][settled]).max() <= 5e-3 * weight
    assert max(D["penetration_rear"].max(), D["penetration_front"].max()) <= 2e-5
    assert max(D["slip_speed_rear"].max(), D["slip_speed_front"].max()) <= 5e-3
    assert np.abs(traj.q - ref.q[:n]).max() <= 1e-3
    assert np.allclose(traj.q[0], initial_state(model, sc).q)
    assert set(D) == {"slip_speed_rear", "slip_speed_front", "penetration_rear",
                      "penetration_front", "normal_force_rear", "normal_force_front"}
    assert traj.settings["approximation"] == "tamsi" and traj.settings["time_step"] == 5e-4


def test_the_declared_conformance_failures_are_trajectory_checks_with_their_reason():
    """Only forward runs may be declared (the terms are exact), each with its reason."""
    from comparisons.conformance.plugin import read_xfails
    xfails = read_xfails(DrakeEngine.conformance_xfails)
    assert xfails
    for check, reason in xfails.items():
        assert check.startswith("test_trajectory_to_the_meaningful_horizon[{engine}-"), check
        assert reason.startswith("soft contact, a declared model difference"), reason


def test_the_facts_declare_a_soft_contact_study():
    """The soft-contact study reads these facts: a run difference, refinements of the step
    and the stiction tolerance, the label and colour."""
    from engines.facts import engine_facts
    f = engine_facts("engines.drake:DrakeEngine")
    assert f.label == "Drake" and f.colour == "tab:green"
    assert f.run_difference.startswith("soft contact")
    params = [r.parameter for r in f.soft_contact.refinements]
    assert params[0] == "time step [s]" and "stiction tolerance [m/s]" in params
    assert dataclasses.is_dataclass(f.soft_contact)


def test_a_body_that_breaks_the_triangle_inequality_is_declared_beyond_drake(tmp_path):
    """Drake's URDF parser does not refuse a body whose principal moments break A + B >= C: it
    warns and builds another (on BicycleParameters' Browser, frame and rider 2.33 % over, M came
    out 6.8e-2 from the reference and the measured-bicycles run failed). The engine declares
    such a bicycle beyond it (`UnsupportedModel`: 'not run on this model', never a failure).
    Independent check of the premise: numpy's eigenvalues of the body's tensor. Planted: the
    check removed, the engine builds and its M is wrong by 1e-2 or more."""
    from comparisons.cli import main
    from engines import UnsupportedModel
    data = Path(__file__).resolve().parent / "data" / "benchmark" / "TriangleBenchmark.txt"
    out = tmp_path / "tri.toml"
    assert main(["import", str(data), "--from", "benchmark", "--out", str(out),
                 "--allow-triangle-violation"]) == 0
    model = load_model(str(out))
    broken = []
    for b in (2, 3, 4, 5):
        xz = getattr(model.params, f"I{b}xz", 0.0)
        m = np.sort(np.linalg.eigvalsh(np.array(
            [[getattr(model.params, f"I{b}xx"), 0, xz], [0, getattr(model.params, f"I{b}yy"), 0],
             [xz, 0, getattr(model.params, f"I{b}zz")]])))
        broken += [b] if m[0] + m[1] < m[2] else []
    assert broken, "the data file no longer breaks the inequality"
    with pytest.raises(UnsupportedModel, match=rf"body {broken[0]} breaks it"):
        load_engine("drake", model)
    load_engine("drake", load_model("benchmark"))      # the control: a physical bicycle builds


def _inertias(**changed):
    """Every body's tensor entries (physical: the benchmark's), some changed."""
    from types import SimpleNamespace
    p = load_model("benchmark").params
    names = [f"I{b}{k}" for b in (2, 3, 4, 5) for k in ("xx", "yy", "zz", "xz")]
    return SimpleNamespace(**{**{n: getattr(p, n, 0.0) for n in names}, **changed})


@pytest.mark.parametrize("body", (2, 3, 4, 5))
def test_each_body_is_checked_for_the_triangle_inequality(body):
    """Moments 1, 1 and 2.5 kg m^2 about the body's axes break A + B >= C by 0.5 (no product
    of inertia): whichever body has them, the engine's check names it."""
    from engines import UnsupportedModel
    from engines.drake.plant import refuse_non_physical_inertia
    refuse_non_physical_inertia(_inertias())                  # the benchmark itself passes
    bad = _inertias(**{f"I{body}xx": 1.0, f"I{body}yy": 2.5, f"I{body}zz": 1.0, f"I{body}xz": 0.0})
    with pytest.raises(UnsupportedModel, match=rf"body {body} breaks it \(principal moments "
                                               r"1, 1, 2\.5 kg m\^2\)"):
        refuse_non_physical_inertia(bad)


def test_a_product_of_inertia_alone_can_break_the_triangle_inequality():
    """Ixx = Izz = 1, Iyy = 0.3 kg m^2 is physical with Ixz = 0 (0.3 + 1 >= 1); Ixz = 0.8 turns
    the x-z block's moments into 1 -+ 0.8 = 0.2 and 1.8: 0.2 + 0.3 < 1.8."""
    from engines import UnsupportedModel
    from engines.drake.plant import refuse_non_physical_inertia
    refuse_non_physical_inertia(_inertias(I3xx=1.0, I3yy=0.3, I3zz=1.0, I3xz=0.0))
    with pytest.raises(UnsupportedModel, match=r"body 3 breaks it \(principal moments 0\.2, "
                                               r"0\.3, 1\.8 kg m\^2\)"):
        refuse_non_physical_inertia(_inertias(I3xx=1.0, I3yy=0.3, I3zz=1.0, I3xz=0.8))


def test_the_run_urdf_frees_the_rear_contact_height_and_drops_the_nominal_wheels():
    """The contact run's URDF, read back with the standard library's XML parser: phi hangs
    from a new massless zc_link, which a prismatic z joint (effectively unlimited, no effort)
    hangs from yc_link; no collision element is left (the run adds its own wheels); and, as in
    any URDF, no element holds character data. Everything else is the export's."""
    import xml.etree.ElementTree as ET

    from engines.drake.plant import run_urdf_text
    from run_urdf_checks import assert_rear_height_freed
    from reference_model.exports.urdf import urdf_text
    params = load_model("thesis-disc").params
    robot = ET.fromstring(run_urdf_text(params))
    export = ET.fromstring(urdf_text(params))
    assert_rear_height_freed(robot, export)
    assert float(robot.find("joint[@name='zc']/limit").get("effort")) == 0.0
    assert not list(robot.iter("collision")) and list(export.iter("collision"))
    for el in robot.iter():
        assert not (el.text or "").strip() and not (el.tail or "").strip(), el.tag


def test_an_export_whose_phi_joint_moved_is_refused_in_one_line(monkeypatch):
    import engines.drake.plant as plant
    from engines import EngineError
    text = plant.urdf_text(load_model("thesis-disc").params)
    monkeypatch.setattr(plant, "urdf_text", lambda p: text.replace(
        '<joint name="phi" type="continuous">\n    <parent link="yc_link"/>',
        '<joint name="phi" type="continuous">\n    <parent link="ground"/>'))
    assert plant.urdf_text(None) != text, "the export's phi joint changed: update this test"
    with pytest.raises(EngineError) as err:
        plant.run_urdf_text(None)
    assert str(err.value) == "the URDF export's phi joint does not hang from yc_link as expected"
