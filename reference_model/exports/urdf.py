"""The bicycle as URDF: the rigid-body tree of ``description`` (links, inertials, the thesis's
joints, wheel radii as collision discs). URDF cannot express the rolling contact (two wheels
rolling without slip on the ground, a non-holonomic constraint), the aerodynamic drag or the
rider torques; the URDF says so in a comment and the JSON export describes them. URDF has no
field for gravity (the comment gives ``g``).
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

from ..parameters.values import Parameters
from .description import bodies, joints
from .text import float_text as _num
from .text import vec as _vec

__all__ = ["urdf_text"]


def urdf_text(p: Parameters) -> str:
    """The URDF document: links, inertials, the thesis's joints, wheel radii as collision discs."""
    by_link = {b["link"]: b for b in bodies(p)}
    radius = {"rear_wheel": p.R_rear, "front_wheel": p.R_front}
    lines = [
        '<?xml version="1.0"?>',
        "<!--",
        f"  The four-body bicycle '{p.name}' (front contact model '{p.contact}'), exported by",
        "  bicycle-xval from its parameter set. Units SI; gravity -z, g = " + _num(p.g) + " m/s^2.",
        "  Joints follow the thesis's coordinates in order: xc, yc (prismatic), phi, theta, psi,",
        "  beta, gamma, eps (revolute; 'continuous' = unbounded). Inertias are about each body's",
        "  CoM in its body axes (x forward, y left, z up when upright).",
        "  NOT EXPRESSIBLE IN URDF: the rolling contact. Both wheels roll without slipping on the",
        "  ground (non-holonomic constraints; the front contact point per the model above), and the",
        "  aerodynamic drag and rider torques are loads. Without them this tree is a free chain;",
        "  the JSON export of the same model describes them.",
        "-->",
        f"<robot name={quoteattr('bicycle-' + p.name)}>",
    ]
    links = ["ground", "xc_link", "yc_link", "yaw", "lean", "rear_wheel", "frame", "fork", "front_wheel"]
    for link in links:
        if link not in by_link:
            lines.append(f'  <link name="{link}"/>')
            continue
        b = by_link[link]
        I = b["inertia"]
        lines += [
            f'  <link name="{link}">',
            f"    <!-- body {b['body']}: {b['name']} -->",
            "    <inertial>",
            f'      <origin xyz="{_vec(b["com"])}" rpy="0 0 0"/>',
            f'      <mass value="{_num(b["mass"])}"/>',
            f'      <inertia ixx="{_num(I[0][0])}" ixy="{_num(I[0][1])}" ixz="{_num(I[0][2])}" '
            f'iyy="{_num(I[1][1])}" iyz="{_num(I[1][2])}" izz="{_num(I[2][2])}"/>',
            "    </inertial>",
        ]
        if link in radius:
            lines += [
                f"    <!-- wheel radius {_num(radius[link])} m; the model's wheels are knife-edge "
                "discs, the cylinder's length is nominal -->",
                "    <collision>",
                '      <origin xyz="0 0 0" rpy="1.5707963267948966 0 0"/>',
                f'      <geometry><cylinder radius="{_num(radius[link])}" length="0.001"/></geometry>',
                "    </collision>",
            ]
        lines.append("  </link>")
    for j in joints(p):
        kind = j["type"] if j["type"] == "prismatic" else "continuous"
        lines += [
            f'  <joint name="{j["name"]}" type="{kind}">',
            f'    <parent link="{j["parent"]}"/>',
            f'    <child link="{j["child"]}"/>',
            f'    <origin xyz="{_vec(j["origin"])}" rpy="0 0 0"/>',
            f'    <axis xyz="{_vec(j["axis"])}"/>',
        ]
        if kind == "prismatic":
            lines.append('    <limit lower="-1e9" upper="1e9" effort="0" velocity="1e9"/>')
        lines.append("  </joint>")
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
