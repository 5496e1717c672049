"""Parts of reference_model/parameters/values.py that the round trips of ``Parameters`` do not
pin, issue 24: a ``source`` given as a path (stored as its string), the one-line errors of a
source or a name that is not a string and of an unknown triangle mode (file, key, problem and
fix, the parts a user reads), the fix of a strict triangle-inequality refusal (how to allow
it), a parameter vector with a gap, and ``attach_benchmark``'s table name in its errors.

Expected values come from the documented contract (``ParameterError``'s message
``<file>: <table.key>: <problem>; fix: <fix>``, the class docstring: ``source`` is the file
the set was read from, ``"<memory>"`` if built in code) and from Meijaard et al. (2007)
Table 1 (the benchmark bicycle: rear wheel IRxx = 0.0603, IRyy = 0.12 kg m^2, so a polar
moment 0.2 > 2 * 0.0603 = 0.1206 breaks the triangle inequality). Each test names the planted
bugs (mutmut's survivors of the module's measurement) it was seen failing on.
"""

from __future__ import annotations

import pathlib

import pytest

from reference_model.parameters import (PARAMETER_NAMES, TABLE1, ParameterError, Parameters,
                                        TriangleInequalityError, attach_benchmark,
                                        parameters_from_benchmark)


@pytest.fixture(scope="module")
def bench() -> Parameters:
    """The Meijaard et al. (2007) benchmark bicycle, built from its Table 1."""
    return parameters_from_benchmark(TABLE1.as_dict(), name="benchmark", source="bench.toml")


def _fields(p: Parameters) -> dict[str, float]:
    return {n: getattr(p, n) for n in PARAMETER_NAMES}


# -- source -------------------------------------------------------------------------------------


def test_a_path_source_is_stored_as_its_string(bench):
    """``source`` is "the file it was read from": a ``pathlib`` path is accepted and kept as
    the plain string of the path (what every error message then names). Planted: the
    conversion dropped (source None, os.fspath(None)), stored on another attribute name
    ("XXsourceXX", "SOURCE") or on nothing, or the attribute set to None."""
    p = Parameters(**_fields(bench), source=pathlib.PurePosixPath("models/bike.toml"))
    assert p.source == "models/bike.toml"
    assert type(p.source) is str
    with pytest.raises(ParameterError) as err:
        p.replace(triangle="sometimes")
    assert err.value.file == "models/bike.toml"


def test_a_source_that_is_not_a_string_is_one_error_naming_it(bench):
    """A source of 42 is refused with file ``'42'`` (its repr), key ``source``, problem
    "source must be a string" and fix "pass a file path or '<memory>'", in the documented
    one-line form. Planted: any of the four parts replaced by None or left out (a TypeError
    instead), repr(None) for the file, and the key, problem or fix misspelled."""
    with pytest.raises(ParameterError) as err:
        Parameters(**_fields(bench), source=42)
    e = err.value
    assert (e.file, e.key, e.problem, e.fix) == (
        "42", "source", "source must be a string", "pass a file path or '<memory>'")
    assert str(e) == "42: source: source must be a string; fix: pass a file path or '<memory>'"


def test_a_name_that_is_not_a_string_is_one_error_naming_the_file(bench):
    """A model name of 7 is refused naming the file, key ``model.name``, problem "name 7 is
    not a string" and fix "use a string name". Planted: any of the four parts replaced by
    None or left out (a TypeError instead), and the key or fix misspelled."""
    with pytest.raises(ParameterError) as err:
        Parameters(**_fields(bench), name=7, source="bike.toml")
    e = err.value
    assert (e.file, e.key, e.problem, e.fix) == (
        "bike.toml", "model.name", "name 7 is not a string", "use a string name")
    assert str(e) == "bike.toml: model.name: name 7 is not a string; fix: use a string name"


def test_an_unknown_triangle_mode_names_the_file(bench):
    """An unknown triangle mode is refused naming the file the set came from (the key is
    ``checks.triangle``). Planted: None passed as the file (the message read 'None: ...')."""
    with pytest.raises(ParameterError) as err:
        Parameters(**_fields(bench), source="bike.toml", triangle="sometimes")
    assert err.value.file == "bike.toml"
    assert err.value.key == "checks.triangle"
    assert str(err.value).startswith("bike.toml: checks.triangle: ")


# -- the triangle inequality --------------------------------------------------------------------


def test_a_strict_triangle_refusal_says_how_to_allow_a_measured_body(bench):
    """The benchmark's rear wheel with I2yy = 0.2 > I2xx + I2zz = 0.1206 kg m^2 is refused in
    "strict" mode; the fix names the three moments to check and then both ways to allow
    measured values: the file's ``[checks] triangle = "warn"`` and the keyword
    ``allow_triangle_violation=True``. Planted: that sentence misspelled ('XX...XX',
    'allow_triangle_violation=true', not a Python literal)."""
    with pytest.raises(TriangleInequalityError) as err:
        bench.replace(I2yy=0.2)
    assert err.value.key == "inertia.I2yy"
    assert err.value.fix == (
        "check the values and units of I2xx, I2yy, I2zz; if the values are measured and right, "
        'allow it with [checks] triangle = "warn" (or allow_triangle_violation=True)')


# -- vectors ------------------------------------------------------------------------------------


def test_a_vector_with_a_gap_is_one_parameter_error_naming_the_parameter(bench):
    """A parameter vector with a missing entry (None where R_front belongs) is read as
    float64 (None is NaN) and refused by the value checks with one ParameterError naming
    ``R_front`` and the source, like any other non-finite value, not a bare TypeError.
    Planted: the vector read without dtype=float64 (float(None) raised TypeError)."""
    v = [float(x) for x in bench.vector()]
    v[PARAMETER_NAMES.index("R_front")] = None
    with pytest.raises(ParameterError) as err:
        Parameters.from_vector(v, source="vec.txt")
    assert err.value.file == "vec.txt"
    assert err.value.key == "geometry.R_front"
    assert "nan" in err.value.problem


# -- attach_benchmark ---------------------------------------------------------------------------


def test_attach_benchmark_names_the_table_it_was_given(bench):
    """The Table 1 attached from a file's table called ``reference`` is checked against the
    model; a w = 1.5 m that does not give the model's wheelbase (1.02 m in Table 1) is refused
    naming ``[reference]`` both in the problem and in the fix. Planted: the key not passed
    on (the message named the default ``[benchmark]`` table)."""
    good = attach_benchmark(bench, TABLE1.as_dict(), key="reference")
    assert good.benchmark is not None
    with pytest.raises(ParameterError) as err:
        attach_benchmark(bench, {**TABLE1.as_dict(), "w": 1.5}, key="reference")
    assert err.value.file == "bench.toml"
    assert "does not follow from the [reference] table" in err.value.problem
    assert "remove the [reference] table" in err.value.fix
    assert "[benchmark]" not in str(err.value)
