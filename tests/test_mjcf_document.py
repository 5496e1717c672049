"""The MJCF export's document and settings (reference_model/exports/mjcf.py), issue 24: the
file's layout (every line after the comment one element, indented two spaces per level of
nesting, no character data: MJCF has none), the comment's facts for each variant, and every
setting's refusal: its bounds as MuJoCo documents them (solimp: 0 < dmin <= dmax < 1,
width > 0, 0 < midpoint < 1, power >= 1, MuJoCo's XML reference, "solimp"), the field named
in the one-line error, and the example the error suggests accepted when given. Each test
names the planted bugs (mutmut's survivors of its first run) it was seen failing on."""

import ast
import re
import xml.etree.ElementTree as ET

import pytest

from reference_model import load_model
from reference_model.exports.mjcf import MjcfSettings, mjcf_text


@pytest.fixture(scope="module")
def params():
    return load_model("benchmark").params


def _body(text):
    """The lines after the comment block."""
    return text.split("-->\n", 1)[1].splitlines()


@pytest.mark.parametrize("rear_height", [False, True])
def test_each_line_is_one_element_indented_by_its_depth(params, rear_height):
    """The depth of each tag, counted here from the tags themselves (an opening tag nests
    what follows, a closing one ends it), sets its indentation at two spaces a level; no line
    holds text outside a tag (MJCF elements have no character data), and the document parses
    to one <mujoco> with every body closed. Planted: the chain's indentation not grown per
    link (`=` for `+=`), its closing tags dedented by 1 or 3 levels, or never; text around
    a closing tag ('XX  </worldbody>XX'), the lines joined by more than a newline; the slide's
    joint not named zc (the MuJoCo engine reads it by name)."""
    lines = _body(mjcf_text(params, rear_height=rear_height))
    depth = 0
    for ln in lines:
        m = re.fullmatch(r"( *)(<(/?)[a-z]+\b[^<>]*?(/?)>)", ln)
        assert m, f"not one element on its own line: {ln!r}"
        indent, closing, selfclosing = len(m.group(1)), m.group(3), m.group(4)
        if closing:
            depth -= 1
        assert indent == 2 * depth, ln
        if not closing and not selfclosing:
            depth += 1
    assert depth == 0
    root = ET.fromstring("\n".join(lines))
    assert root.tag == "mujoco"
    assert all((e.text or "").strip() == "" and (e.tail or "").strip() == "" for e in root.iter())
    links = ["xc_link", "yc_link"] + (["zc_link"] if rear_height else []) + ["yaw", "lean"]
    chain = root.find("worldbody")
    joints = ["xc", "yc"] + (["zc"] if rear_height else []) + ["phi", "theta"]
    for name, joint in zip(links, joints):      # each massless link nests the next
        chain = chain.find("body")
        assert chain.get("name") == name and chain.find("joint").get("name") == joint
    assert [b.get("name") for b in chain.findall("body")] == ["rear_wheel", "frame"]


def test_the_comment_states_the_variant_it_describes(params):
    """The comment tells a reader what the file leaves out: the rear contact's height is a
    slide zc in the forward-run variant (and said so), while the export's own variant tells
    how to add it; g and cv in the model's numbers. Planted: either variant's sentence given
    to both or to none (`and False`, `or True`); the contact's note wrong for the thesis's
    fork-axis contact (the file only approximates the disc's)."""
    export = mjcf_text(params).split("-->")[0]
    run = mjcf_text(params, rear_height=True).split("-->")[0]
    assert "with a slide zc" not in export and "FOR A FORWARD RUN" in export
    assert "with a slide zc" in run and "FOR A FORWARD RUN" not in run
    assert f"g = {params.g:g} m/s^2" in export.replace("\n", " ") or f"g = {params.g!r}" in export
    assert "cv = " in export
    thesis = mjcf_text(load_model("thesis").params).split("-->")[0].replace("\n  ", " ")
    assert "approximates this model's rolling-disc contact" in export.replace("\n  ", " ")
    assert "NOT this model's thesis fork-axis front contact" in thesis


def test_settings_are_stored_as_floats_whatever_sequence_is_given():
    """solref and solimp given as lists of ints and floats are kept as tuples of floats (as
    the dataclass's types and `as_dict` say), the scalars as floats. Planted: the checked
    tuples stored under another name (the input list kept)."""
    s = MjcfSettings(solref=[1, 1], solimp=[0.9, 0.95, 1, 0.5, 2], timestep=1, friction=2)
    assert s.solref == (1.0, 1.0) and type(s.solref) is tuple
    assert s.solimp == (0.9, 0.95, 1.0, 0.5, 2.0) and type(s.solimp) is tuple
    assert type(s.timestep) is float and type(s.friction) is float


@pytest.mark.parametrize("field, allowed", [
    ("integrator", ("Euler", "implicit", "implicitfast", "RK4")),   # MuJoCo's option/integrator
    ("cone", ("elliptic", "pyramidal")),
    ("solver", ("Newton", "CG", "PGS")),
])
def test_a_choice_lists_what_mujoco_accepts(field, allowed):
    """The refusal lists MuJoCo's own values for the attribute (its XML reference), comma
    separated. Planted: the separator changed."""
    with pytest.raises(ValueError, match=f"must be one of {', '.join(allowed)}; fix: "):
        MjcfSettings(**{field: "nope"})


def test_condim_lists_mujocos_contact_dimensions():
    """MuJoCo's condim for a frictional contact: 3, 4 or 6 (1 is frictionless). Planted: the
    separator changed."""
    with pytest.raises(ValueError, match=r"^MJCF setting condim = 2: must be one of 3, 4, 6; fix: 3 "):
        MjcfSettings(condim=2)


def test_the_arguments_are_checked_by_type(params):
    """Planted: the TypeErrors' messages lost (None)."""
    with pytest.raises(TypeError, match=r"^mjcf_text needs a reference_model.Parameters, got dict$"):
        mjcf_text({"g": 9.81})
    with pytest.raises(TypeError, match=r"^settings must be an MjcfSettings, got dict$"):
        mjcf_text(params, {"timestep": 1e-4})


@pytest.mark.parametrize("solimp, ok", [
    ((1e-9, 0.999, 1e-3, 0.5, 2.0), True),
    ((0.0, 0.999, 1e-3, 0.5, 2.0), False),      # dmin = 0
    ((0.9, 0.9, 1e-3, 0.5, 2.0), True),         # dmin = dmax
    ((0.99, 1.0, 1e-3, 0.5, 2.0), False),       # dmax = 1
    ((0.99, 1.5, 1e-3, 0.5, 2.0), False),
    ((0.99, 0.999, 0.0, 0.5, 2.0), False),      # width = 0
    ((0.99, 0.999, 1e-3, 0.0, 2.0), False),     # midpoint = 0
    ((0.99, 0.999, 1e-3, 1.0, 2.0), False),     # midpoint = 1
    ((0.99, 0.999, 1e-3, 1.5, 2.0), False),
    ((0.99, 0.999, 1e-3, 0.5, 1.0), True),      # power = 1
    ((0.99, 0.999, 1e-3, 0.5, 1.5), True),
    ((0.99, 0.999, 1e-3, 0.5, 0.5), False),
])
def test_solimp_has_mujocos_bounds(solimp, ok):
    """MuJoCo's solimp: 0 < dmin <= dmax < 1, width > 0, 0 < midpoint < 1, power >= 1, each
    bound tried at its edge. Planted: every comparison's edge moved (`<=` for `<`, `<` for
    `<=`, 2 for 1, `>` for `>=`); the refusal's fix mangled."""
    if ok:
        assert MjcfSettings(solimp=solimp).solimp == solimp
    else:
        with pytest.raises(ValueError, match=r"^MJCF setting solimp = .*: needs 0 < dmin <= dmax < 1, "
                           r"width > 0, 0 < midpoint < 1, power >= 1; fix: e\.g\. (\(.*\))$") as err:
            MjcfSettings(solimp=solimp)
        example = ast.literal_eval(re.search(r"e\.g\. (\(.*\))$", str(err.value)).group(1))
        assert MjcfSettings(solimp=example).solimp == example      # the suggested fix works


BAD = [
    ("timestep", -1e-4), ("timestep", "1e-4"), ("timestep", True), ("timestep", float("nan")),
    ("integrator", "rk4"), ("cone", "round"), ("solver", "LU"), ("condim", 1),
    ("noslip_iterations", -1), ("iterations", 2.5),
    ("friction", 0.0), ("tolerance", -1.0), ("wheel_half_width", 0),
    ("solref", "abc"), ("solref", (True, 1.0)), ("solref", (1e-3,)),
    ("solimp", (0.9, 0.95, 1e-3, 0.5)),
]


@pytest.mark.parametrize("field, value", BAD)
def test_a_bad_setting_is_named_with_a_fix_that_works(field, value):
    """Each bad value: a ValueError (not a TypeError from deeper down) naming the field and
    the value; the example the fix gives ('e.g. X', condim's '3 for ...') is a valid setting.
    Planted: the field's name lost or changed in its check (None), its fix lost, a string or
    a bool let through to math.isfinite or accepted (`and` for `or` in `_positive`), an
    unparsable tuple left None, bools in a tuple accepted."""
    with pytest.raises(ValueError) as err:
        MjcfSettings(**{field: value})
    msg = str(err.value)
    assert msg.startswith(f"MJCF setting {field} = {value!r}: "), msg
    fix = msg.split("; fix: ", 1)[1]
    assert "\n" not in msg and fix and fix != "None"
    example = re.search(r"e\.g\. (.+?)(?: m)?$", fix) or re.match(r"(\S+) for ", fix)
    assert example, fix
    raw = example.group(1)
    try:
        parsed = ast.literal_eval(raw)
    except (ValueError, SyntaxError):
        parsed = raw                       # a name: Euler, elliptic, Newton
    assert MjcfSettings(**{field: parsed}) is not None


@pytest.mark.parametrize("which, value", [(0, 0.0), (1, -1.0)])
def test_each_solref_number_is_named_apart(which, value):
    """solref's time constant and damping ratio each refused by its own name. Planted: the
    name or the fix not passed on (None)."""
    solref = [2e-4, 1.0]
    solref[which] = value
    name = ("solref time constant", "solref damping ratio")[which]
    with pytest.raises(ValueError, match=rf"^MJCF setting {name} = {value!r}: must be a positive "
                       r"finite number; fix: solref = \(time constant s, damping ratio\), both > 0$"):
        MjcfSettings(solref=tuple(solref))
