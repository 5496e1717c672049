"""The URDF export as an XML document (reference_model/exports/urdf.py), issue 24: read by the
standard library's own XML parser, not by string matching. Pinocchio's loader (tests/
test_export.py) checks the tree's physics; it ignores what a URDF parser may ignore, so here:
the document is well-formed, holds no stray text, names the robot after the model, turns each
wheel's collision cylinder onto its axle (URDF's cylinder axis is z; the wheel spins about y),
bounds the prismatic joints as URDF requires, and its header comment gives what URDF has no
field for (units, g, the rolling contact it cannot express), as the module promises.
Planted bugs each test was seen failing on are named in it."""

import xml.etree.ElementTree as ET

import pytest

from reference_model import load_model
from reference_model.exports.urdf import urdf_text


def _parse(text: str) -> ET.Element:
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    parser.feed(text)
    return parser.close()


@pytest.fixture(scope="module", params=["thesis", "benchmark"])
def urdf(request):
    p = load_model(request.param).params
    return p, urdf_text(p)


def test_the_document_is_well_formed_with_no_stray_text(urdf):
    """Planted: the XML declaration upper-cased (a parse error), text written around a
    closing tag ('XX  </link>XX' in the element's text)."""
    p, text = urdf
    root = _parse(text)
    assert root.tag == "robot" and root.get("name") == f"bicycle-{p.name}"
    for el in root.iter():
        if el.tag is ET.Comment:
            continue
        assert (el.text or "").strip() == "" and (el.tail or "").strip() == "", el.tag


def test_each_wheel_s_collision_cylinder_lies_on_its_axle(urdf):
    """A URDF cylinder's axis is its z; rotated by roll pi/2 about x it lies along y, the
    wheel's spin axis, with the wheel's radius. Planted: the origin's tag upper-cased (the
    rotation dropped by any parser)."""
    p, text = urdf
    root = _parse(text)
    wheels = {"rear_wheel": p.R_rear, "front_wheel": p.R_front}
    for link in root.findall("link"):
        col = link.find("collision")
        if link.get("name") not in wheels:
            assert col is None
            continue
        assert col.find("origin").get("rpy") == "1.5707963267948966 0 0"
        cyl = col.find("geometry/cylinder")
        assert float(cyl.get("radius")) == wheels[link.get("name")]


def test_prismatic_joints_are_bounded_as_urdf_requires(urdf):
    """URDF requires a limit element on a prismatic joint; the bounds are wide enough never
    to act. Planted: the limit written as text."""
    _, text = urdf
    root = _parse(text)
    prismatic = [j for j in root.findall("joint") if j.get("type") == "prismatic"]
    assert [j.get("name") for j in prismatic] == ["xc", "yc"]
    for j in prismatic:
        lim = j.find("limit")
        assert {k: float(v) for k, v in lim.attrib.items()} == \
            {"lower": -1e9, "upper": 1e9, "effort": 0.0, "velocity": 1e9}


def test_the_header_comment_gives_what_urdf_has_no_field_for(urdf):
    """The comment before the robot element states the units and g (read back as a number)
    and the rolling contact URDF cannot express. Planted: the units, g's unit or the
    sentence garbled, the comment's opening or closing."""
    import re
    p, text = urdf
    _parse(text)
    assert text.index("<!--") < text.index("-->") < text.index("<robot ")
    header = " ".join(text.split("<!--", 1)[1].split("-->", 1)[0].split())
    found = re.search(r"Units SI; gravity -z, g = (\S+) m/s\^2\.", header)
    assert found and float(found.group(1)) == p.g, header
    assert "NOT EXPRESSIBLE IN URDF: the rolling contact." in header
    assert "the JSON export of the same model describes them." in header
