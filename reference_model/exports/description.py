"""The bicycle as engine-neutral plain data: the thesis's chain of joints, the four bodies,
the rolling contact and the loads (:func:`model_description`, what the JSON export holds;
:func:`json_text`). Built from a `Parameters` set only (nothing here imports an engine). The
tree is the thesis's chain of joints, one joint per coordinate in the thesis's order, the
floating base included::

    ground -xc (prismatic x)-> -yc (prismatic y)-> -phi (revolute z)-> -theta (revolute x)-> lean
    lean -psi (revolute y, at [0, 0, R_rear])-> rear_wheel
    lean -beta (revolute y, at [0, 0, R_rear])-> frame -gamma (revolute z, at [xa, 0, za])-> fork
    fork -eps (revolute y, at [x5, 0, z5])-> front_wheel

Every joint frame has the orientation of its parent at zero angle, so each body's joint frame
is its body frame (x forward, y left, z up when upright); inertias are about the CoM in those
axes. `xc_link`, `yc_link`, `yaw` and `lean` are massless. Gravity is along -z with magnitude
``g``. The JSON describes what a URDF cannot (``urdf``): the rolling contact, the drag, the
rider torques.
"""

from __future__ import annotations

import dataclasses
import json
from typing import Any

from ..names import BODY_NAMES, COORDINATES, TORQUE_NAMES
from ..parameters.schema import PARAMETER_NAMES
from ..parameters.values import Parameters

__all__ = ["COORDINATE_MEANING", "SCHEMA", "bodies", "joints", "json_text", "model_description"]

SCHEMA = "bicycle-xval/model-export/1"

COORDINATE_MEANING = {
    "xc": ("m", "x of the rear contact point C on the ground (global frame)"),
    "yc": ("m", "y of the rear contact point C on the ground (global frame)"),
    "phi": ("rad", "yaw: rotation of the rear assembly about global z"),
    "theta": ("rad", "lean (roll): rotation about the yawed x axis, positive leans to the right"
                     " (toward -y)"),
    "psi": ("rad", "rear wheel rotation about its axle (lean frame's y axis)"),
    "beta": ("rad", "frame pitch about the rear axle (lean frame's y axis)"),
    "gamma": ("rad", "steer: fork rotation about the steering axis (frame's z axis)"),
    "eps": ("rad", "front wheel rotation about its axle (fork's y axis)"),
}


def joints(p: Parameters) -> list[dict[str, Any]]:
    """The thesis's chain: (name, type, parent, child, origin in parent joint frame, axis)."""
    R = p.R_rear
    return [
        dict(name="xc", type="prismatic", parent="ground", child="xc_link", origin=[0, 0, 0], axis=[1, 0, 0]),
        dict(name="yc", type="prismatic", parent="xc_link", child="yc_link", origin=[0, 0, 0], axis=[0, 1, 0]),
        dict(name="phi", type="revolute", parent="yc_link", child="yaw", origin=[0, 0, 0], axis=[0, 0, 1]),
        dict(name="theta", type="revolute", parent="yaw", child="lean", origin=[0, 0, 0], axis=[1, 0, 0]),
        dict(name="psi", type="revolute", parent="lean", child="rear_wheel", origin=[0, 0, R], axis=[0, 1, 0]),
        dict(name="beta", type="revolute", parent="lean", child="frame", origin=[0, 0, R], axis=[0, 1, 0]),
        dict(name="gamma", type="revolute", parent="frame", child="fork", origin=[p.xa, 0, p.za], axis=[0, 0, 1]),
        dict(name="eps", type="revolute", parent="fork", child="front_wheel", origin=[p.x5, 0, p.z5], axis=[0, 1, 0]),
    ]


def bodies(p: Parameters) -> list[dict[str, Any]]:
    """The four bodies: mass, CoM in the body (joint) frame, inertia about the CoM, body axes."""
    com = {2: [0.0, 0.0, 0.0], 3: [p.x3, 0.0, p.z3], 4: [p.dx4, 0.0, p.dz4], 5: [0.0, 0.0, 0.0]}
    link = {2: "rear_wheel", 3: "frame", 4: "fork", 5: "front_wheel"}
    out = []
    for b in (2, 3, 4, 5):
        I = p.inertia(b)
        out.append(dict(body=b, link=link[b], name=BODY_NAMES[b], mass=getattr(p, f"m{b}"),
                        com=com[b], inertia=[[float(v) for v in row] for row in I]))
    return out


def _contact(p: Parameters) -> dict[str, Any]:
    front = {
        "thesis": ("rD = rG5 - R_front * z4: the rim point along the fork's -z axis from the front "
                   "hub (the thesis's model; it is the lowest point only when the fork's z axis is "
                   "vertical)"),
        "disc": ("rD = rG5 - R_front * (e_z - (e_z . y4) y4) / |e_z - (e_z . y4) y4|: the true "
                 "lowest point of the front disc (y4 = the fork's y axis = the wheel's axle)"),
    }[p.contact]
    return {
        "model": p.contact,
        "rear": ("rC = [xc, yc, 0]: the rear wheel touches the ground at C by construction of the "
                 "chain (hub at R_rear along the lean frame's z); it rolls without slipping: the "
                 "velocity of the rear wheel's material point at rC is zero in x and y"),
        "front": front,
        "constraints": [
            {"name": "rD_z", "kind": "holonomic", "equation": "z of rD = 0 (front wheel touches the ground)"},
            {"name": "vC_x", "kind": "non-holonomic", "equation": "x velocity of the rear wheel's material point at rC = 0"},
            {"name": "vC_y", "kind": "non-holonomic", "equation": "y velocity of the rear wheel's material point at rC = 0"},
            {"name": "vD_x", "kind": "non-holonomic", "equation": "x velocity of the front wheel's material point at rD = 0"},
            {"name": "vD_y", "kind": "non-holonomic", "equation": "y velocity of the front wheel's material point at rD = 0"},
        ],
        "velocity_form": "D(q) dq = 0 with D (5x8): row rD_z = d(rD_z)/dq, rows vC_x..vD_y = "
                         "d(velocity)/d(dq); accelerations: D ddq + dD dq = 0",
        "no_vertical_velocity_constraint_at_C": "the rear contact's height is zero identically",
    }


def model_description(p: Parameters) -> dict[str, Any]:
    """Everything the export says, as plain data (what the JSON file holds)."""
    return {
        "schema": SCHEMA,
        "model": {"name": p.name, "contact": p.contact, "source": p.source},
        "units": {"length": "m", "mass": "kg", "inertia": "kg*m^2", "angle": "rad", "time": "s",
                  "torque": "N*m"},
        "gravity": {"g": p.g, "direction": [0.0, 0.0, -1.0]},
        "coordinates": [{"name": n, "unit": COORDINATE_MEANING[n][0],
                         "meaning": COORDINATE_MEANING[n][1]} for n in COORDINATES],
        "frames": ("every joint frame has its parent's orientation at zero angle, so a body's "
                   "joint frame is its body frame: x forward, y left, z up in the upright, "
                   "straight-ahead configuration; rotations are right-handed"),
        "joints": joints(p),
        "bodies": bodies(p),
        "wheels": {"rear": {"link": "rear_wheel", "radius": p.R_rear, "axle": "body y"},
                   "front": {"link": "front_wheel", "radius": p.R_front, "axle": "body y"},
                   "shape": "knife-edge discs (no width, no tyre), centred on the hubs"},
        "rolling_contact": _contact(p),
        "loads": {
            "drag": {"cv": p.cv, "unit": "kg/m", "force": "-cv |vG3| vG3 at the frame's CoM G3"},
            "rider_torques": {
                TORQUE_NAMES[0]: "steer torque on the fork about its z axis (single-sided)",
                TORQUE_NAMES[1]: "pedal torque on the rear wheel about its y axis (single-sided)",
                TORQUE_NAMES[2]: "anti-roll torque on the frame about its x axis (single-sided)",
            },
        },
        "parameters": {n: float(getattr(p, n)) for n in PARAMETER_NAMES},
        "provenance": {k: _plain(v) for k, v in p.as_dict().items() if k not in PARAMETER_NAMES},
    }


def _plain(value: Any) -> Any:
    """JSON-ready: numbers, strings and None as they are, dataclasses (e.g. a benchmark's Table
    1) as dicts, numpy scalars as floats, anything else by its text."""
    if value is None or isinstance(value, (str, bool, int, float)):
        return value
    if dataclasses.is_dataclass(value):
        return {k: _plain(v) for k, v in dataclasses.asdict(value).items()}
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


def json_text(p: Parameters) -> str:
    return json.dumps(model_description(p), indent=2) + "\n"
