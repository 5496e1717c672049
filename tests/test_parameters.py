"""Tests of reference_model.params: the thesis parameter file and the validation messages."""

from __future__ import annotations

import dataclasses
import math
import pickle
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from thesis_params import THESIS_PARAMS

from reference_model.params import (
    CONTACT_MODELS,
    NAMED_MODELS,
    PARAMETER_GROUPS,
    PARAMETER_NAMES,
    PARAMETER_UNITS,
    THESIS_FILE,
    ParameterError,
    Parameters,
    load_parameters,
    parameters_from_mapping,
    resolve_model,
)

# The thesis numbers (din_Bicicleta), written independently of thesis.toml.
THESIS_VALUES: dict[str, float] = THESIS_PARAMS  # typed in by hand from the listing

THESIS_TEXT = THESIS_FILE.read_text(encoding="utf-8")


# ---------------------------------------------------------------------------- helpers


def set_entry(text: str, key: str, rhs: str) -> str:
    """Replace the right-hand side of the line ``key = ...`` (comment dropped)."""
    pattern = re.compile(rf"^{re.escape(key)}\s*=.*$", re.MULTILINE)
    assert len(pattern.findall(text)) == 1, key
    return pattern.sub(lambda _: f"{key} = {rhs}", text)


def rename_key(text: str, key: str, new: str) -> str:
    pattern = re.compile(rf"^{re.escape(key)}(\s*=)", re.MULTILINE)
    assert len(pattern.findall(text)) == 1, key
    return pattern.sub(lambda m: new + m.group(1), text)


def drop_key(text: str, key: str) -> str:
    pattern = re.compile(rf"^{re.escape(key)}\s*=.*\n", re.MULTILINE)
    assert len(pattern.findall(text)) == 1, key
    return pattern.sub("", text)


def write(tmp_path: Path, text: str, name: str = "bad.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def thesis_dict() -> dict[str, float]:
    return dict(THESIS_VALUES)


# ---------------------------------------------------------------------------- the thesis file


def test_thesis_file_values_match_the_thesis() -> None:
    p = load_parameters(THESIS_FILE)
    for name, expected in THESIS_VALUES.items():
        assert getattr(p, name) == pytest.approx(expected, rel=0, abs=1e-12), name
    assert p.name == "thesis"
    assert p.contact == "thesis"
    assert p.source == str(THESIS_FILE)


def test_thesis_file_has_exactly_the_parameter_names_in_their_tables() -> None:
    data = tomllib.loads(THESIS_TEXT)
    assert set(data) == {"model", "geometry", "mass", "inertia", "environment"}
    found = {key: table for table in data if table != "model" for key in data[table]}
    assert set(found) == set(PARAMETER_NAMES)
    assert found == PARAMETER_GROUPS
    # written in the contract order, with the canonical unit
    order = [key for table in data if table != "model" for key in data[table]]
    assert order == list(PARAMETER_NAMES)
    for name, table in PARAMETER_GROUPS.items():
        assert data[table][name]["unit"] == PARAMETER_UNITS[name]


def test_thesis_model_table() -> None:
    model = tomllib.loads(THESIS_TEXT)["model"]
    assert model["name"] == "thesis"
    assert model["contact"] == "thesis"
    assert "mínimo número de coordenadas" in model["source"]


def test_parameter_names_contract() -> None:
    assert len(PARAMETER_NAMES) == 30 == len(set(PARAMETER_NAMES))
    assert PARAMETER_NAMES[:2] == ("R_rear", "R_front")
    assert PARAMETER_NAMES[-2:] == ("g", "cv")
    fields = [f.name for f in dataclasses.fields(Parameters)]
    assert fields == [*PARAMETER_NAMES, "name", "contact", "source", "triangle", "benchmark",
                      "warnings"]
    assert list(PARAMETER_UNITS) == list(PARAMETER_NAMES)
    assert list(PARAMETER_GROUPS) == list(PARAMETER_NAMES)
    assert CONTACT_MODELS == ("thesis", "disc")


def test_vector_order_and_dtype() -> None:
    p = load_parameters(THESIS_FILE)
    v = p.vector()
    assert v.dtype == np.float64 and v.shape == (30,)
    for i, name in enumerate(PARAMETER_NAMES):
        assert v[i] == getattr(p, name)
    assert Parameters.from_vector(v, name=p.name, source=p.source) == p


def test_inertia_tensors() -> None:
    p = load_parameters(THESIS_FILE)
    i3 = p.inertia(3)
    assert i3.shape == (3, 3)
    np.testing.assert_array_equal(i3, i3.T)
    assert i3[0, 2] == i3[2, 0] == pytest.approx(-1.820)
    assert np.diag(i3) == pytest.approx([20.213, 21.769, 3.205])
    assert p.inertia(4)[0, 2] == pytest.approx(0.018)
    np.testing.assert_array_equal(p.inertia(2), np.diag([0.108, 0.216, 0.108]))
    np.testing.assert_array_equal(p.inertia(5), p.inertia(2))
    for body in (2, 3, 4, 5):
        assert np.all(np.linalg.eigvalsh(p.inertia(body)) > 0)
    for bad in (1, 6, True):
        with pytest.raises(ValueError, match="body"):
            p.inertia(bad)


def test_as_dict_round_trip_and_immutability() -> None:
    p = load_parameters(THESIS_FILE)
    d = p.as_dict()
    assert list(d)[:30] == list(PARAMETER_NAMES)
    assert Parameters(**d) == p
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.m2 = 3.0  # type: ignore[misc]


def test_named_models() -> None:
    assert set(NAMED_MODELS) == {"thesis", "thesis-disc", "benchmark"}
    a = resolve_model("thesis")
    b = resolve_model("thesis-disc")
    assert (a.name, a.contact) == ("thesis", "thesis")
    assert (b.name, b.contact) == ("thesis-disc", "disc")
    np.testing.assert_array_equal(a.vector(), b.vector())
    assert resolve_model(str(THESIS_FILE)) == a
    assert resolve_model(THESIS_FILE) == a
    assert resolve_model(a) is a


def test_contact_and_name_overrides() -> None:
    p = load_parameters(THESIS_FILE, contact="disc", name="x")
    assert (p.contact, p.name) == ("disc", "x")
    assert p.with_contact("thesis").contact == "thesis"


def test_model_table_is_optional(tmp_path: Path) -> None:
    text = THESIS_TEXT.split("[geometry]", 1)[1]
    p = load_parameters(write(tmp_path, "[geometry]" + text, "mybike.toml"))
    assert (p.name, p.contact) == ("mybike", "thesis")


def test_plain_numbers_mean_canonical_units(tmp_path: Path) -> None:
    text = set_entry(THESIS_TEXT, "m2", "2.612")
    text = set_entry(text, "x3", "0.26047")
    text = set_entry(text, "dx4", "0")  # an integer is a number too
    p = load_parameters(write(tmp_path, text))
    ref = load_parameters(THESIS_FILE)
    assert p.vector() == pytest.approx(ref.vector(), rel=1e-15, abs=0)


def test_unit_conversions(tmp_path: Path) -> None:
    text = set_entry(THESIS_TEXT, "x3", '{ value = 26.047, unit = "cm" }')
    text = set_entry(text, "z3", '{ value = 946.87, unit = "mm" }')
    text = set_entry(text, "m2", '{ value = 2612, unit = "g" }')
    text = set_entry(text, "I3xx", '{ value = 20.213, unit = "kg m^2" }')
    text = set_entry(text, "I3yy", '{ value = 21.769, unit = "kg·m²" }')
    text = set_entry(text, "I2yy", '{ value = 2160000, unit = "g*cm^2" }')
    p = load_parameters(write(tmp_path, text))
    ref = load_parameters(THESIS_FILE)
    assert p.vector() == pytest.approx(ref.vector(), rel=1e-12, abs=0)


def test_replace_validates_and_copies() -> None:
    p = resolve_model("thesis")
    q = p.replace(m3=80.0, cv=0.0)
    assert (q.m3, q.cv, p.m3) == (80.0, 0.0, 77.391)
    with pytest.raises(ParameterError, match=r"mass\.m3.*> 0"):
        p.replace(m3=-1.0)
    with pytest.raises(ParameterError, match=r"'m33'.*'m3'"):
        p.replace(m33=1.0)
    with pytest.raises(ParameterError, match=r"model\.contact.*'sphere'"):
        p.with_contact("sphere")


def test_parameters_built_in_code_are_validated() -> None:
    values = thesis_dict()
    assert Parameters(**values).source == "<memory>"
    values["I4xz"] = float("nan")
    with pytest.raises(ParameterError, match=r"<memory>: inertia\.I4xz: .*finite"):
        Parameters(**values)


def test_parameters_from_mapping() -> None:
    data = {table: {} for table in ("geometry", "mass", "inertia", "environment")}
    for name, value in THESIS_VALUES.items():
        data[PARAMETER_GROUPS[name]][name] = value
    p = parameters_from_mapping(data)
    assert p.vector() == pytest.approx(resolve_model("thesis").vector(), abs=1e-12)


def test_parameter_error_is_picklable_value_error() -> None:
    err = ParameterError("f.toml", "mass.m2", "bad", "fix it")
    assert isinstance(err, ValueError)
    back = pickle.loads(pickle.dumps(err))
    assert str(back) == str(err) == "f.toml: mass.m2: bad; fix: fix it"
    assert (back.file, back.key, back.problem, back.fix) == ("f.toml", "mass.m2", "bad", "fix it")


def test_missing_file() -> None:
    with pytest.raises(ParameterError, match=r"nope\.toml: \(file\): no such file"):
        load_parameters("nope.toml")
    with pytest.raises(ParameterError, match="no such file"):
        resolve_model("nope.toml")


# ---------------------------------------------------------------------------- bad inputs


def _unknown_key(t: str) -> str:
    return rename_key(t, "R_rear", "R_reer")


def _misplaced_key(t: str) -> str:
    return drop_key(t, "m2").replace("[geometry]\n", "[geometry]\nm2 = 2.612\n")


def _unknown_table(t: str) -> str:
    return t.replace("[environment]", "[enviroment]")


def _triangle(t: str) -> str:
    t = set_entry(t, "I2xx", '{ value = 1.0, unit = "kg*m^2" }')
    t = set_entry(t, "I2yy", '{ value = 1.0, unit = "kg*m^2" }')
    return set_entry(t, "I2zz", '{ value = 3.0, unit = "kg*m^2" }')


def _triangle_with_product(t: str) -> str:
    # principal moments of the x-z block: 20.213 + 3.205 +- ..., yy far too large
    return set_entry(t, "I3yy", '{ value = 30.0, unit = "kg*m^2" }')


BAD_CASES = [
    pytest.param(_unknown_key, ["geometry.R_reer", "unknown key", "'R_rear'"], id="unknown-key"),
    pytest.param(_misplaced_key, ["geometry.m2", "belongs in [mass]"], id="misplaced-key"),
    pytest.param(_unknown_table, ["enviroment", "unknown table", "[environment]"], id="unknown-table"),
    pytest.param(
        lambda t: drop_key(t, "cv"), ["environment.cv", "missing", 'unit = "kg/m"'], id="missing-key"
    ),
    pytest.param(
        lambda t: set_entry(t, "x3", '{ value = nan, unit = "m" }'),
        ["geometry.x3", "nan", "not a finite real number"],
        id="nan",
    ),
    pytest.param(
        lambda t: set_entry(t, "g", '{ value = inf, unit = "m/s^2" }'),
        ["environment.g", "inf", "not a finite real number"],
        id="inf",
    ),
    pytest.param(
        lambda t: set_entry(t, "z5", "-inf"),
        ["geometry.z5", "-inf", "not a finite real number"],
        id="plain-minus-inf",
    ),
    pytest.param(
        lambda t: set_entry(t, "m3", '{ value = "77.391", unit = "kg" }'),
        ["mass.m3", "string, not a number", "remove the quotes"],
        id="string",
    ),
    pytest.param(
        lambda t: set_entry(t, "za", '{ value = true, unit = "m" }'),
        ["geometry.za", "boolean, not a number"],
        id="bool",
    ),
    pytest.param(
        lambda t: set_entry(t, "m4", '{ value = -1.725, unit = "kg" }'),
        ["mass.m4", "-1.725", "must be > 0"],
        id="negative-mass",
    ),
    pytest.param(
        lambda t: set_entry(t, "R_front", '{ value = 0.0, unit = "m" }'),
        ["geometry.R_front", "must be > 0"],
        id="zero-radius",
    ),
    pytest.param(
        lambda t: set_entry(t, "cv", '{ value = -0.1, unit = "kg/m" }'),
        ["environment.cv", "must be >= 0"],
        id="negative-drag",
    ),
    pytest.param(
        lambda t: set_entry(t, "x5", '{ value = 0.06891, unit = "in" }'),
        ["geometry.x5", "unit 'in'", "length", "'m'", "'cm'", "'mm'"],
        id="wrong-unit",
    ),
    pytest.param(
        lambda t: set_entry(t, "m2", '{ value = 2.612, unit = "m" }'),
        ["mass.m2", "unit 'm'", "mass unit", "'kg'", "'g'"],
        id="unit-of-other-dimension",
    ),
    pytest.param(
        lambda t: set_entry(t, "x5", "{ value = 0.06891 }"),
        ["geometry.x5", "unit missing", 'unit = "m"'],
        id="missing-unit",
    ),
    pytest.param(
        lambda t: set_entry(t, "x5", '{ valeu = 0.06891, unit = "m" }'),
        ["geometry.x5", "unknown field 'valeu'", "'value'"],
        id="misspelt-value",
    ),
    pytest.param(
        lambda t: set_entry(t, "I3xz", '{ value = -9.0, unit = "kg*m^2" }'),
        ["inertia of body 3 (frame+rider)", "not positive definite", "inertia.I3xz"],
        id="non-pd-product",
    ),
    pytest.param(
        lambda t: set_entry(t, "I4yy", '{ value = -0.103, unit = "kg*m^2" }'),
        ["inertia of body 4 (fork/handlebar)", "not positive definite", "inertia.I4yy"],
        id="non-pd-diagonal",
    ),
    pytest.param(
        _triangle,
        ["inertia of body 2 (rear wheel)", "triangle inequality", "inertia.I2zz"],
        id="triangle",
    ),
    pytest.param(
        _triangle_with_product,
        ["inertia of body 3 (frame+rider)", "triangle inequality", "inertia.I3yy"],
        id="triangle-with-product",
    ),
    pytest.param(
        lambda t: set_entry(t, "contact", '"sphere"'),
        ["model.contact", "'sphere'", "'thesis'", "'disc'"],
        id="unknown-contact",
    ),
    pytest.param(
        lambda t: set_entry(t, "description", "42"),
        ["model.description", "not a string"],
        id="non-string-description",
    ),
    pytest.param(
        lambda t: set_entry(t, "x3", '{ value = 0.26047, unit = "m" '),
        ["line ", "invalid TOML", "Unclosed inline table", "x3 = "],
        id="toml-syntax",
    ),
]


@pytest.mark.parametrize(("mutate", "expected"), BAD_CASES)
def test_bad_file_gives_one_clear_error(tmp_path: Path, mutate, expected: list[str]) -> None:
    path = write(tmp_path, mutate(THESIS_TEXT))
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ")
    assert "\n" not in message
    assert "; fix: " in message
    for part in expected:
        assert part in message, (part, message)


def test_toml_syntax_line_number_is_right(tmp_path: Path) -> None:
    lineno = THESIS_TEXT.splitlines().index(
        next(line for line in THESIS_TEXT.splitlines() if line.startswith("x3 ="))
    ) + 1
    text = set_entry(THESIS_TEXT, "x3", '{ value = 0.26047, unit = "m" ')
    with pytest.raises(ParameterError, match=rf": line {lineno}: invalid TOML"):
        load_parameters(write(tmp_path, text))


def test_unknown_contact_argument() -> None:
    with pytest.raises(ParameterError, match=r"model\.contact.*'wheel'"):
        load_parameters(THESIS_FILE, contact="wheel")


def test_unknown_named_model() -> None:
    with pytest.raises(ParameterError) as info:
        resolve_model("thesis-dsc")
    message = str(info.value)
    for part in ("thesis-dsc", "unknown model", "'thesis-disc'", "thesis, thesis-disc", ".toml"):
        assert part in message, (part, message)


# ---------------------------------------------------------------------------- properties

moment = st.floats(min_value=1e-3, max_value=1e3, allow_nan=False, allow_infinity=False)


@pytest.mark.filterwarnings("ignore::reference_model.params.ParameterWarning")  # unusual on purpose
@given(a=moment, b=moment, c=moment)
def test_wheel_inertia_valid_iff_triangle_holds(a: float, b: float, c: float) -> None:
    values = thesis_dict() | {"I5xx": a, "I5yy": b, "I5zz": c}
    top = max(a, b, c)
    if (a + b + c) - top >= top * (1 - 1e-9):
        Parameters(**values)
    elif (a + b + c) - top < top * (1 - 1e-11):
        with pytest.raises(ParameterError, match=r"body 5 \(front wheel\).*triangle"):
            Parameters(**values)


@pytest.mark.filterwarnings("ignore::reference_model.params.ParameterWarning")  # unusual on purpose
@given(
    xx=moment,
    zz=moment,
    angle=st.floats(min_value=-math.pi, max_value=math.pi),
    yy_scale=st.floats(min_value=0.01, max_value=3.0),
)
def test_frame_inertia_agrees_with_eigenvalues(xx: float, zz: float, angle: float, yy_scale: float) -> None:
    # a physically meaningful x-z block rotated about y, and a yy that may or may not fit
    c, s = math.cos(angle), math.sin(angle)
    block = np.array([[c, -s], [s, c]]) @ np.diag([xx, zz]) @ np.array([[c, s], [-s, c]])
    yy = yy_scale * (xx + zz)
    values = thesis_dict() | {"I3xx": block[0, 0], "I3zz": block[1, 1], "I3xz": block[0, 1], "I3yy": yy}
    principal = sorted([xx, zz, yy])
    margin = principal[0] + principal[1] - principal[2]
    if margin > 1e-9 * principal[2]:
        p = Parameters(**values)
        assert np.linalg.eigvalsh(p.inertia(3)) == pytest.approx(principal, rel=1e-9)
    elif margin < -1e-9 * principal[2]:
        with pytest.raises(ParameterError, match=r"body 3 \(frame\+rider\).*triangle"):
            Parameters(**values)


# ---------------------------------------------------------------------------- issue 24: gaps
# Each test below was written against a mutant that survived the suite (mutmut, issue 24):
# its expected values are the documented contract (docstrings) or a hand-made input.


def test_from_vector_keeps_every_keyword_and_defaults_to_custom() -> None:
    thesis = Parameters(**thesis_dict())
    p = Parameters.from_vector(thesis.vector(), name="v", contact="disc", source="here.toml",
                               triangle="warn")
    assert (p.name, p.contact, p.source, p.triangle) == ("v", "disc", "here.toml", "warn")
    assert p.vector().tolist() == thesis.vector().tolist()
    plain = Parameters.from_vector(thesis.vector())
    # the dataclass's own defaults, as Parameters(**values) has them
    assert (plain.name, plain.contact, plain.triangle) == ("custom", "thesis", "strict")


def test_from_vector_of_the_wrong_length_names_the_source_and_both_lengths() -> None:
    with pytest.raises(ParameterError) as info:
        Parameters.from_vector([1.0] * 29, source="vec.txt")
    err = info.value
    assert (err.file, err.key) == ("vec.txt", "(vector)")
    assert err.problem == "parameter vector has 29 entries, expected 30"
    assert err.fix == "pass one value per name in PARAMETER_NAMES, in that order"


def test_as_dict_carries_contact_triangle_and_the_benchmark() -> None:
    from reference_model.parameters.benchmark import TABLE1
    p = Parameters.from_benchmark(TABLE1.as_dict(), allow_triangle_violation=True)
    d = p.as_dict()
    assert list(d)[:30] == list(PARAMETER_NAMES)
    assert list(d)[30:] == ["name", "contact", "source", "triangle", "benchmark"]
    assert (d["contact"], d["triangle"]) == ("disc", "warn")
    assert d["benchmark"] is p.benchmark == TABLE1     # benchmark is not compared by ==: say it


def test_reference_parameters_are_the_benchmark_with_disc_contact_and_provenance() -> None:
    from reference_model.parameters.benchmark import TABLE1, reference_parameters
    kwargs = reference_parameters()
    assert set(kwargs) == set(PARAMETER_NAMES) | {"contact", "benchmark"}
    p = Parameters(**kwargs)
    assert p.contact == "disc" and p.benchmark is TABLE1


def test_closest_is_none_without_a_near_name() -> None:
    from reference_model.parameters.schema import closest
    assert closest("zzzzzz", PARAMETER_NAMES) is None
    assert closest("m_3", PARAMETER_NAMES) == "m3"


def test_a_quoted_word_is_not_told_to_drop_its_quotes(tmp_path: Path) -> None:
    # only a quoted number has the fix "remove the quotes"; a quoted word needs a number
    path = write(tmp_path, set_entry(THESIS_TEXT, "m3", '{ value = "heavy", unit = "kg" }'))
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    assert info.value.fix == "write a finite real number, e.g. value = 1.0"


def test_toml_syntax_error_at_end_of_file(tmp_path: Path) -> None:
    # tomllib says "(at end of document)", no line and column: the key is the end of the file
    path = write(tmp_path, THESIS_TEXT + "\nextra = ")
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    err = info.value
    assert (err.file, err.key) == (str(path), "(end of file)")
    assert err.problem == "invalid TOML: Invalid value (at end of document)"
    assert err.fix == "correct the TOML syntax"


@pytest.mark.parametrize("where", ["first", "middle", "last"])
def test_toml_syntax_error_quotes_its_own_line(tmp_path: Path, where: str) -> None:
    lines = THESIS_TEXT.rstrip("\n").splitlines()
    bad = "x3 = 0.26047 m"      # a statement with something after it: tomllib gives its line
    if where == "first":
        lines.insert(0, bad)
    elif where == "last":
        lines.append(bad)
    else:
        lines = [bad if line.startswith("x3 =") else line for line in lines]
    lineno = lines.index(bad) + 1          # counted by hand: 1-based
    path = write(tmp_path, "\n".join(lines))
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    err = info.value
    assert err.key == f"line {lineno}"
    assert err.problem.endswith(f": {bad.strip()!r}")
    assert err.fix == 'correct the TOML syntax on that line, e.g. x3 = { value = 0.26047, unit = "m" }'


def test_unknown_key_of_another_table_is_sent_there(tmp_path: Path) -> None:
    # I3yyy (a typo of I3yy) in [geometry]: like no geometry key, like inertia.I3yy
    path = write(tmp_path, THESIS_TEXT.replace("[geometry]\n", "[geometry]\nI3yyy = 1.0\n"))
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    assert info.value.fix == "did you mean 'inertia.I3yy'? rename it and put it in [inertia]"


def test_unknown_key_like_nothing_lists_the_tables_keys(tmp_path: Path) -> None:
    path = write(tmp_path, THESIS_TEXT.replace("[mass]\n", "[mass]\nwheelbase = 1.0\n"))
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    assert info.value.key == "mass.wheelbase"
    assert info.value.fix == "remove it; valid keys in [mass] are m2, m3, m4, m5"


def test_inertia_of_no_body_lists_the_bodies() -> None:
    p = Parameters(**thesis_dict())
    for bad in (1, 6, True):
        with pytest.raises(ValueError) as info:
            p.inertia(bad)
        assert str(info.value) == ("body must be one of (2, 3, 4, 5) (2: rear wheel, 3: frame+rider, "
                                   f"4: fork/handlebar, 5: front wheel), got {bad!r}")


@pytest.mark.parametrize(("table", "key", "fix"), [
    # the symmetric entry of the one product the frame has
    ("inertia", "I3zx", "the tensor is symmetric: I3zx is the entry I3xz; rename it to inertia.I3xz"),
    ("inertia", "I2xz", "remove it: body 2 (rear wheel) is an axisymmetric wheel with no product of inertia"),
    # not a tensor entry at all: the nearest name, as for any other table
    ("inertia", "I3xxx", "did you mean 'I3xx'? rename it to inertia.I3xx"),
    # a tensor entry written in another table: sent to [inertia] (to the nearest name, I3xz
    # and I3zz tie), not told it is symmetric
    ("geometry", "I3zx", re.compile(r"did you mean 'inertia\.I3(xz|zz)'\? rename it and put it in \[inertia\]")),
])
def test_unknown_inertia_like_keys_get_their_own_fix(tmp_path: Path, table: str, key: str, fix: str) -> None:
    path = write(tmp_path, THESIS_TEXT.replace(f"[{table}]\n", f"[{table}]\n{key} = 1.0\n"))
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    assert info.value.key == f"{table}.{key}"
    if isinstance(fix, str):
        assert info.value.fix == fix
    else:
        assert fix.fullmatch(info.value.fix), info.value.fix


# ---------------------------------------------------------------------------- benchmark.toml's tool


def test_the_named_benchmark_file_is_what_its_generator_writes() -> None:
    from reference_model.parameters.loading import BENCHMARK_FILE, named_model_text
    assert named_model_text() == BENCHMARK_FILE.read_text(encoding="utf-8")


def test_check_passes_on_the_shipped_file(capsys) -> None:
    from reference_model.parameters.loading import BENCHMARK_FILE, main
    assert main(["--check"]) == 0
    out, err = capsys.readouterr()
    assert (out, err) == (f"{BENCHMARK_FILE}: matches the formulas\n", "")


def test_check_names_each_value_that_differs_and_write_repairs_it(tmp_path, monkeypatch, capsys) -> None:
    from reference_model.parameters import loading
    from reference_model.parameters.benchmark import TABLE1, model_values
    stale = tmp_path / "benchmark.toml"
    text = loading.BENCHMARK_FILE.read_text(encoding="utf-8")
    x3 = model_values(TABLE1)["x3"]
    changed = re.sub(r"^x3 = \{ value = [^,]+,", "x3 = { value = 0.5,", text, flags=re.M)
    changed = re.sub(r"^m3 = \{ value = [^,]+,", "m3 = { value = 80.0,", changed, flags=re.M)
    stale.write_text(changed, encoding="utf-8")
    monkeypatch.setattr(loading, "BENCHMARK_FILE", stale)
    assert loading.main(["--check"]) == 1
    out, err = capsys.readouterr()
    assert out == f"{stale}: 2 value(s) differ\n"
    assert err == f"x3: file 0.5, formula {x3!r}\nm3: file 80.0, formula 85.0\n"   # Table 1: mB = 85 kg
    assert loading.main(["--write"]) == 0
    assert capsys.readouterr().out == f"wrote {stale}\n"
    assert stale.read_text(encoding="utf-8") == text
    assert loading.main(["--check"]) == 0


def test_the_benchmark_tool_needs_one_of_write_or_check(capsys) -> None:
    from reference_model.parameters.loading import main
    for argv in ([], ["--write", "--check"]):
        with pytest.raises(SystemExit) as info:
            main(argv)
        assert info.value.code == 2
    assert "python -m reference_model.benchmark" in capsys.readouterr().err


# ---------------------------------------------------------------------------- issue 24: more gaps


def test_parameters_from_table1_are_custom_and_strict_by_default() -> None:
    from reference_model.parameters.benchmark import TABLE1
    from reference_model.parameters.values import parameters_from_benchmark
    from reference_model.params import TriangleInequalityError
    assert Parameters.from_benchmark(TABLE1.as_dict()).name == "custom"
    assert parameters_from_benchmark(TABLE1.as_dict()).name == "custom"
    # IByy far above IBxx + IBzz: not a real body
    broken = TABLE1.as_dict() | {"IByy": 30.0}
    with pytest.raises(TriangleInequalityError):
        parameters_from_benchmark(broken)
    assert parameters_from_benchmark(broken, allow_triangle_violation=True).warnings


def test_replace_with_an_unknown_field_names_it_and_the_source() -> None:
    p = Parameters(**thesis_dict(), source="bike.toml")
    with pytest.raises(ParameterError) as info:
        p.replace(zzzzzz=1.0)
    err = info.value
    assert (err.file, err.key, err.problem) == ("bike.toml", "zzzzzz", "'zzzzzz' is not a field of Parameters")
    assert err.fix == "use a name from PARAMETER_NAMES, or name/contact/source"
    with pytest.raises(ParameterError) as info:
        p.replace(contcat="disc")
    assert info.value.fix == "use 'contact'"


def test_replace_keeps_a_benchmark_given_with_the_change() -> None:
    from reference_model.parameters.benchmark import TABLE1
    p = Parameters.from_benchmark(TABLE1.as_dict())
    assert p.replace(g=p.g, benchmark=TABLE1).benchmark is TABLE1     # said explicitly: kept
    assert p.replace(g=p.g).benchmark is None                         # not said: dropped


def test_attach_benchmark_refusal_names_the_source_and_the_table() -> None:
    from reference_model.parameters.benchmark import TABLE1
    from reference_model.parameters.values import attach_benchmark
    p = Parameters.from_benchmark(TABLE1.as_dict(), source="bike.toml").replace(benchmark=None)
    moved = TABLE1.as_dict() | {"w": 1.1}
    with pytest.raises(ParameterError) as info:
        attach_benchmark(p, moved)
    assert info.value.file == "bike.toml"
    assert "does not follow from the [benchmark] table" in info.value.problem
    assert attach_benchmark(p, TABLE1.as_dict()).benchmark == TABLE1


def test_a_stray_top_level_g_in_a_model_file_is_the_model_files_error(tmp_path: Path) -> None:
    # g is both a Table 1 name and a parameter: beside the model's tables it is misplaced,
    # not a sign of a Table 1 file
    path = write(tmp_path, "g = 9.81\n" + THESIS_TEXT)
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    assert (info.value.key, info.value.problem) == ("g", "parameter 'g' is outside any table")


def test_resolve_model_of_a_path_is_strict_by_default(tmp_path: Path) -> None:
    from reference_model.params import TriangleInequalityError
    path = write(tmp_path, set_entry(THESIS_TEXT, "I3yy", '{ value = 30.0, unit = "kg*m^2" }'))
    with pytest.raises(TriangleInequalityError):
        resolve_model(path)
    assert resolve_model(path, allow_triangle_violation=True).warnings


def test_unknown_model_like_nothing_has_no_suggestion() -> None:
    with pytest.raises(ParameterError) as info:
        resolve_model("zzzz")
    err = info.value
    assert (err.file, err.key, err.problem) == ("zzzz", "model", "unknown model 'zzzz'")


def test_a_flat_file_of_unknown_names_is_read_as_table1_an_empty_one_as_a_model(tmp_path: Path) -> None:
    # flat key = number lines with no table and no model parameter: Table 1's layout, so its
    # error lists Table 1's names; an empty file has no layout: the model's first table missing
    with pytest.raises(ParameterError) as info:
        load_parameters(write(tmp_path, "wheelbase = 1.02\n", "flat.toml"))
    assert (info.value.key, info.value.problem) == ("wheelbase", "unknown benchmark parameter 'wheelbase'")
    with pytest.raises(ParameterError) as info:
        load_parameters(write(tmp_path, "", "empty.toml"))
    assert (info.value.key, info.value.problem) == ("geometry", "table [geometry] is missing")


def test_missing_file_lists_the_named_models() -> None:
    with pytest.raises(ParameterError) as info:
        load_parameters("nope.toml")
    assert info.value.fix == ("give the path of an existing .toml parameter file "
                              "(named models: thesis, thesis-disc, benchmark)")


def test_unreadable_and_non_utf8_files_are_one_error_each(tmp_path: Path) -> None:
    with pytest.raises(ParameterError) as info:
        load_parameters(tmp_path)                     # a folder: the OS's own reason, no errno
    err = info.value
    assert (err.file, err.key, err.problem, err.fix) == (
        str(tmp_path), "(file)", "cannot read the file: Is a directory",
        "give the path of a readable .toml parameter file")
    path = tmp_path / "latin1.toml"
    path.write_bytes("# Bicicleta de Álvaro\n".encode("latin-1"))   # Á (0xC1) follows the 15 bytes "# Bicicleta de "
    with pytest.raises(ParameterError) as info:
        load_parameters(path)
    err = info.value
    assert (err.file, err.key, err.problem, err.fix) == (
        str(path), "(file)", "not UTF-8 text (byte 15)", "save the file as UTF-8")


def test_non_positive_moments_are_listed_with_their_unit() -> None:
    with pytest.raises(ParameterError) as info:
        Parameters(**thesis_dict() | {"I4xx": -1.0, "I4yy": 0.0})    # zero is not positive either
    err = info.value
    assert err.key == "inertia.I4xx, inertia.I4yy"
    assert err.problem == ("inertia of body 4 (fork/handlebar) is not positive definite: "
                           "I4xx = -1.0, I4yy = 0.0 kg*m^2 (moments must be > 0)")
    assert err.fix == "use positive moments of inertia in kg*m^2"


@pytest.mark.filterwarnings("ignore::reference_model.params.ParameterWarning")  # unusual on purpose
def test_a_singular_or_indefinite_xz_block_states_the_limit() -> None:
    # xx zz - xz^2 = 9 - 9 = 0 exactly: singular, not positive definite
    with pytest.raises(ParameterError, match="not positive definite"):
        Parameters(**thesis_dict() | {"I3xx": 3.0, "I3zz": 3.0, "I3xz": 3.0, "I3yy": 4.0})
    with pytest.raises(ParameterError) as info:
        Parameters(**thesis_dict() | {"I3xx": 3.0, "I3zz": 3.0, "I3xz": 5.0, "I3yy": 4.0})
    err = info.value
    assert err.key == "inertia.I3xz, inertia.I3xx, inertia.I3zz"
    assert err.problem == ("inertia of body 3 (frame+rider) is not positive definite: "
                           "I3xz^2 = 25.0 >= I3xx*I3zz = 9.0 (kg*m^2)^2")
    assert err.fix == "make |I3xz| < sqrt(I3xx*I3zz) = 3 kg*m^2 (check its sign and units)"   # sqrt(9)


def test_unknown_contact_lists_the_models() -> None:
    with pytest.raises(ParameterError) as info:
        Parameters(**thesis_dict(), contact="sphere")
    assert info.value.key == "model.contact"
    assert info.value.fix == ("use one of 'thesis', 'disc' ('thesis': rim point along the fork z "
                              "axis; 'disc': lowest point of the disc)")


def test_a_benchmark_file_is_read_as_one_by_its_suffix_and_takes_the_overrides(tmp_path: Path) -> None:
    from reference_model.parameters.benchmark import TABLE1
    # a .json holding a model parameter's name is still a Table 1 file: its suffix says so
    with pytest.raises(ParameterError) as info:
        load_parameters(write(tmp_path, '{"x3": 0.3}', "odd.JSON"))
    assert info.value.problem == "unknown benchmark parameter 'x3'"
    path = write(tmp_path, __import__("json").dumps(TABLE1.as_dict()), "bike.json")
    p = load_parameters(path)
    assert (p.source, p.name, p.contact) == (str(path), "bike", "disc")
    q = load_parameters(path, contact="thesis", name="other")
    assert (q.source, q.name, q.contact) == (str(path), "other", "thesis")


@pytest.mark.filterwarnings("ignore::reference_model.params.ParameterWarning")  # unusual on purpose
def test_triangle_violations_name_the_moments_and_every_key() -> None:
    # a wheel: principal moments are the diagonal, 3 > 1 + 1
    with pytest.raises(ParameterError) as info:
        Parameters(**thesis_dict() | {"I2xx": 1.0, "I2yy": 1.0, "I2zz": 3.0})
    err = info.value
    assert err.key == "inertia.I2zz"
    assert err.problem == ("inertia of body 2 (rear wheel) violates the triangle inequality of "
                           "principal moments (I1 + I2 >= I3 for a real body): I2zz = 3.0 > sum of "
                           "the other two moments = 2.0 kg*m^2")
    assert err.fix.startswith("check the values and units of I2xx, I2yy, I2zz;")
    # the frame: [[3, 1], [1, 3]] has eigenvalues 3 +- 1 = (4, 2); 4 > 1 + 2 along the first axis
    with pytest.raises(ParameterError) as info:
        Parameters(**thesis_dict() | {"I3xx": 3.0, "I3zz": 3.0, "I3xz": 1.0, "I3yy": 1.0})
    err = info.value
    assert err.key == "inertia.I3xx, inertia.I3zz, inertia.I3xz"
    assert err.problem.endswith(": principal moments (4.0, 1.0, 2.0) kg*m^2: 4.0 > sum of the "
                                "other two = 3.0")
    assert err.fix.startswith("check the values and units of I3xx, I3yy, I3zz, I3xz;")


@pytest.mark.filterwarnings("ignore::reference_model.params.ParameterWarning")  # unusual on purpose
def test_triangle_tolerance_is_relative_to_the_largest_moment() -> None:
    # TRIANGLE_RTOL = 1e-12 of the largest moment (2 here): 1.5e-12 over is rounding, 3e-12 is not
    Parameters(**thesis_dict() | {"I5xx": 1.0, "I5yy": 1.0, "I5zz": 2.0 + 1.5e-12})
    with pytest.raises(ParameterError, match="triangle inequality"):
        Parameters(**thesis_dict() | {"I5xx": 1.0, "I5yy": 1.0, "I5zz": 2.0 + 3e-12})


def test_a_tiny_moment_is_outside_the_range_not_skipped() -> None:
    with pytest.raises(ParameterError) as info:
        Parameters(**thesis_dict() | {"I2yy": 1e-12})     # below 1e-9 kg m^2: no bicycle part
    assert info.value.key == "inertia.I2yy" and "is outside the range" in info.value.problem


def test_bounds_after_a_non_positive_moment_are_still_checked() -> None:
    # the bounds run before the tensors (schema docstring): g's absurd value is the error
    with pytest.raises(ParameterError) as info:
        Parameters(**thesis_dict() | {"I2xx": -1.0, "g": 1e6})
    assert info.value.key == "environment.g"


def test_the_benchmark_tools_help_says_what_each_option_does(capsys, monkeypatch) -> None:
    from reference_model.parameters.loading import BENCHMARK_FILE, main
    monkeypatch.setenv("COLUMNS", "1000")      # argparse wraps (even at hyphens of the path)
    with pytest.raises(SystemExit) as info:
        main(["--help"])
    assert info.value.code == 0
    out = " ".join(capsys.readouterr().out.split())
    assert out.startswith("usage: python -m reference_model.benchmark [-h] (--write | --check) ")
    assert "``--write`` regenerates benchmark.toml; ``--check`` compares it with the formulas" in out
    assert f"--write write {BENCHMARK_FILE}" in out
    assert "--check exit 1 if the file's values differ" in out


@pytest.mark.parametrize(("changes", "key", "span", "unit"), [
    ({"x3": 20.0}, "geometry.x3", "|x3| <= 10 m", "m"),             # a signed length: |value|
    ({"cv": 200.0}, "environment.cv", "0 to 100 kg/m", "kg/m"),      # low 0, but not a magnitude
])
def test_an_absurd_value_states_its_range_and_the_fix(changes, key, span, unit) -> None:
    with pytest.raises(ParameterError) as info:
        Parameters(**thesis_dict() | changes)
    err = info.value
    assert err.key == key and f"({span}; " in err.problem
    assert err.fix == f"check the value and its unit (the range is in {unit}, after unit conversion)"


@pytest.mark.filterwarnings("ignore::reference_model.params.ParameterWarning")  # unusual on purpose
def test_a_frame_without_product_is_named_like_a_wheel() -> None:
    # I3xz = 0: the diagonal are the principal moments, 3 > 1 + 1 names I3xx alone
    with pytest.raises(ParameterError) as info:
        Parameters(**thesis_dict() | {"I3xx": 3.0, "I3yy": 1.0, "I3zz": 1.0, "I3xz": 0.0})
    assert info.value.key == "inertia.I3xx"
    assert info.value.problem.endswith(": I3xx = 3.0 > sum of the other two moments = 2.0 kg*m^2")
