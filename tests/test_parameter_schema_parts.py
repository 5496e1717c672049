"""Parts of the parameter schema (reference_model/parameters/schema.py), issue 24: the
one-line ParameterError of a value that is not a number in both input languages (TOML and
Python literals), the fix of a sign error, the bound edges (inclusive, per the module's
``[low, high]`` and ``[usual_low, usual_high]``), the wording of an unusual value's warning
and where it points, the edge of the triangle inequality's tolerance, the rounding of the
principal moments in its message and the triangle-mode error. Expected values come from
the module docstring's contract (message ``<file>: <table.key>: <problem>; fix: <fix>``),
the stated bounds (docs/model.md's parameter table), the thesis parameters typed in by hand
(tests/thesis_params.py) and hand computations. Planted bugs each test was seen failing on
are named in it."""

import inspect
import math
import re
import warnings

import numpy as np
import pytest

from reference_model.parameters import Parameters
from reference_model.parameters.schema import (PARAMETER_NAMES, ParameterError, ParameterWarning,
                                               TriangleInequalityError, as_real, check_bounds,
                                               check_inertia, check_signs, check_triangle_mode)
from thesis_params import THESIS_PARAMS


def _values(**changes):
    values = {n: float(THESIS_PARAMS[n]) for n in PARAMETER_NAMES}
    values.update(changes)
    return values


def _error(fn, *args, **kwargs):
    with pytest.raises(ParameterError) as info:
        fn(*args, **kwargs)
    return info.value


# -- as_real: values that are not numbers ---------------------------------------------------------

@pytest.mark.parametrize("value, spelled", [(True, "true"), (False, "false"),
                                            (np.bool_(True), "true")])
def test_a_boolean_in_a_toml_file_is_spelled_as_toml_and_the_fix_is_toml(value, spelled):
    """A TOML boolean is reported in TOML spelling ("value true") with the fix
    "value = 1.0" (as_real's docstring). Planted: the Python repr in TOML mode; "true" for
    False; "TRUE"/"XXtrueXX"/"XXfalseXX"; no fix; the Python example in TOML mode."""
    e = _error(as_real, "bike.toml", "mass.m2", value)
    assert e.problem == f"value {spelled} is a boolean, not a number"
    assert e.fix == "write a finite real number, e.g. value = 1.0"
    assert str(e) == (f"bike.toml: mass.m2: value {spelled} is a boolean, not a number; "
                      "fix: write a finite real number, e.g. value = 1.0")


def test_a_boolean_given_in_python_is_spelled_as_python_and_the_fix_is_a_literal():
    """With python_literals the boolean is "True" and the example is "1.02" (as_real's
    docstring). Planted: the TOML example in Python mode; "XX1.02XX"."""
    e = _error(as_real, "<memory>", "mass.m2", True, python_literals=True)
    assert e.problem == "value True is a boolean, not a number"
    assert e.fix == "write a finite real number, e.g. 1.02"


def test_a_quoted_number_is_told_to_lose_its_quotes_in_the_inputs_language():
    """A number in quotes: in TOML the fix shows the unquoted line, in Python just "remove
    the quotes". Planted: the Python fix in TOML mode; the TOML fix in Python mode;
    "XXremove the quotesXX"."""
    toml = _error(as_real, "bike.toml", "mass.m2", " 2.5 ")
    assert toml.problem == "value ' 2.5 ' is a string, not a number"
    assert toml.fix == "remove the quotes: value = 2.5"
    python = _error(as_real, "<memory>", "mass.m2", "2.5", python_literals=True)
    assert python.fix == "remove the quotes"


def test_a_value_of_another_type_names_its_type_and_every_part_of_the_message():
    """A list is no real number: the problem names the value and its type "list", and the
    error carries file, key, problem and fix, in the one-line order. Planted: the type of
    None named; no problem; no file, key or fix; parts shifted by a dropped argument."""
    e = _error(as_real, "bike.toml", "geometry.x3", [1.0])
    assert type(e) is ParameterError
    assert (e.file, e.key) == ("bike.toml", "geometry.x3")
    assert e.problem == "value [1.0] of type list is not a real number"
    assert e.fix == "write a finite real number, e.g. value = 1.0"
    assert str(e) == ("bike.toml: geometry.x3: value [1.0] of type list is not a real number; "
                      "fix: write a finite real number, e.g. value = 1.0")


def test_a_non_finite_number_has_the_fix_of_a_finite_one():
    """inf is a real number but not a finite one: the fix asks for a finite number.
    Planted: no fix."""
    e = _error(as_real, "bike.toml", "environment.g", math.inf)
    assert e.problem == "value inf is not a finite real number"
    assert e.fix == "write a finite real number, e.g. value = 1.0"


# -- signs ----------------------------------------------------------------------------------------

def test_a_non_positive_mass_is_told_the_unit_of_a_positive_value():
    """m3 = 0 kg must be > 0: the fix names the unit kg. Planted: no fix."""
    e = _error(check_signs, "bike.toml", _values(m3=0.0))
    assert e.key == "mass.m3"
    assert e.fix == "use a positive value in kg"


def test_a_negative_drag_is_told_that_zero_disables_drag():
    """cv = -0.1 kg/m must be >= 0; the fix says 0 disables drag. Planted: no fix."""
    e = _error(check_signs, "bike.toml", _values(cv=-0.1))
    assert e.key == "environment.cv"
    assert e.fix == "use a non-negative value in kg/m (0 disables drag)"


# -- bounds ---------------------------------------------------------------------------------------

def test_the_bounds_are_inclusive_at_the_top_of_the_range_and_of_the_usual_range():
    """x3 = 10 m is the top of a position's range (|x| <= 10 m): unusual, not an error;
    g = 9.9 m/s^2 is the top of the usual range (9.7 to 9.9): no warning at all. Planted:
    x < high; x < usual_high."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_bounds("bike.toml", _values(x3=10.0))
    assert [type(w.message) for w in caught] == [ParameterWarning]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_bounds("bike.toml", _values(g=9.9))


def test_check_bounds_alone_refuses_a_negative_mass_by_its_range():
    """The mass bound is on the signed value (1e-3 to 1e3 kg, not a magnitude): check_bounds
    called alone refuses m2 = -5 kg even though |m2| is in range. Planted: abs() of every
    value."""
    e = _error(check_bounds, "bike.toml", _values(m2=-5.0))
    assert e.key == "mass.m2"
    assert "outside the range of a wheel (0.001 to 1000 kg" in e.problem


def _warning(**changes):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_bounds("bike.toml", _values(**changes))
    (w,) = caught
    return str(w.message)


def test_an_unusual_signed_length_is_worded_as_a_magnitude():
    """x3 = 4 m: usual is |x3| <= 3 m (a magnitude bound starting at 0), and the whole
    one-line message follows the ParameterError format. Planted: the "low to high" wording
    for a magnitude; usual_low != 0; usual_low == 1; the fix text changed or uppercased."""
    assert _warning(x3=4.0) == (
        "bike.toml: geometry.x3: x3 = 4.0 m is unusual for a position within the bicycle "
        "(usual: |x3| <= 3 m); fix: check the value and its unit, or ignore this warning if "
        "it is intended")


def test_an_unusual_drag_is_worded_as_a_range_not_a_magnitude():
    """cv = 6 kg/m: cv is not a magnitude bound, so the usual range is "0 to 5 kg/m" although
    it starts at 0. Planted: magnitude OR usual_low == 0."""
    assert "(usual: 0 to 5 kg/m)" in _warning(cv=6.0)


def test_an_unusual_value_warning_points_at_the_callers_line():
    """Parameters(...) with the Moon's g (1.62 m/s^2) warns, and the warning points at the
    line that built the parameters (caller -> __init__ -> __post_init__ -> check_bounds).
    Planted: stacklevel 1 (the schema's own line); stacklevel 5 (beyond the caller)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        line = inspect.currentframe().f_lineno + 1
        Parameters(**_values(g=1.62))
    (w,) = [w for w in caught if isinstance(w.message, ParameterWarning)]
    assert (w.filename, w.lineno) == (__file__, line)


# -- inertia --------------------------------------------------------------------------------------

def test_a_tensor_exactly_at_the_triangle_tolerance_is_accepted():
    """With zz = 1 the largest moment, the tolerance is 1e-12 kg*m^2; xx + yy exactly
    1 - 1e-12 meets I1 + I2 >= I3 - tol (accepted) and one ulp less is refused. Planted:
    others > I3 - tol (the edge refused)."""
    edge = 1.0 - 1e-12
    yy = edge - 0.5                # exact (Sterbenz), so 0.5 + yy == edge exactly
    assert 0.5 + yy == edge
    check_inertia("bike.toml", 2, _values(I2xx=0.5, I2yy=yy, I2zz=1.0))
    with pytest.raises(TriangleInequalityError):
        check_inertia("bike.toml", 2, _values(I2xx=0.5, I2yy=np.nextafter(yy, 0.0), I2zz=1.0))


def test_the_principal_moments_in_a_triangle_error_are_rounded_to_twelve_decimals():
    """I3 = [[1, 0, 0.3], [0, 0.1, 0], [0.3, 0, 0.6]]: principal moments 0.8 +- sqrt(0.13)
    and 0.1, so 1.1605... > 0.1 + 0.4394...: refused, the moments printed to 12 decimals and
    equal to numpy's eigenvalues. Planted: 13 decimals."""
    e = _error(check_inertia, "bike.toml", 3, _values(I3xx=1.0, I3yy=0.1, I3zz=0.6, I3xz=0.3))
    printed = re.search(r"principal moments \(([-\d.e, ]*)\)", e.problem).group(1).split(", ")
    r = math.sqrt(0.13)
    for text, expected in zip(printed, (0.8 + r, 0.1, 0.8 - r)):
        assert len(text.split(".")[1]) <= 12
        assert float(text) == pytest.approx(expected, abs=1e-12)
    assert sorted(float(t) for t in printed) == pytest.approx(
        np.linalg.eigvalsh([[1.0, 0, 0.3], [0, 0.1, 0], [0.3, 0, 0.6]]), abs=1e-12)


# -- triangle mode --------------------------------------------------------------------------------

def test_an_unknown_triangle_mode_names_the_file_and_the_two_modes():
    """checks.triangle = "loose" is unknown: the error names the file and the fix lists
    "strict" (the default) and "warn". Planted: no file; the fix text changed."""
    e = _error(check_triangle_mode, "bike.toml", "loose")
    assert (e.file, e.key) == ("bike.toml", "checks.triangle")
    assert e.fix == 'use "strict" (refuse, the default) or "warn" (load and record a warning)'
    assert str(e).startswith("bike.toml: checks.triangle: unknown triangle-inequality check mode "
                             "'loose'; fix: use \"strict\"")
