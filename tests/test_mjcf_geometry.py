"""The exported MJCF's geometry against the model, on bicycles whose wheels differ (the
benchmark: R_rear 0.3 m, R_front 0.35 m; the general disc bicycle: 0.34 and 0.30 m), and a
short MuJoCo run on the benchmark against the reference.

The mass matrix test (tests/test_mujoco.py) cannot see a tyre's size: the wheel geoms carry no
mass. Here the file, compiled by MuJoCo, is checked for every size, inertia and axis:

* each body's mass, and its inertia tensor (MuJoCo keeps the principal moments and their
  axes: rebuilt as R diag(I) R^T) against the parameters' tensor;
* at random states, MuJoCo's own forward kinematics against the reference model's points
  (`Model.points`, from the thesis's derivation): each body's CoM in world axes (this tests
  every body position and every joint axis along the chain), the tyres' centres, and the
  lowest point of each tyre's circle (centre - radius x the downward direction in the wheel's
  plane, from MuJoCo's geom axis and size) against the model's contact points rC and rD,
  which tests each radius and each tyre's axis.

Tolerances: positions are sums of a few products of O(1) lengths and rotations, evaluated in
two codes (MuJoCo's float64 kinematics, the generated C): round-off ~1e-15 m; 1e-12 m. The
inertia tensor goes through MuJoCo's eigen-decomposition (its own Jacobi, ~1e-15 relative):
1e-12 relative. A wrong radius (0.05 m between the benchmark's wheels) or a swapped axis moves
them by O(0.01-1). Cost: ~0.5 s (the 0.5 s MuJoCo run 0.3 s).
"""

import dataclasses

import numpy as np
import pytest

from comparisons.judgments.terms import random_states
from reference_model import COORDINATES, load_model
from reference_model.export_mjcf import MjcfSettings, mjcf_text
from reference_model.solvers import solve_beta

mujoco = pytest.importorskip("mujoco")

BODIES = {"rear_wheel": 2, "frame": 3, "fork": 4, "front_wheel": 5}
TYRES = {"rear_tyre": ("rear_wheel", "rC", "R_rear"), "front_tyre": ("front_wheel", "rD", "R_front")}


# function scope: the export is compiled in each test (~10 ms), so a mutation run sees every
# test that reads the file as a test of the export (a module fixture counts for its first test only)
@pytest.fixture(params=["benchmark", "general-disc"])
def compiled(request):
    from comparisons.conformance.models import conformance_model
    model = (load_model("benchmark") if request.param == "benchmark"
             else conformance_model("general-disc"))
    assert model.params.R_rear != model.params.R_front and model.params.contact == "disc"
    mj = mujoco.MjModel.from_xml_string(mjcf_text(model.params))
    return model, mj


def _id(mj, kind, name):
    i = mujoco.mj_name2id(mj, kind, name)
    assert i >= 0, name
    return i


def test_each_body_carries_its_mass_and_inertia_tensor(compiled):
    model, mj = compiled
    p = model.params
    for name, b in BODIES.items():
        i = _id(mj, mujoco.mjtObj.mjOBJ_BODY, name)
        assert mj.body_mass[i] == getattr(p, f"m{b}")
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, mj.body_iquat[i])
        R = R.reshape(3, 3)
        tensor = R @ np.diag(mj.body_inertia[i]) @ R.T
        expected = p.inertia(b)
        assert np.abs(tensor - expected).max() <= 1e-12 * np.abs(expected).max(), name
        assert np.array_equal(mj.body_quat[i], [1, 0, 0, 0])    # body axes = parent's at zero


def test_joints_are_the_thesis_coordinates_in_order(compiled):
    _, mj = compiled
    assert tuple(mj.joint(i).name for i in range(mj.njnt)) == COORDINATES
    slide, hinge = mujoco.mjtJoint.mjJNT_SLIDE, mujoco.mjtJoint.mjJNT_HINGE
    assert list(mj.jnt_type) == [slide, slide] + [hinge] * 6


def test_tyres_are_cylinders_of_each_wheels_radius(compiled):
    model, mj = compiled
    w = MjcfSettings().wheel_half_width
    for tyre, (_, _, radius) in TYRES.items():
        g = _id(mj, mujoco.mjtObj.mjOBJ_GEOM, tyre)
        assert mj.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER
        assert mj.geom_size[g][:2] == pytest.approx([getattr(model.params, radius), w],
                                                    rel=1e-15)


def test_forward_kinematics_place_every_com_and_contact_where_the_model_does(compiled):
    """12 random states (large lean, steer, every angle), beta from the front contact's
    height constraint so the front tyre touches the ground as in the model."""
    model, mj = compiled
    d = mujoco.MjData(mj)
    for q in random_states(12, seed=24).q:
        q, _ = solve_beta(model, q)
        d.qpos[:] = q
        mujoco.mj_kinematics(mj, d)
        pts = model.points(q)
        for name, b in BODIES.items():
            i = _id(mj, mujoco.mjtObj.mjOBJ_BODY, name)
            assert np.abs(d.xipos[i] - pts[f"rG{b}"]).max() <= 1e-12, (name, q)
        for tyre, (body, contact, _) in TYRES.items():
            g = _id(mj, mujoco.mjtObj.mjOBJ_GEOM, tyre)
            centre, axis = d.geom_xpos[g], d.geom_xmat[g].reshape(3, 3)[:, 2]
            b = _id(mj, mujoco.mjtObj.mjOBJ_BODY, body)
            # the cylinder's axis is the wheel's axle: the body's y axis
            assert np.abs(axis - d.xmat[b].reshape(3, 3)[:, 1]).max() <= 1e-12, tyre
            assert np.abs(centre - pts[f"rG{BODIES[body]}"]).max() <= 1e-12, tyre
            down = np.array([0.0, 0.0, -1.0]) + axis[2] * axis   # -z, in the wheel's plane
            lowest = centre + mj.geom_size[g][0] * down / np.linalg.norm(down)
            assert np.abs(lowest - pts[contact]).max() <= 1e-12, (tyre, q)
            assert abs(lowest[2]) <= 1e-12                    # on the ground, as in the model


def test_a_short_mujoco_run_on_the_benchmark_follows_the_reference():
    """0.5 s upright at 4.6 m/s with the 0.05 rad/s roll-rate kick (the stability stage's
    scenario, cut short). MuJoCo's soft contact (solref 2e-4 s) rolls the discs with a slip of
    ~1e-7 m/s: measured 4.3e-6 rad or m at most over the eight coordinates; 1e-4 (the
    soft-contact bound of tests/test_mujoco.py's fall test) leaves a factor 20. A front tyre of
    the rear wheel's radius leaves the front wheel 0.05 m in the air: 0.83 rad off (eps)."""
    from comparisons.stages.stability import scenario
    from engines import load_engine
    from engines.mujoco import MujocoEngine
    model = load_model("benchmark")
    sc = dataclasses.replace(scenario("benchmark", 4.6), grid=(0.0, 0.01, 51))
    mine = MujocoEngine(model).simulate(sc)
    ref = load_engine("reference", model).simulate(sc)
    assert mine.status == ref.status == "completed", mine.message
    assert mine.t.shape == ref.t.shape and np.array_equal(mine.t, ref.t)
    assert np.abs(mine.q - ref.q).max() <= 1e-4


@pytest.mark.parametrize("rear_height", [False, True])
def test_the_massless_links_are_the_bodies_with_the_placeholder_mass(rear_height):
    """`massless_links` names exactly the bodies the file gives the placeholder inertial (an
    engine zeroes those after compiling): xc_link, yc_link, yaw, lean, and zc_link only in the
    forward-run chain."""
    from reference_model.export_mjcf import PLACEHOLDER_MASS, massless_links
    mj = mujoco.MjModel.from_xml_string(mjcf_text(load_model("benchmark").params,
                                                  rear_height=rear_height))
    light = tuple(mj.body(i).name for i in range(1, mj.nbody)
                  if mj.body_mass[i] == PLACEHOLDER_MASS)
    assert massless_links(rear_height) == light
    assert ("zc_link" in light) == rear_height
    assert massless_links() == massless_links(False)


def test_the_file_says_which_contact_it_approximates_and_its_settings_are_plain_data():
    """A disc-contact model's file approximates its own contact; a thesis-contact model's file
    says it does NOT model that contact (the declared difference travels with the file). The
    settings' tuples come out as lists (a run's JSON settings)."""
    disc = mjcf_text(load_model("benchmark").params)
    thesis = mjcf_text(load_model("thesis").params)
    assert "approximates this model's rolling-disc contact" in disc and "NOT" not in \
        disc.split("CONTACT:")[1].split("NOT IN THIS FILE")[0]
    assert "NOT this model's thesis fork-axis" in " ".join(thesis.replace("\n", " ").split())
    d = MjcfSettings().as_dict()
    assert d["solref"] == [2e-4, 1.0] and isinstance(d["solimp"], list)
