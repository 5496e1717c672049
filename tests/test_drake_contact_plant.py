"""Drake's plant of a contact run (engines/drake/contact_plant.py), read back from Drake itself
and held to physics: every run setting reaches the built MultibodyPlant and its SceneGraph
(the step, the contact model and solver; each wheel's cylinder, the ground's half-space and
the proximity properties on both: friction, point stiffness and dissipation, or the
hydroelastic compliance), the ground carries a bicycle standing still with each wheel sunk by
its load over the pair's stiffness, the hydroelastic wheels are the soft side of their contact
and the ground the rigid one, and Drake's warnings during the build are kept out of the run's
output. Expected values come from the options' documentation (docs/engines.md, Drake section,
and engines/drake/options.py), from Drake's own API (SceneGraphInspector, QueryObject, its
friction combination) and from statics; never from the module's output. Each test names the
planted bugs (mutmut's survivors of the module's first measurement) it fails on.

Cost: ~1 s to import pydrake (once per process; shared with tests/test_drake.py), a few ms per
plant (five built here), ~10 ms for the 100 steps of the standing bicycle.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from reference_model import load_model
from reference_model.solvers import consistent_state

pytest.importorskip("pydrake")

from pydrake.geometry import Cylinder, HalfSpace, HydroelasticContactRepresentation  # noqa: E402
from pydrake.multibody.plant import (CalcContactFrictionFromSurfaceProperties,  # noqa: E402
                                     ContactModel, DiscreteContactApproximation)

import engines.drake.contact_plant as contact_plant  # noqa: E402
from engines.drake.contact_plant import RUN_COORDINATES, build_run_plant  # noqa: E402
from engines.drake.options import RunSettings  # noqa: E402
from standing import static_split  # noqa: E402

#: point contact with every option away from its default (options.py) and from Drake's own
#: defaults (SceneGraphConfig().default_proximity_properties: friction 0.5, point stiffness
#: 1e6 N/m, Hunt-Crossley dissipation 50 s/m), so a setting dropped on the way to Drake's
#: plant shows as Drake's default or ours
POINT = RunSettings(time_step=1e-3, approximation="sap", contact_model="point",
                    stiction_tolerance=1e-3, friction=0.8, point_stiffness=4e7, dissipation=3.0,
                    wheel_half_width=1e-3)
#: hydroelastic contact, the same way (Drake's default modulus is 1e7 Pa, its resolution hint
#: 0.02 m)
HYDRO = RunSettings(time_step=2.5e-4, approximation="similar", contact_model="hydroelastic",
                    friction=0.6, dissipation=7.0, hydroelastic_modulus=3e8,
                    wheel_half_width=2e-3)
#: docs/engines.md's table of the options' defaults, typed from it
DOCUMENTED_DEFAULTS = {"time_step": 5e-4, "approximation": DiscreteContactApproximation.kTamsi,
                       "contact_model": ContactModel.kPoint, "friction": 2.0,
                       "point_stiffness": 1e8, "dissipation": 10.0, "wheel_half_width": 1e-6}
#: docs/engines.md: "the compliant wheels meshed at 0.1 m (contact_plant.HYDRO_RESOLUTION)"
DOCUMENTED_RESOLUTION = 0.1


@pytest.fixture(scope="module")
def bench():
    """The benchmark bicycle: its wheels differ (R_rear 0.3 m, R_front 0.35 m, Meijaard et al.
    2007, Table 1), so a radius given to the wrong wheel shows."""
    return load_model("benchmark")


@pytest.fixture(scope="module")
def point(bench):
    return build_run_plant(bench.params, POINT)


@pytest.fixture(scope="module")
def hydro(bench):
    return build_run_plant(bench.params, HYDRO)


@pytest.fixture(scope="module")
def default(bench):
    return build_run_plant(bench.params, RunSettings())


def _inspector(rp):
    return rp.plant.get_geometry_query_input_port().Eval(rp.context).inspector()


def _geometry(rp, body):
    """The one collision geometry on ``body`` (found through the plant, not by name)."""
    ids = rp.plant.GetCollisionGeometriesForBody(body)
    assert len(ids) == 1, [_inspector(rp).GetName(i) for i in ids]
    return ids[0]


def _material(rp, body):
    """(static friction, dynamic friction, point stiffness or None, dissipation) of the
    geometry on ``body``, read back from SceneGraph's proximity properties."""
    props = _inspector(rp).GetProximityProperties(_geometry(rp, body))
    mu = props.GetProperty("material", "coulomb_friction")
    k = props.GetPropertyOrDefault("material", "point_contact_stiffness", None)
    return (mu.static_friction(), mu.dynamic_friction(), k,
            props.GetProperty("material", "hunt_crossley_dissipation"))


def _expected(settings: RunSettings) -> dict:
    """What the plant should hold for ``settings``, in Drake's enumerators by option name
    (options.py: the option values name Drake's DiscreteContactApproximation and
    ContactModel)."""
    return {"time_step": settings.time_step,
            "approximation": getattr(DiscreteContactApproximation,
                                     "k" + settings.approximation.capitalize()),
            "contact_model": getattr(ContactModel, "k" + settings.contact_model.capitalize())}


@pytest.mark.parametrize("which, expected", [("point", _expected(POINT)),
                                             ("hydro", _expected(HYDRO)),
                                             ("default", DOCUMENTED_DEFAULTS)])
def test_the_plant_steps_and_contacts_as_the_settings_say(request, which, expected):
    """plant.time_step(), get_contact_model() and get_discrete_contact_approximation() read
    back from Drake: the settings' step, model and solver, with every option away from its
    default and at docs/engines.md's defaults (5e-4 s, point, tamsi). Exact: stored values.
    Fails when a setting is left at Drake's default or mapped to another enumerator."""
    rp = request.getfixturevalue(which)
    assert rp.plant.time_step() == expected["time_step"]
    assert rp.plant.get_contact_model() == expected["contact_model"]
    assert rp.plant.get_discrete_contact_approximation() == expected["approximation"]


@pytest.mark.parametrize("which, half_width", [
    ("point", POINT.wheel_half_width), ("hydro", HYDRO.wheel_half_width),
    ("default", DOCUMENTED_DEFAULTS["wheel_half_width"])])
def test_each_wheel_is_a_cylinder_of_its_radius_about_its_axle(request, bench, which, half_width):
    """Each wheel body carries one collision geometry, a Drake Cylinder of that wheel's radius
    (the benchmark's 0.3 and 0.35 m) and length 2 x wheel_half_width (docs/engines.md: "half
    the cylinder's length"), its axis (the cylinder's z) along the body's axle y and its centre
    at the body's origin (the wheel's centre in the export); the frame and fork carry none.
    Read back through SceneGraphInspector.GetShape and GetPoseInFrame; exact but for the
    rotation's cos(pi/2) = 6e-17 (1e-15). Fails when the length is 3 x the half-width, when
    the radii are swapped, or when the cylinder is left on the body's z axis (the wheel lies
    flat: test_drake's planted run failure)."""
    rp = request.getfixturevalue(which)
    inspector = _inspector(rp)
    p = bench.params
    for b, radius in ((2, p.R_rear), (5, p.R_front)):
        gid = _geometry(rp, rp.wheels[b])
        shape = inspector.GetShape(gid)
        assert isinstance(shape, Cylinder)
        assert (shape.radius(), shape.length()) == (radius, 2 * half_width)
        X = inspector.GetPoseInFrame(gid)
        assert np.abs(np.abs(X.rotation().matrix()[:, 2]) - [0.0, 1.0, 0.0]).max() <= 1e-15
        assert np.array_equal(X.translation(), np.zeros(3))
    for link in ("frame", "fork"):
        assert not rp.plant.GetCollisionGeometriesForBody(rp.plant.GetBodyByName(link))


@pytest.mark.parametrize("which", ["point", "hydro"])
def test_the_ground_is_the_half_space_below_z_0(request, which):
    """The world body carries one collision geometry, a HalfSpace whose pose has its normal
    (the half-space frame's z) along the world's z and its boundary through z = 0 (Drake's
    HalfSpace is z <= 0 in its own frame). Exact: a unit normal and a zero offset are stored
    as given. Fails when the ground is tilted or offset along its normal, or missing."""
    rp = request.getfixturevalue(which)
    gid = _geometry(rp, rp.plant.world_body())
    inspector = _inspector(rp)
    assert isinstance(inspector.GetShape(gid), HalfSpace)
    X = inspector.GetPoseInFrame(gid)
    assert np.array_equal(X.rotation().matrix()[:, 2], [0.0, 0.0, 1.0])
    assert X.translation()[2] == 0.0


def _pair_stiffness(k1: float, k2: float) -> float:
    """Drake's point contact combines two geometries' stiffnesses in series (Drake's "Contact
    Modeling" documentation, point contact: k = k1 k2 / (k1 + k2))."""
    return k1 * k2 / (k1 + k2)


@pytest.mark.parametrize("which, expected", [
    ("point", {"friction": POINT.friction, "point_stiffness": POINT.point_stiffness,
               "dissipation": POINT.dissipation}),
    ("default", DOCUMENTED_DEFAULTS),
])
def test_point_contact_carries_the_friction_stiffness_and_dissipation_given(request, which,
                                                                            expected):
    """The wheels' and the ground's proximity properties, read back from SceneGraph: the
    Coulomb coefficient on each geometry, static = dynamic (options.py), and the pair's as
    Drake itself combines them (CalcContactFrictionFromSurfaceProperties); the pair's point
    stiffness, the two geometries' in series (`_pair_stiffness`), is the given one
    (docs/engines.md: "the point contact's stiffness (of the pair)"), each geometry's the
    same; the Hunt-Crossley dissipation on each geometry (Drake combines two dissipations as
    a weighted mean, so equal values are the pair's). Once with every option away from its
    default, once at the documented defaults (docs/engines.md's table). 1e-15 relative on the
    combinations (one rounding of a product and a quotient); the rest exact. Fails when the
    friction, the stiffness or the dissipation is not given to Drake (its defaults 0.5,
    1e6 N/m, 50 s/m), or the stiffness is scaled by 3 instead of 2 (the pair's 1.5 x the
    given)."""
    rp = request.getfixturevalue(which)
    wheels = [_material(rp, rp.wheels[b]) for b in (2, 5)]
    ground = _material(rp, rp.plant.world_body())
    mu = expected["friction"]
    for mat in wheels + [ground]:
        assert mat[:2] == (mu, mu)
        assert mat[3] == expected["dissipation"]
    props = _inspector(rp).GetProximityProperties
    f_ground = props(_geometry(rp, rp.plant.world_body())).GetProperty("material",
                                                                       "coulomb_friction")
    for b, mat in zip((2, 5), wheels):
        f_wheel = props(_geometry(rp, rp.wheels[b])).GetProperty("material", "coulomb_friction")
        pair = CalcContactFrictionFromSurfaceProperties(f_wheel, f_ground)
        assert pair.static_friction() == pytest.approx(mu, rel=1e-15)
        assert pair.dynamic_friction() == pytest.approx(mu, rel=1e-15)
        assert mat[2] == ground[2]
        assert _pair_stiffness(mat[2], ground[2]) == pytest.approx(expected["point_stiffness"],
                                                                  rel=1e-15)


def test_a_bicycle_standing_still_sinks_by_its_load_over_the_pairs_stiffness(bench):
    """Statics on Drake's own contact: the benchmark bicycle upright and still on the ground
    (q = 0 projected onto the constraints, which pitches its frame by beta = -pi/10 so that the
    front wheel touches; zc = 0) with TAMSI (SAP ignores a point stiffness above its near-rigid
    limit, docs/engines.md) at point_stiffness 4e7 N/m and dissipation 3 s/m, stepped 0.1 s
    (100 steps of 1e-3 s; the contact's vertical mode, sqrt(k / m) ~ 1e3 rad/s, settles within
    them: the rate of zc is 1e-15 m/s after). Then Drake's contact results (the ground's
    vertical force on each wheel) are the static split of the weight (`static_split`: 612.8 N
    rear, 309.3 N front of 922.1 N), and each wheel's penetration (QueryObject.
    ComputePointPairPenetration, Drake's own geometry) is its force over the pair's stiffness,
    the given 4e7 N/m (a sink of 1.5e-5 m rear, 7.7e-6 m front). Bounds: 1e-4 of the weight
    for the forces (measured 5e-6: the unequal sinks pitch the bicycle by 7e-6 rad, which
    moves its CoM along the wheelbase by ~1e-5 of the split's lever) and 1e-6 relative for the
    stiffness (measured 1e-12, settled).
    Fails when the stiffness given to each geometry is not twice the pair's (3 x: the pair
    1.5 x stiffer, the sink 2/3), or when a wheel has no contact."""
    model = bench
    s = RunSettings(approximation="tamsi", time_step=1e-3, point_stiffness=4e7, dissipation=3.0)
    rp = build_run_plant(model.params, s)
    plant = rp.plant
    assert RUN_COORDINATES[2] == "zc"
    q = consistent_state(model, np.zeros(8), np.zeros(8)).q
    plant.SetPositions(rp.context, rp.mapping.q_to_drake(np.insert(q, 2, 0.0)))
    plant.SetVelocities(rp.context, np.zeros(9))
    rp.simulator.AdvanceTo(0.1)
    query = plant.get_geometry_query_input_port().Eval(rp.context)
    inspector = query.inspector()
    wheel_of = {_geometry(rp, rp.wheels[b]): b for b in (2, 5)}
    depth = {}
    for pair in query.ComputePointPairPenetration():
        b = wheel_of.get(pair.id_A, wheel_of.get(pair.id_B))
        assert b is not None, (inspector.GetName(pair.id_A), inspector.GetName(pair.id_B))
        depth[b] = pair.depth
    results = plant.get_contact_results_output_port().Eval(rp.context)
    force = {2: 0.0, 5: 0.0}
    index = {rp.wheels[b].index(): b for b in (2, 5)}
    for i in range(results.num_point_pair_contacts()):
        c = results.point_pair_contact_info(i)      # contact_force: on body B, in the world
        if c.bodyB_index() in index:
            force[index[c.bodyB_index()]] += c.contact_force()[2]
        else:
            force[index[c.bodyA_index()]] -= c.contact_force()[2]
    p = model.params
    weight = p.g * (p.m2 + p.m3 + p.m4 + p.m5)
    rear, front = static_split(model, q)
    assert abs(force[2] - rear) <= 1e-4 * weight and abs(force[5] - front) <= 1e-4 * weight
    for b in (2, 5):
        assert force[b] / depth[b] == pytest.approx(s.point_stiffness, rel=1e-6)


def test_hydroelastic_wheels_are_compliant_on_a_rigid_ground(hydro, bench):
    """Hydroelastic contact (docs/engines.md: "compliant wheels, hydroelastic_modulus, rigid
    ground"), read back from SceneGraph: on the wheels the hydroelastic modulus given and the
    documented mesh resolution 0.1 m; on the wheels and the ground the friction and the
    dissipation given (Drake's defaults would be 0.5 and 50 s/m). Then from Drake's own
    hydroelastic query: the bicycle upright and still (q = 0 projected onto the constraints)
    lowered 1 cm into the ground (zc = -0.01 m, more than a polygon of 0.1 m edges sags inside
    a 0.3 m circle, h^2 / (8 R) = 4.2e-3 m) gives one contact surface per wheel, each between
    that wheel and the ground, with a pressure field gradient on the wheel's side only: the
    wheel is the soft geometry, the ground the rigid one. Exact: stored values and flags.
    Fails when the wheels are made rigid or the ground compliant (Drake refuses either when
    the plant is built: a rigid cylinder needs a resolution hint, a soft half-space a slab
    thickness; given those, this query refuses a rigid-rigid pair and a soft half-space
    against a soft cylinder, both tried), or when the modulus, the resolution, the friction
    or the dissipation is not given to Drake."""
    rp = hydro
    inspector = _inspector(rp)
    ground = _geometry(rp, rp.plant.world_body())
    for gid in [_geometry(rp, rp.wheels[b]) for b in (2, 5)]:
        props = inspector.GetProximityProperties(gid)
        assert props.GetProperty("hydroelastic", "hydroelastic_modulus") == \
            HYDRO.hydroelastic_modulus
        assert props.GetProperty("hydroelastic", "resolution_hint") == DOCUMENTED_RESOLUTION
    for body in (rp.wheels[2], rp.wheels[5], rp.plant.world_body()):
        mat = _material(rp, body)
        assert mat[:2] == (HYDRO.friction, HYDRO.friction) and mat[3] == HYDRO.dissipation
    root = rp.simulator.get_system().CreateDefaultContext()     # the fixture's stays as built
    context = rp.plant.GetMyMutableContextFromRoot(root)
    q = consistent_state(bench, np.zeros(8), np.zeros(8)).q
    rp.plant.SetPositions(context, rp.mapping.q_to_drake(np.insert(q, 2, -0.01)))
    query = rp.plant.get_geometry_query_input_port().Eval(context)
    surfaces = query.ComputeContactSurfaces(HydroelasticContactRepresentation.kPolygon)
    seen = set()
    for surface in surfaces:
        soft = {surface.id_M(): surface.HasGradE_M(), surface.id_N(): surface.HasGradE_N()}
        assert ground in soft and not soft.pop(ground)
        (wheel, graded), = soft.items()
        assert graded
        seen.add(wheel)
    assert seen == {_geometry(rp, rp.wheels[b]) for b in (2, 5)}


def test_drakes_warnings_during_the_build_are_kept_out_and_its_level_restored(
        bench, caplog, monkeypatch):
    """build_run_plant's docstring: Drake's warnings during the build (it warns once per
    process about the rigid half-space and deformable contact) are kept out of the run's
    output and the logger's level is restored after. pydrake logs through the Python logger
    'drake'; here set to INFO (pydrake's own level) and a probe warning logged on it from
    inside the build (in add_bicycle, which the build calls): no record of it reaches the
    handlers, the 'drake' logger is back at INFO after, also when the build fails, and the
    root logger's level is never touched. Fails when the level is set on another logger
    (the root's, which the 'drake' logger's own INFO overrides, or a misspelt name)."""
    caplog.set_level(logging.INFO, logger="drake")
    root_level = logging.getLogger().level
    seen_root = []
    real = contact_plant.add_bicycle

    def probing(plant, params, text=None):
        seen_root.append(logging.getLogger().level)
        logging.getLogger("drake").warning("probe: a warning Drake logs during the build")
        return real(plant, params, text)

    monkeypatch.setattr(contact_plant, "add_bicycle", probing)
    build_run_plant(bench.params, POINT)
    assert seen_root == [root_level]
    assert not [r for r in caplog.records if r.name == "drake"], caplog.text
    assert logging.getLogger("drake").level == logging.INFO
    # the control: the same probe outside the build is logged
    logging.getLogger("drake").warning("probe outside")
    assert [r.getMessage() for r in caplog.records if r.name == "drake"] == ["probe outside"]

    def failing(plant, params, text=None):
        raise RuntimeError("planted failure")

    monkeypatch.setattr(contact_plant, "add_bicycle", failing)
    with pytest.raises(RuntimeError, match="planted failure"):
        build_run_plant(bench.params, POINT)
    assert logging.getLogger("drake").level == logging.INFO
