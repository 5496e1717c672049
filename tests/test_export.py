"""The exported bicycle, read back by independent loaders.

The URDF goes through Pinocchio's own URDF parser (`buildModelFromUrdf`), whose CRBA mass
matrix is a second formulation of M (recursive spatial inertias) against the reference's
generated L^T MM L; the JSON's joints and bodies are assembled into a Pinocchio model by hand
here. Both must give the reference's M at random states.
"""

import json
import os

import numpy as np
import pytest

from reference_model import COORDINATES, CONSTRAINT_NAMES, ParameterError, load_model
from reference_model.export import export_model, model_description
from reference_model.params import PARAMETER_NAMES

pin = pytest.importorskip("pinocchio")

MODELS = ("thesis", "thesis-disc", "benchmark")
# M agrees to round-off: CRBA and L^T MM L each sum ~1e2 products of O(1)..O(1e2) numbers, so
# ~1e-15 relative to max|M| (measured 7e-16); 1e-12 relative is the bar and leaves
# three digits of margin while a 1e-6 change of any inertia entry shows as >= 1e-8.
RTOL_M = 1e-12


def _states(n=100, seed=11):
    rng = np.random.default_rng(seed)
    lo = np.array([-10, -10, -np.pi, -1.2, -np.pi, -0.5, -1.55, -np.pi])
    return rng.uniform(lo, -lo, (n, 8))


def _pin_config(pm, q):
    """Pinocchio's configuration for thesis q: an unbounded revolute joint ('continuous' in
    URDF) stores (cos, sin); joints are matched by name, whatever order the parser chose."""
    qp = np.zeros(pm.nq)
    for name, value in zip(COORDINATES, q):
        j = pm.joints[pm.getJointId(name)]
        if j.nq == 2:
            qp[j.idx_q:j.idx_q + 2] = np.cos(value), np.sin(value)
        else:
            qp[j.idx_q] = value
    return qp


def _mass_matrix_in_thesis_order(pm, q):
    data = pm.createData()
    M = pin.crba(pm, data, _pin_config(pm, q))
    M = np.triu(M) + np.triu(M, 1).T
    idx = [pm.joints[pm.getJointId(n)].idx_v for n in COORDINATES]
    return M[np.ix_(idx, idx)]


def _worst_relative(pm, model):
    worst = 0.0
    for q in _states():
        ref = model.mass_matrix(q)
        worst = max(worst, np.abs(_mass_matrix_in_thesis_order(pm, q) - ref).max() / np.abs(ref).max())
    return worst


@pytest.mark.parametrize("name", MODELS)
def test_urdf_mass_matrix_matches_reference(tmp_path, name):
    path = export_model(name, "urdf", tmp_path / f"{name}.urdf")
    pm = pin.buildModelFromUrdf(str(path))
    assert pm.nv == 8 and set(COORDINATES) <= set(pm.names)
    assert _worst_relative(pm, load_model(name)) <= RTOL_M


def test_urdf_says_what_it_cannot_express(tmp_path):
    text = export_model("thesis", "urdf", tmp_path / "b.urdf").read_text()
    assert "NOT EXPRESSIBLE IN URDF: the rolling contact" in text
    joints = [line.split('"')[1] for line in text.splitlines() if line.strip().startswith("<joint name=")]
    assert tuple(joints) == COORDINATES
    assert text.count('<cylinder radius="0.32"') == 2


def _pin_from_json(desc):
    """A Pinocchio model assembled from the JSON's joints and bodies alone."""
    kinds = {("prismatic", 0): pin.JointModelPX, ("prismatic", 1): pin.JointModelPY,
             ("revolute", 0): pin.JointModelRX, ("revolute", 1): pin.JointModelRY,
             ("revolute", 2): pin.JointModelRZ}
    pm = pin.Model()
    joint_of = {"ground": 0}
    for j in desc["joints"]:
        axis = int(np.argmax(j["axis"]))
        assert j["axis"][axis] == 1 and sum(j["axis"]) == 1
        placement = pin.SE3(np.eye(3), np.array(j["origin"], dtype=float))
        joint_of[j["child"]] = pm.addJoint(joint_of[j["parent"]], kinds[j["type"], axis](),
                                           placement, j["name"])
    for b in desc["bodies"]:
        pm.appendBodyToJoint(joint_of[b["link"]],
                             pin.Inertia(b["mass"], np.array(b["com"]), np.array(b["inertia"])),
                             pin.SE3.Identity())
    return pm


@pytest.mark.parametrize("name", MODELS)
def test_json_describes_tree_contact_and_parameters(tmp_path, name):
    model = load_model(name)
    desc = json.loads(export_model(name, "json", tmp_path / "b.json").read_text())
    assert [c["name"] for c in desc["coordinates"]] == list(COORDINATES)
    assert [j["name"] for j in desc["joints"]] == list(COORDINATES)
    assert desc["rolling_contact"]["model"] == model.contact
    assert [c["name"] for c in desc["rolling_contact"]["constraints"]] == list(CONSTRAINT_NAMES)
    assert desc["parameters"] == {n: getattr(model.params, n) for n in PARAMETER_NAMES}
    assert desc["provenance"]["name"] == model.params.name
    assert desc["wheels"]["front"]["radius"] == model.params.R_front
    pm = _pin_from_json(desc)
    q = _states(20)
    worst = max(np.abs(np.triu(pin.crba(pm, pm.createData(), x)) - np.triu(model.mass_matrix(x))).max()
                / np.abs(model.mass_matrix(x)).max() for x in q)
    assert worst <= RTOL_M   # crba fills the upper triangle: the upper triangles are compared


def test_bad_format_and_model_and_no_half_written_file(tmp_path):
    with pytest.raises(ValueError) as err:
        export_model("thesis", "sdf", tmp_path / "b.sdf")
    # the whole message: the CLI prints it as the fix (the choices and how to write them)
    assert str(err.value) == ("format 'sdf' is not one of urdf, mjcf, json; use --format urdf, "
                              "mjcf or json")
    with pytest.raises(ParameterError, match="unknown model 'thesis-dsic'"):
        export_model("thesis-dsic", "urdf", tmp_path / "b.urdf")
    with pytest.raises(OSError):
        export_model("thesis", "urdf", tmp_path / "no" / "such" / "dir" / "b.urdf")
    assert os.listdir(tmp_path) == []


def test_description_is_plain_data():
    desc = model_description(load_model("benchmark").params)
    json.dumps(desc)   # no numpy types
    assert desc["model"]["contact"] == "disc" and desc["gravity"]["g"] > 0
