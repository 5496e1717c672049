"""Parts of the parameter file reader and writer (reference_model/parameters/model_file.py),
issue 24: the one-line error contract (file, ``table.key``, problem, fix) of each structural
problem (a table written as a value, a parameter outside any table, an unknown table or key,
a misplaced or missing table), of a malformed entry (no value, no unit, a unit that is not a
string) and of a TOML syntax error, plus the documented default name "custom". Expected
values come from the module docstring (five tables, the accepted units, "the closest valid
name"), the ParameterError contract in schema.py and Table 1's layout. Planted bugs each test
was seen failing on are named in it."""

import copy
import tomllib

import pytest

from reference_model.parameters.benchmark import TABLE1
from reference_model.parameters.model_file import (parameters_from_mapping, syntax_error,
                                                   toml_text)
from reference_model.parameters.schema import ParameterError

FILE = "bike.toml"
VALID_TABLES = "model, geometry, mass, inertia, environment, checks, benchmark"
MASS_TEMPLATE = 'm2 = { value = ..., unit = "kg" }'


@pytest.fixture(scope="module")
def base():
    """A valid document (the benchmark bicycle as the writer writes it), without [benchmark]
    so that edits to the model's values are not checked against Table 1."""
    data = tomllib.loads(toml_text(TABLE1, name="bench", source="Meijaard 2007"))
    del data["benchmark"]
    return data


def _error(data, **kwargs):
    with pytest.raises(ParameterError) as info:
        parameters_from_mapping(data, source=FILE, **kwargs)
    return info.value


def _parts(err):
    return err.file, err.key, err.problem, err.fix


# -- structure: tables ---------------------------------------------------------------------------

def test_a_table_written_as_a_value_names_the_file_the_table_and_the_fix(base):
    """``mass = 3`` where [mass] is required: the error names the file, the key 'mass', the
    type found and the fix. Planted: the file dropped, the key dropped, the problem or the fix
    dropped or swapped, the type name of None reported."""
    data = copy.deepcopy(base)
    data["mass"] = 3
    err = _error(data)
    assert _parts(err) == (FILE, "mass", "'mass' must be a table, got int",
                           "write it as a [mass] table")
    assert str(err) == ("bike.toml: mass: 'mass' must be a table, got int; "
                        "fix: write it as a [mass] table")


def test_a_parameter_outside_any_table_is_told_its_table(base):
    """``m2 = 2.6`` at the top level belongs under [mass] (Table: mass m2 m3 m4 m5). Planted:
    the file dropped; the fix dropped."""
    data = copy.deepcopy(base)
    data["m2"] = 2.6
    assert _parts(_error(data)) == (FILE, "m2", "parameter 'm2' is outside any table",
                                    "put it under [mass]")


def test_an_unknown_table_gets_the_closest_name_and_the_list_of_valid_tables(base):
    """[geometri] is a misspelling of [geometry]; [zzzzzz] resembles nothing and is to be
    removed; both fixes list the seven tables of the docstring. Planted: 'did you mean' without
    a hint, the key dropped, the 'remove it' text or the list separator changed."""
    data = copy.deepcopy(base)
    data["geometri"] = {}
    assert _parts(_error(data)) == (FILE, "geometri", "unknown table [geometri]",
                                    f"did you mean [geometry]? valid tables are {VALID_TABLES}")
    data = copy.deepcopy(base)
    data["zzzzzz"] = {}
    assert _parts(_error(data)) == (FILE, "zzzzzz", "unknown table [zzzzzz]",
                                    f"remove it valid tables are {VALID_TABLES}")


def test_a_missing_table_is_named_with_its_keys(base):
    """Without [environment] the fix lists its keys g and cv (docstring: ``[environment]
    # g cv``). Planted: the file dropped; the fix dropped; the list separator changed."""
    data = copy.deepcopy(base)
    del data["environment"]
    assert _parts(_error(data)) == (FILE, "environment", "table [environment] is missing",
                                    "add a [environment] table with g, cv")


def test_a_parameter_in_the_wrong_table_is_told_where_it_belongs(base):
    """m2 written in [geometry] is moved to [mass]. Planted: the fix dropped."""
    data = copy.deepcopy(base)
    data["geometry"]["m2"] = data["mass"]["m2"]
    assert _parts(_error(data)) == (FILE, "geometry.m2", "'m2' belongs in [mass], not in [geometry]",
                                    "move it to [mass]")


# -- structure: [checks] and [model] -----------------------------------------------------------

def test_an_unknown_key_in_checks_lists_the_valid_keys(base):
    """[checks] has one key, triangle. Planted: the file dropped; the fix dropped; the list
    separator changed."""
    data = copy.deepcopy(base)
    data["checks"] = {"speed": "fast"}
    assert _parts(_error(data)) == (FILE, "checks.speed", "unknown key 'speed' in [checks]",
                                    "remove it; valid keys in [checks] are triangle")


def test_an_unknown_key_in_model_gets_the_closest_key_and_the_valid_keys(base):
    """[model] keys are name, description, source, contact (docstring). 'nmae' is a
    misspelling of 'name'; 'zzzz' resembles nothing. Planted: the [model] table not read
    (wrong table name), no hint searched, the hint always or never used, the file, key,
    problem or fix dropped, the parts concatenated wrongly."""
    data = copy.deepcopy(base)
    data["model"]["nmae"] = "x"
    assert _parts(_error(data)) == (
        FILE, "model.nmae", "unknown key 'nmae' in [model]",
        "did you mean 'name'? valid keys in [model] are name, description, source, contact")
    data = copy.deepcopy(base)
    data["model"]["zzzz"] = "x"
    assert _parts(_error(data)) == (
        FILE, "model.zzzz", "unknown key 'zzzz' in [model]",
        "remove it; valid keys in [model] are name, description, source, contact")


def test_a_model_value_that_is_not_a_string_is_told_to_be_quoted(base):
    """``name = 3`` in [model]: the fix shows the quoted form. Planted: the fix dropped."""
    data = copy.deepcopy(base)
    data["model"]["name"] = 3
    assert _parts(_error(data)) == (FILE, "model.name", "value 3 is not a string",
                                    'write it in quotes, e.g. name = "..."')


def test_an_unknown_triangle_mode_names_the_file(base):
    """``[checks] triangle = "maybe"`` is refused, naming the file. Planted: the file not
    passed to the mode check."""
    data = copy.deepcopy(base)
    data["checks"] = {"triangle": "maybe"}
    err = _error(data)
    assert (err.file, err.key) == (FILE, "checks.triangle")


def test_without_a_name_the_model_is_called_custom(base):
    """The documented default_name is "custom" when neither name= nor [model].name is given.
    Planted: another default name."""
    data = copy.deepcopy(base)
    del data["model"]["name"]
    assert parameters_from_mapping(data).name == "custom"


# -- entries -------------------------------------------------------------------------------------

def test_an_entry_with_an_unknown_field_and_no_close_one_shows_the_template(base):
    """``m2 = { value = 2.6, unit = "kg", zzzz = 1 }``: nothing resembles 'zzzz', so the fix is
    only the template (no 'did you mean'). Planted: the hint always used; the empty prefix
    replaced by text."""
    data = copy.deepcopy(base)
    data["mass"]["m2"] = {"value": 2.6, "unit": "kg", "zzzz": 1}
    assert _parts(_error(data)) == (FILE, "mass.m2", "unknown field 'zzzz' in the entry of m2",
                                    f"write {MASS_TEMPLATE}")


def test_an_entry_without_a_value_shows_the_template(base):
    """``m2 = { unit = "kg" }`` has no value: the error names file, key mass.m2, the problem
    and the template with m2's canonical unit kg. Planted: any of the four parts dropped or
    changed; the template of no name."""
    data = copy.deepcopy(base)
    data["mass"]["m2"] = {"unit": "kg"}
    err = _error(data)
    assert _parts(err) == (FILE, "mass.m2", "the entry has no 'value'", f"write {MASS_TEMPLATE}")
    assert str(err) == f"bike.toml: mass.m2: the entry has no 'value'; fix: write {MASS_TEMPLATE}"


def test_an_entry_without_a_unit_is_told_the_canonical_unit(base):
    """``m2 = { value = 2.6 }``: a plain number means kg (docstring). Planted: the problem
    text changed."""
    data = copy.deepcopy(base)
    data["mass"]["m2"] = {"value": 2.6}
    assert _parts(_error(data)) == (
        FILE, "mass.m2", "unit missing",
        'add unit = "kg", or write a plain number, which means kg')


def test_a_unit_that_is_not_a_string_is_a_parameter_error_listing_the_mass_units(base):
    """``unit = 1`` is not an accepted mass unit; the accepted ones are kg and g (docstring).
    Planted: .strip() called on the number (AttributeError instead of the error); the fix's
    text or separator changed."""
    data = copy.deepcopy(base)
    data["mass"]["m2"] = {"value": 2.6, "unit": 1}
    assert _parts(_error(data)) == (FILE, "mass.m2", "unit 1 is not an accepted mass unit",
                                    "use one of 'kg', 'g'")


# -- syntax errors -------------------------------------------------------------------------------

def test_a_syntax_error_quotes_the_offending_line():
    """``g = `` on line 2 is invalid TOML: the error names line 2 and quotes the line."""
    text = 'cv = 0.0\ng = \n'
    with pytest.raises(tomllib.TOMLDecodeError) as info:
        tomllib.loads(text)
    err = syntax_error(FILE, text, info.value)
    assert (err.file, err.key) == (FILE, "line 2")
    assert err.problem == "invalid TOML at line 2, column 5: Invalid value: 'g ='"


def test_a_syntax_error_beyond_the_text_quotes_an_empty_line():
    """When the text given is shorter than the line the parser reports (e.g. the caller passes
    only the start of the file), no line is quoted: the quote is ''. Planted: the line
    looked up anyway (IndexError); another placeholder than the empty string."""
    with pytest.raises(tomllib.TOMLDecodeError) as info:
        tomllib.loads('cv = 0.0\ng = \n')
    err = syntax_error(FILE, "cv = 0.0", info.value)
    assert err.problem == "invalid TOML at line 2, column 5: Invalid value: ''"
