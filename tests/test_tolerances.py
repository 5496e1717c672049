"""comparisons/tolerances.py: the tolerance file's validation and the error scales.

Every malformed entry must be refused with a message naming the file, the quantity and the
field; each scale divides an absolute error by what its name says (values by hand).
"""

import dataclasses

import numpy as np
import pytest

import pickle
import re

from comparisons.judgments.tolerances import (TOLERANCES_FILE, Tolerance, ToleranceError,
                                              Tolerances, load_complete, load_tolerances)

GOOD = 'tolerance = 1e-6\nscale = "absolute"\nreason = "why"\n'


def _load(tmp_path, text):
    path = tmp_path / "tol.toml"
    path.write_text(text)
    return load_tolerances(path), path


def test_shipped_file_loads_with_reasons():
    tols = load_tolerances()
    assert {"mass_matrix", "trajectory", "constraint_residual", "torques"} <= set(tols)
    for name, t in tols.items():
        assert t.quantity == name and 0 < t.tolerance < 1 and t.reason.strip()


def test_a_good_entry_is_read_exactly(tmp_path):
    tols, _ = _load(tmp_path, "[trajectory]\n" + GOOD)
    assert tols == {"trajectory": Tolerance("trajectory", 1e-6, "absolute", "why")}
    assert isinstance(tols["trajectory"].tolerance, float)


def test_the_tolerances_are_a_value_that_pickles_and_hashes(tmp_path):
    """What a stage's Task args and a Dask task carry: equal after a pickle round trip (a worker
    judges by exactly these), hashable, equal for equal tables whatever the file's name, and
    no environment variable selects them."""
    tols = load_tolerances()
    assert isinstance(tols, Tolerances) and tols == load_tolerances(TOLERANCES_FILE)
    back = pickle.loads(pickle.dumps(tols))
    assert back == tols and hash(back) == hash(tols) and back["mass_matrix"] == tols["mass_matrix"]
    copy = tmp_path / "copy.toml"
    copy.write_text(TOLERANCES_FILE.read_text())
    assert load_tolerances(copy) == tols and load_tolerances(copy).source == str(copy)
    tighter = tmp_path / "tighter.toml"
    tighter.write_text(TOLERANCES_FILE.read_text().replace(
        "[mass_matrix]\ntolerance = 1e-12", "[mass_matrix]\ntolerance = 1e-13"))
    assert load_tolerances(tighter) != tols and load_tolerances(tighter).as_json() != tols.as_json()
    with pytest.raises(KeyError, match="no_such_quantity"):
        tols["no_such_quantity"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        tols.entries = ()


def test_a_user_file_must_have_every_packaged_table(tmp_path):
    path = tmp_path / "few.toml"
    path.write_text("[mass_matrix]\n" + GOOD)
    with pytest.raises(ToleranceError, match=r"lacks \[inverse_dynamics\] \(and \d+ more\)"):
        load_complete(path)
    gone = tmp_path / "missing.toml"
    with pytest.raises(ToleranceError, match="no file " + re.escape(repr(str(gone)))):
        load_complete(gone)
    assert load_complete(TOLERANCES_FILE) == load_tolerances()


def test_the_missing_tables_are_counted_and_a_single_one_named_alone(tmp_path):
    """The count after the first missing table is the packaged file's tables (read here with
    tomllib) less the one the file has and the one named; a file lacking only one table names
    it without '(and ...)'."""
    import tomllib
    tables = list(tomllib.loads(TOLERANCES_FILE.read_text()))
    path = tmp_path / "few.toml"
    path.write_text("[mass_matrix]\n" + GOOD)
    with pytest.raises(ToleranceError, match=rf"lacks \[{tables[1]}\] \(and {len(tables) - 2} "
                                             r"more\); start from a copy of"):
        load_complete(path)
    almost = tmp_path / "almost.toml"
    almost.write_text("".join(f"[{name}]\n" + GOOD for name in tables[:-1]))
    with pytest.raises(ToleranceError, match=rf"{almost} lacks \[{tables[-1]}\]; start from"):
        load_complete(almost)
    two = tmp_path / "two.toml"
    two.write_text("".join(f"[{name}]\n" + GOOD for name in tables[:-2]))
    with pytest.raises(ToleranceError, match=rf"lacks \[{tables[-2]}\] \(and 1 more\);"):
        load_complete(two)


def test_as_json_is_the_files_tables_and_each_scale_divides_by_its_own_number():
    """as_json (what a sweep's spec hash covers) is the file's tables as tomllib reads them,
    under the same keys; the normalizers by hand: 'absolute' 1, 'max_abs' the largest |entry|
    (1 for an all-zero reference), 'max_abs_or_one' at least 1 and never the terms,
    'largest_term' the largest |entry| of the terms (at least 1)."""
    import tomllib
    assert load_tolerances().as_json() == tomllib.loads(TOLERANCES_FILE.read_text())
    ref, terms = np.array([[0.5, -3.0]]), [np.array([7.0]), np.array([-20.0])]
    by = {s: Tolerance("x", 1e-6, s, "why") for s in ("absolute", "max_abs", "max_abs_or_one",
                                                      "largest_term")}
    assert by["absolute"].normalizer(ref, terms) == 1.0
    assert by["max_abs"].normalizer(ref, terms) == 3.0
    assert by["max_abs"].normalizer(np.zeros(2)) == 1.0
    assert by["max_abs_or_one"].normalizer(ref, terms) == 3.0
    assert by["max_abs_or_one"].normalizer(np.array([0.5])) == 1.0
    assert by["largest_term"].normalizer(ref, terms) == 20.0
    assert by["largest_term"].normalizer(np.array([0.25])) == 1.0


def test_tolerances_equal_a_mapping_only_with_the_same_tables():
    tols = load_tolerances()
    assert tols == dict(tols)
    assert tols != {} and tols != {**dict(tols), "mass_matrix": None}
    assert tols != [("mass_matrix", tols["mass_matrix"])]


ENTRY = "[x]\n" + GOOD


@pytest.mark.parametrize("text, fragment", [
    ("[x\n", "tol.toml: "),                                                 # TOML syntax
    ("x = 3\n", "[x] must be a table"),
    ('[x]\ntolerance = 1e-6\nscale = "absolute"\n', "[x] lacks reason"),
    ('[x]\nscale = "absolute"\n', "[x] lacks reason, tolerance"),
    (ENTRY.replace("1e-6", "0"), "x.tolerance must be a number in (0, 1); got 0"),
    (ENTRY.replace("1e-6", "1"), "x.tolerance must be a number in (0, 1); got 1"),
    (ENTRY.replace("1e-6", "-1e-3"), "got -0.001"),
    (ENTRY.replace("1e-6", "true"), "got True"),
    (ENTRY.replace("1e-6", '"1e-6"'), "got '1e-6'"),
    (ENTRY.replace('"absolute"', '"relative"'), "x.scale must be one of"),
    (ENTRY.replace('"why"', '"  "'), "x.reason is empty"),
])
def test_malformed_entry_is_named(tmp_path, text, fragment):
    with pytest.raises(ToleranceError) as info:
        _load(tmp_path, text)
    message = str(info.value)
    assert fragment in message and "tol.toml" in message and "\n" not in message, message


def test_tolerance_just_inside_the_bounds_is_accepted(tmp_path):
    for value in ("1e-300", "0.999999"):
        tols, _ = _load(tmp_path, ENTRY.replace("1e-6", value))
        assert tols["x"].tolerance == float(value)


@pytest.mark.parametrize("scale, reference, terms, expected", [
    ("absolute", [3.0, -7.0], None, 1.0),
    ("max_abs", [3.0, -7.0], None, 7.0),
    ("max_abs", [0.0, 0.0], None, 1.0),           # nothing to be relative to: absolute
    ("max_abs", [0.2, -0.5], None, 0.5),          # small values are not rounded up
    ("max_abs_or_one", [0.2, -0.5], None, 1.0),
    ("max_abs_or_one", [3.0, -7.0], None, 7.0),
    ("largest_term", [0.5], [[2.0, -30.0], [4.0]], 30.0),
    ("largest_term", [0.5], [[0.2], [-0.4]], 1.0),
    ("largest_term", [-12.0, 3.0], None, 12.0),   # no terms given: the reference itself
])
def test_normalizer(scale, reference, terms, expected):
    t = Tolerance("x", 1e-6, scale, "why")
    assert t.normalizer(np.array(reference), terms) == expected
