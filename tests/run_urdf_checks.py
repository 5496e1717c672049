"""The contract both soft-contact adapters' run URDFs share (tests/test_drake.py and
tests/test_dart.py): the export's URDF with the rear contact's height freed."""

from __future__ import annotations

import xml.etree.ElementTree as ET

__all__ = ["assert_rear_height_freed"]


def _shape(e):
    return (e.tag, e.attrib, [_shape(c) for c in e])


def assert_rear_height_freed(robot: ET.Element, export: ET.Element) -> None:
    """``robot`` (a run's URDF) is ``export`` with phi hanging from a massless zc_link, which a
    prismatic z joint at the origin, effectively unlimited (|limit| >= 1e9 m), hangs from
    yc_link; every other joint and link the export's, in the same order."""
    joints = {j.get("name"): j for j in robot.iter("joint")}
    assert joints["phi"].find("parent").get("link") == "zc_link"
    zc = joints["zc"]
    assert zc.get("type") == "prismatic"
    assert (zc.find("parent").get("link"), zc.find("child").get("link")) == ("yc_link", "zc_link")
    assert zc.find("axis").get("xyz").split() == ["0", "0", "1"]
    origin = zc.find("origin")
    assert origin.get("xyz").split() == ["0", "0", "0"] == origin.get("rpy").split()
    limit = zc.find("limit")
    assert float(limit.get("lower")) <= -1e9 and float(limit.get("upper")) >= 1e9
    links = [ln.get("name") for ln in robot.iter("link")]
    assert links == [ln.get("name") for ln in export.iter("link")] + ["zc_link"]
    assert robot.find("link[@name='zc_link']").find("inertial") is None
    for j in export.iter("joint"):
        if j.get("name") != "phi":
            assert _shape(joints[j.get("name")]) == _shape(j)
