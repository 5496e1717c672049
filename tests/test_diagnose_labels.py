"""Diagnose's naming of causes and bodies (comparisons/judgments/diagnose.py), issue 24: which
body each parameter is printed with, and the one-line localization a user reads. Expected
bodies from the thesis's own symbols (docs/model.md, the parameter table): body 2 the rear
wheel (its radius, mass, inertia), 3 the frame+rider (its CoM x3, z3, mass, inertia, and the
drag cv acting at its CoM), 4 the fork/handlebar (the thesis's x4, z4 are our xa, za, the
steering-axis point where the fork is jointed; its CoM offsets dx4, dz4), 5 the front wheel
(its hub x5, z5, radius, mass, inertia); g acts on every body. mutmut credits the planted
engines' module fixture (tests/test_diagnose_planted.py) to its first test only, so these
small functions are checked here on their own. Each test names the planted bugs it was seen
failing on."""

import pytest

from comparisons.judgments.diagnose import (body_label, cause_body, cause_label,
                                            format_localization, parameter_body)
from reference_model.params import PARAMETER_NAMES

BODY = {"R_rear": 2, "m2": 2, "I2xx": 2, "I2yy": 2, "I2zz": 2,
        "x3": 3, "z3": 3, "m3": 3, "I3xx": 3, "I3yy": 3, "I3zz": 3, "I3xz": 3, "cv": 3,
        "xa": 4, "za": 4, "dx4": 4, "dz4": 4, "m4": 4, "I4xx": 4, "I4yy": 4, "I4zz": 4, "I4xz": 4,
        "x5": 5, "z5": 5, "R_front": 5, "m5": 5, "I5xx": 5, "I5yy": 5, "I5zz": 5,
        "g": None}


def test_every_parameter_has_its_body():
    """All 30 parameters, each with the body the thesis's symbols give it. Planted: any
    name's branch changed or dropped, the body loop starting at 3, the inertia prefix
    test dropped."""
    assert set(BODY) == set(PARAMETER_NAMES)
    assert {n: parameter_body(n) for n in PARAMETER_NAMES} == BODY


def test_a_structural_cause_has_its_body_and_label():
    """The front contact model belongs to the front wheel, the gyroscopic terms to no one
    body; both have a label a reader understands, a parameter is named by itself; an unknown
    name has no body. Planted: the contact's body, the labels' texts or keys."""
    assert cause_body("contact") == 5 and cause_body("gyroscopic") is None
    assert cause_body("I3xz") == 3 and cause_body("nonsense") is None
    assert cause_label("gyroscopic") == "gyroscopic terms w x (I w)"
    assert cause_label("contact") == "front contact model"
    assert cause_label("m4") == "m4"
    assert body_label(None) == "all bodies"
    assert [body_label(b) for b in (2, 3, 4, 5)] == ["body 2 rear wheel", "body 3 frame+rider",
                                                     "body 4 fork/handlebar", "body 5 front wheel"]


def test_a_localization_reads_in_the_terms_order():
    """The README's example line, the terms in the harness's order whatever order they are
    given in (dD dq and the accelerations last), several causes joined by ' + ', labels and a
    body text replacing the defaults. Planted: the terms in the given order, ', ' or ' + '
    changed, the body's parentheses, the labels or body text ignored, 'nothing' for no term."""
    assert format_localization(["Qv", "M"], ["I3xz"], 3) == "M, Qv via I3xz (body 3 frame+rider)"
    assert format_localization(["ddq", "dD dq", "D"], ["contact"], 5) == \
        "D, dD dq, ddq via front contact model (body 5 front wheel)"
    assert format_localization(["Qgrav"], ["g", "gyroscopic"], None) == \
        "Qgrav via g + gyroscopic terms w x (I w) (all bodies)"
    assert format_localization(["S"], ["x"], 4, labels=["the steer torque's sign"],
                               body_text=" (on the fork)") == "S via the steer torque's sign (on the fork)"
    assert format_localization([], ["m2"], 2) == "nothing via m2 (body 2 rear wheel)"
