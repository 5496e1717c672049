"""The fmu engine's mapping file (engines/fmu/mapping.py) read by `parse_mapping`, without any
FMU: a TOML text written here and the set of variable names an FMU would have.

The contract (docs/engines.md, "The fmu engine" / "The mapping file", and the module's
docstring): a value is an FMU variable name or ``{name = "...", scale = s}`` with thesis value
(SI) = s * FMU value; ``[coordinates]``, ``[rates]`` (the eight thesis coordinates xc ... eps)
and ``[torques]`` (Mdir, Mped, Mvue) are required, ``[baumgarte]`` (a1, a2), ``[terms]`` (M, F,
S, Qgrav, D, dDdq: a pattern with 1-based {i} and {j}), ``[residual]`` (rD_z, vC_x, vC_y, vD_x,
vD_y) and ``[parameters]`` (the thesis parameter names of docs/model.md) are optional; every
problem is one `MappingError` line that starts with where the mapping came from (the engine
passes ``mapping=PATH``) and names the field. The refusals are a user's only guide to a file
they write by hand, so each expected line is written out here whole: a message that loses its
``where``, its field, the offending value or its fix fails. The accepted mappings are checked
field by field against what the text says (names in the thesis's order, the scale written,
the documented default scale 1), so a parser that drops an optional table, reads it under
another key or requires it fails. Written from the survivors of `make mutants` on the module;
about 0.1 s (TOML parsing only).
"""

from __future__ import annotations

import tomllib

import pytest

from engines.fmu.mapping import FmuMapping, MappingError, Ref, parse_mapping

#: where the mapping came from, as the engine names it (engines/fmu/engine.py: mapping=PATH)
WHERE = "mapping=map.toml"
#: docs/engines.md: the eight thesis coordinates xc ... eps (docs/model.md's order)
COORDS = ("xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps")
TORQUES = ("Mdir", "Mped", "Mvue")
RESIDUAL = ("rD_z", "vC_x", "vC_y", "vD_x", "vD_y")
#: the fix of every unknown-variable refusal (docs/engines.md: "naming ... the fix")
UNKNOWN_FIX = "fix: use one of its variables (fmpy dump FILE.fmu lists them)"
#: one degree in radians: the docs' example scale for an FMU in degrees
DEG = 0.017453292519943295


def _fmu_names() -> frozenset[str]:
    """The variables of an FMU written like bicycle-xval's own (docs/engines.md, "The reference
    as an FMU": states q and d_q, inputs, a1, a2, outputs C.*, term.* with 1-based indices),
    with a few parameters by their thesis names and the coordinates' states in degrees."""
    names = set(COORDS) | {f"d_{c}" for c in COORDS} | set(TORQUES) | {"a1", "a2"}
    names |= {f"C.{k}" for k in RESIDUAL}
    names |= {f"term.M[{i},{j}]" for i in range(1, 9) for j in range(1, 9)}
    names |= {f"term.S[{i},{j}]" for i in range(1, 9) for j in range(1, 4)}
    names |= {f"term.{t}[{i}]" for t in ("F", "Qgrav") for i in range(1, 9)}
    names |= {f"term.D[{i},{j}]" for i in range(1, 6) for j in range(1, 9)}
    names |= {f"term.dDdq[{i}]" for i in range(1, 6)}
    names |= {"R_rear", "m3", "I3xz", "theta_deg"}
    return frozenset(names)


NAMES = _fmu_names()


def _sections() -> dict[str, list[str]]:
    """A complete mapping, table by table (the top-level ``contact`` under the key "")."""
    return {
        "": ['contact = "thesis"'],
        "coordinates": [f'{c} = "{c}"' for c in COORDS if c != "theta"]
        + [f'theta = {{name = "theta_deg", scale = {DEG!r}}}'],
        "rates": [f'{c} = "d_{c}"' for c in COORDS],
        "torques": [f'{t} = "{t}"' for t in TORQUES],
        "baumgarte": ['a1 = "a1"', 'a2 = "a2"'],
        "terms": ['M = "term.M[{i},{j}]"', 'F = "term.F[{i}]"', 'S = "term.S[{i},{j}]"',
                  'Qgrav = "term.Qgrav[{i}]"', 'D = "term.D[{i},{j}]"', 'dDdq = "term.dDdq[{i}]"'],
        "residual": [f'{k} = "C.{k}"' for k in reversed(RESIDUAL)],
        "parameters": ['R_rear = "R_rear"', 'm3 = {name = "m3", scale = 2}'],
    }


def _text(omit=(), top=(), **tables) -> str:
    """The complete mapping without the tables in ``omit``, with the top-level lines ``top``
    (before any table, where TOML needs them) and any table's lines replaced by ``tables``."""
    sections = _sections()
    sections.update(tables)
    lines = list(top) + [line for line in sections.pop("") if "" not in omit]
    for name, body in sections.items():
        if name not in omit:
            lines += ["", f"[{name}]", *body]
    return "\n".join(lines) + "\n"


def _refused(text: str) -> str:
    with pytest.raises(MappingError) as err:
        parse_mapping(text, NAMES, WHERE)
    return str(err.value)


# -- accepted mappings ------------------------------------------------------------------------

def test_a_complete_mapping_is_read_field_by_field():
    """Every table of the complete mapping as its text says: the coordinates, rates and torques
    in the thesis's order (the text lists theta last), theta's scale the degree written
    (thesis rad = DEG * FMU deg, docs/engines.md's example), every other scale the default 1;
    Baumgarte's two parameter names; each term's names row by row with 1-based indices (M 8x8,
    F 8 rows of one, S 8x3, D 5x8, dDdq 5 of one); the residual in the documented order rD_z ...
    vD_y though the text lists it reversed; the parameters with their scales (an integer scale
    2 read as 2.0). Fails when a dict value loses its name or scale (or gets another default),
    when the residual or parameters table is dropped, read under another key or replaced, or
    when the residual follows the text's order."""
    got = parse_mapping(_text(), NAMES, WHERE)
    assert isinstance(got, FmuMapping) and got.contact == "thesis"
    assert got.coordinates == tuple(Ref("theta_deg", DEG) if c == "theta" else Ref(c, 1.0)
                                    for c in COORDS)
    assert got.rates == tuple(Ref(f"d_{c}", 1.0) for c in COORDS)
    assert got.torques == (Ref("Mdir", 1.0), Ref("Mped", 1.0), Ref("Mvue", 1.0))
    assert got.baumgarte == ("a1", "a2")
    assert set(got.terms) == {"M", "F", "S", "Qgrav", "D", "dDdq"}
    assert got.terms["M"][2][6] == "term.M[3,7]" and len(got.terms["M"]) == 8
    assert got.terms["S"] == tuple(tuple(f"term.S[{i},{j}]" for j in (1, 2, 3)) for i in range(1, 9))
    assert got.terms["D"] == tuple(tuple(f"term.D[{i},{j}]" for j in range(1, 9)) for i in range(1, 6))
    assert got.terms["F"] == tuple((f"term.F[{i}]",) for i in range(1, 9))
    assert got.terms["dDdq"] == tuple((f"term.dDdq[{i}]",) for i in range(1, 6))
    assert got.residual == ("C.rD_z", "C.vC_x", "C.vC_y", "C.vD_x", "C.vD_y")
    assert got.parameters == {"R_rear": Ref("R_rear", 1.0), "m3": Ref("m3", 2.0)}
    assert type(got.parameters["m3"].scale) is float


def test_a_dict_value_without_a_scale_has_scale_one():
    """``{name = "..."}`` alone: the scale is 1 (Ref's documented default; docs/engines.md: the
    scale maps FMU value to SI, so an unscaled FMU variable is already SI). Fails when the
    default is another number or missing (float(None))."""
    got = parse_mapping(_text(torques=['Mdir = {name = "Mdir"}', 'Mped = "Mped"', 'Mvue = "Mvue"']),
                        NAMES, WHERE)
    assert got.torques[0] == Ref("Mdir", 1.0)


def test_the_optional_tables_may_all_be_left_out():
    """docs/engines.md marks [baumgarte], [terms], [residual] and [parameters] optional (the
    mapping of someone else's FMU: states and torques only): the mapping then has no Baumgarte
    parameters (None, which the engine tests to run at its own constraint handling), no terms,
    no residual (None) and no parameters. Fails when an optional table is required, or when
    a missing one reads as something other than None (e.g. an empty string)."""
    got = parse_mapping(_text(omit=("baumgarte", "terms", "residual", "parameters")), NAMES, WHERE)
    assert got.baumgarte is None and got.terms == {} and got.residual is None
    assert got.parameters == {}


def test_a_mapping_without_contact_is_read_as_the_templates_disc_contact():
    """The template for someone else's FMU (``export --format fmu-mapping`` without a model,
    reference_model/exports/fmu.py's mapping_text(None)) writes ``contact = "disc"``; a mapping
    that leaves the key out reads the same. Fails when the default is missing (None is
    refused as a contact) or another word."""
    from reference_model.exports.fmu import mapping_text
    template = tomllib.loads(mapping_text(None))["contact"]
    assert parse_mapping(_text(omit=("",)), NAMES, WHERE).contact == template == "disc"


# -- refusals: the whole line -----------------------------------------------------------------

def test_a_file_that_is_not_toml_says_so_with_tomllibs_reason():
    """A hand-written file with a syntax error: the line names where, tomllib's own reason (got
    here from tomllib itself) and the docs section to read. Fails when the message is lost."""
    text = 'contact = "thesis\n[coordinates]\n'
    with pytest.raises(tomllib.TOMLDecodeError) as exc:
        tomllib.loads(text)
    assert _refused(text) == (f'{WHERE}: not TOML ({exc.value}); fix: see docs/engines.md, '
                              '"The fmu engine"')


def test_an_unknown_contact_is_refused_with_the_two_contacts():
    """docs/engines.md: contact is "thesis" or "disc". Fails when the message or its fix is lost."""
    assert _refused(_text(**{"": ['contact = "tyre"']})) == (
        f"{WHERE}: contact = 'tyre'; fix: thesis or disc (the front contact the FMU models)")


@pytest.mark.parametrize("table", ["coordinates", "rates", "torques"])
def test_a_missing_required_table_is_named_with_the_template_command(table):
    """Each of the three required tables left out: the line names it and the command that
    writes the template (docs/engines.md). Fails when a required table is treated as optional
    (then a TypeError, not this line) or the line loses where or its fix."""
    assert _refused(_text(omit=(table,))) == (
        f"{WHERE}: no [{table}] table; fix: add it (bicycle-xval export --format fmu-mapping "
        "writes the template)")


@pytest.mark.parametrize("table", ["coordinates", "rates", "torques", "baumgarte", "terms",
                                   "residual", "parameters"])
def test_a_key_that_should_be_a_table_is_refused(table):
    """``rates = 3`` at the top level instead of a [rates] table, for each table: the line
    names the value and how a TOML table is written. Fails when the line loses where (for any
    one table) or is lost."""
    assert _refused(_text(omit=(table,), top=[f"{table} = 3"])) == (
        f"{WHERE}: {table} must be a table; got 3; fix: write [{table}] on a line of its own, "
        "its keys on the lines below")


def test_a_required_table_lacking_keys_names_them_and_the_full_list():
    """[torques] with Mdir only: the two missing (in the documented order, comma-separated) and
    the three it needs. Fails when the check is dropped (then a KeyError) or the line changes."""
    assert _refused(_text(torques=['Mdir = "Mdir"'])) == (
        f"{WHERE}: [torques] lacks Mped, Mvue; fix: map each of Mdir, Mped, Mvue to an FMU variable")


def test_unknown_keys_in_a_required_table_are_named_sorted():
    """[torques] with two keys that are no torque (written unsorted): both named, sorted, and
    the three allowed. Fails when extra keys pass silently (a typo'd torque is then unmapped)
    or the line changes."""
    body = ['Mrear = "Mdir"', *_sections()["torques"], 'Mfoo = "Mdir"']
    assert _refused(_text(torques=body)) == (
        f"{WHERE}: [torques] has unknown keys Mfoo, Mrear; fix: use Mdir, Mped, Mvue")


@pytest.mark.parametrize("table, key, good", [
    ("coordinates", "theta", '{name = "theta_deg", scale = 1.0}'),
    ("rates", "gamma", '"d_gamma"'),
    ("torques", "Mped", '"Mped"'),
])
def test_a_required_tables_variable_the_fmu_lacks_is_named(table, key, good):
    """One value of each required table naming a variable the FMU does not have: the line
    names where, the field, the name and the fix. Fails when the name check is dropped or the
    line loses where, its field or its fix (checked for each table: each passes where on)."""
    body = [line for line in _sections()[table] if not line.startswith(f"{key} =")]
    assert _refused(_text(**{table: body + [f'{key} = "nope"']})) == (
        f"{WHERE}: {table}.{key} names 'nope', which the FMU does not have; {UNKNOWN_FIX}")
    assert parse_mapping(_text(**{table: body + [f"{key} = {good}"]}), NAMES, WHERE)


@pytest.mark.parametrize("value, shown", [
    ("3", "3"),
    ('["theta"]', "['theta']"),
    ('{name = 3}', "{'name': 3}"),
    ('{scale = 2.0}', "{'scale': 2.0}"),
    ('{name = "theta", scale = true}', "{'name': 'theta', 'scale': True}"),
    ('{name = "theta", scale = "deg"}', "{'name': 'theta', 'scale': 'deg'}"),
])
def test_a_value_that_is_neither_a_name_nor_name_and_scale_is_refused(value, shown):
    """docs/engines.md: a value is an FMU variable name or {name = "...", scale = s}; a number,
    a list, a dict whose name is no text or is missing, a boolean or text scale are each one
    line quoting the value. Fails when the check's and/or are swapped or its bool exclusion
    inverted (then a boolean scale passes as 1, a text scale reaches float() and raises a
    ValueError, a number reaches .get and raises an AttributeError, a numeric name is reported
    as a missing variable) or the line is lost."""
    body = [line for line in _sections()["coordinates"] if not line.startswith("theta =")]
    assert _refused(_text(coordinates=body + [f"theta = {value}"])) == (
        f'{WHERE}: coordinates.theta must be an FMU variable name or {{name = "...", scale = s}}; '
        f"got {shown}")


def test_baumgarte_needs_exactly_a1_and_a2():
    """[baumgarte] with a1 only, and with a third key: the lines name what is missing or extra
    and the two keys it takes, as the required tables' do. Fails when the check or its message
    is lost."""
    assert _refused(_text(baumgarte=['a1 = "a1"'])) == (
        f"{WHERE}: [baumgarte] lacks a2; fix: map each of a1, a2 to an FMU variable")
    assert _refused(_text(baumgarte=['a1 = "a1"', 'a2 = "a2"', 'a3 = "a1"'])) == (
        f"{WHERE}: [baumgarte] has unknown keys a3; fix: use a1, a2")


def test_a_baumgarte_value_must_be_a_name_the_fmu_has():
    """a1 as a number (the Baumgarte constant itself, not the parameter's name: a likely slip)
    and a2 naming a missing parameter: each line names where, the field and the value. Fails
    when either refusal is lost or loses where or its field."""
    assert _refused(_text(baumgarte=["a1 = 10", 'a2 = "a2"'])) == (
        f"{WHERE}: baumgarte.a1 must be an FMU variable name (text); got 10")
    assert _refused(_text(baumgarte=['a1 = "a1"', 'a2 = "alpha2"'])) == (
        f"{WHERE}: baumgarte.a2 names 'alpha2', which the FMU does not have; {UNKNOWN_FIX}")


def test_an_unknown_term_is_refused_with_the_six_terms():
    """[terms] with K (no thesis term): the six terms of docs/engines.md's table, in its order.
    Fails when the check or its message is lost."""
    assert _refused(_text(terms=['K = "term.M[{i},{j}]"'])) == (
        f"{WHERE}: terms.K is not a term; fix: use M, F, S, Qgrav, D, dDdq")


def test_a_term_pattern_must_be_text():
    """A number where a pattern goes: the line gives an example of the term's own shape (a
    matrix takes {i} and {j}, a vector {i}), in the template's names."""
    assert _refused(_text(terms=["M = 3"])) == (
        f'{WHERE}: terms.M must be a name pattern; got 3; fix: e.g. M = "term.M[{{i}},{{j}}]"')
    assert _refused(_text(terms=["F = true"])) == (
        f'{WHERE}: terms.F must be a name pattern; got True; fix: e.g. F = "term.F[{{i}}]"')


@pytest.mark.parametrize("pattern, error", [
    ("term.M[{i},{k}]", "KeyError: 'k'"),
    ("term.M[{0}]", "IndexError: Replacement index 0 out of range for positional args tuple"),
    ("term.M[{i", "ValueError: expected '}' before end of string"),
])
def test_a_pattern_with_a_bad_placeholder_is_one_line_not_a_traceback(pattern, error):
    """A typo in a hand-written pattern ({k} for {j}, a positional {0}, an unclosed brace):
    str.format's own error (its words, from Python) is wrapped in the one-line refusal with
    the fix. Before, the KeyError, IndexError or ValueError reached the user as a traceback:
    the engine turns MappingError alone into its one-line error."""
    assert _refused(_text(terms=[f'M = "{pattern}"'])) == (
        f"{WHERE}: terms.M = {pattern!r} is not a name pattern ({error}); fix: use only {{i}} "
        "(the row) and {j} (the column), 1-based, and {{ }} for a literal brace, "
        'e.g. M = "term.M[{i},{j}]"')


def test_a_transposed_term_pattern_names_the_first_output_the_fmu_lacks():
    """D (5x8) written with {j} and {i} swapped: row 1 asks for D[1,1] ... D[8,1], and the FMU has
    D's rows 1 to 5 only, so the line names 'term.D[6,1]' (the first missing, computed by hand)
    under terms.D. Fails when the line loses where or its field."""
    assert _refused(_text(terms=['D = "term.D[{j},{i}]"'])) == (
        f"{WHERE}: terms.D names 'term.D[6,1]', which the FMU does not have; {UNKNOWN_FIX}")


def test_a_residual_lacking_a_constraint_or_naming_a_missing_output_is_refused():
    """[residual] without vD_y, with a key that is no constraint, and with rD_z misspelt: the
    first two as the required tables' lines (what is missing or extra, the five keys), the
    third naming where and the field residual.<constraint>. Fails when a residual field loses
    where or its name, or a check is dropped."""
    keys = "rD_z, vC_x, vC_y, vD_x, vD_y"      # docs/engines.md's [residual] row, in order
    body = [line for line in _sections()["residual"] if not line.startswith("vD_y")]
    assert _refused(_text(residual=body)) == (
        f"{WHERE}: [residual] lacks vD_y; fix: map each of {keys} to an FMU variable")
    assert _refused(_text(residual=_sections()["residual"] + ['vA_x = "C.rD_z"'])) == (
        f"{WHERE}: [residual] has unknown keys vA_x; fix: use {keys}")
    body = [line for line in _sections()["residual"] if not line.startswith("rD_z")]
    assert _refused(_text(residual=body + ['rD_z = "C.rd_z"'])) == (
        f"{WHERE}: residual.rD_z names 'C.rd_z', which the FMU does not have; {UNKNOWN_FIX}")


def test_a_parameter_that_is_no_thesis_parameter_is_refused():
    """docs/engines.md: [parameters] keys are thesis parameter names (docs/model.md). Fails
    when the check or its message is lost."""
    assert _refused(_text(parameters=['mass = "m3"'])) == (
        f"{WHERE}: parameters.mass is not a thesis parameter; fix: use the names of "
        "docs/model.md (R_rear, m3, I3xz, ...)")


def test_a_parameters_fmu_variable_is_checked_like_any_value():
    """m3 mapped to a missing FMU parameter, and to a boolean scale: the lines name where and
    parameters.m3. Fails when either loses where or its field."""
    assert _refused(_text(parameters=['m3 = "mass3"'])) == (
        f"{WHERE}: parameters.m3 names 'mass3', which the FMU does not have; {UNKNOWN_FIX}")
    assert _refused(_text(parameters=['m3 = {name = "m3", scale = true}'])) == (
        f'{WHERE}: parameters.m3 must be an FMU variable name or {{name = "...", scale = s}}; '
        "got {'name': 'm3', 'scale': True}")
