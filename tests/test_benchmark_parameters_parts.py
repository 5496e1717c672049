"""The parts of reference_model/parameters/benchmark.py that the Table 1 round trips do not pin:
the triangle inequality of principal moments (its tolerance ``TRIANGLE_RTOL`` times the largest
moment, the keys and the message of a violation, ``checked_table``'s default of refusing it),
the consistency check of a model against its stored Table 1 (``CONSISTENCY_RTOL`` times the
documented scale of each parameter), ``consistent_table``'s errors (the ``[benchmark]`` table's
keys, the file named), ``Table1``'s own errors, and the reverse's upright pitch at its limits.

Expected values are Meijaard et al. (2007) Table 1 (``TABLE1``'s defaults) and hand arithmetic:
principal moments of a 2x2 block ``mean +- hypot(half difference, xz)``, the pitch equation
``R_rear - a sin(beta) + b cos(beta) = R_front`` solved by hand for chosen ``a, b``. Each test
names the planted bugs (mutmut's survivors of the module's measurement) it fails on.
"""

from __future__ import annotations

import decimal
import math

import pytest

from reference_model.parameters.benchmark import (
    CONSISTENCY_RTOL, TABLE1, Table1, _upright_pitch, benchmark_values, checked_table,
    consistent_table, inconsistency, model_values, table1_from_mapping)
from reference_model.parameters.schema import (TRIANGLE_RTOL, ParameterError,
                                               TriangleInequalityError)

TRIANGLE_FIX = ("check the values and units; if they are measured and right, allow it with "
                "allow_triangle_violation=True (bicycle-xval import --allow-triangle-violation)")


def _table(**changes) -> dict[str, float]:
    return {**TABLE1.as_dict(), **changes}


# -- the triangle inequality ------------------------------------------------------------------


def test_wheel_polar_moment_beyond_twice_the_diametral_is_refused_with_its_key_and_margin():
    """A rear wheel with IRyy = 0.2 > IRxx + IRzz = 2 * 0.0603 = 0.1206 breaks the triangle
    inequality on its y moment: ``checked_table`` refuses it by default, naming only IRyy, the
    excess 0.2 / 0.1206 - 1 = 65.84 %, both sides and the principal moments (0.0603, 0.2, 0.0603)
    (rounded to 12 digits), with the fix naming the flag. Planted: the default
    ``allow_triangle_violation=True``; the prefix "XXXX" on the keys; the keys joined by
    "XX, XX"; the excess printed as ratio + 1; the moments rounded to integers (``round(m,
    None)``, ``round(m)``) or replaced by ``round(12)``; the fix's text altered or upper-cased."""
    with pytest.raises(TriangleInequalityError) as err:
        checked_table(_table(IRyy=0.2))
    e = err.value
    assert e.file == "<memory>"
    assert e.key == "IRyy"
    assert e.problem == ("inertia of the rear wheel violates the triangle inequality of "
                         "principal moments by 65.84%: 0.2 > 0.1206 (sum of the other two; "
                         "principal moments (0.0603, 0.2, 0.0603) kg m^2)")
    assert e.fix == TRIANGLE_FIX
    # allowed on request: the same values make a table
    assert checked_table(_table(IRyy=0.2), allow_triangle_violation=True).IRyy == 0.2


def test_principal_moments_in_the_message_are_rounded_to_twelve_decimals():
    """The principal moments in the message are rounded to 12 decimals: IRxx = 0.0612345678901234
    shows as 0.061234567890 (repr 0.06123456789), not 0.0612345678901 (13 decimals). Planted:
    ``round(m, 13)``."""
    ixx = 0.0612345678901234
    with pytest.raises(TriangleInequalityError) as err:
        checked_table(_table(IRxx=ixx, IRyy=0.2))
    assert "principal moments (0.06123456789, 0.2, 0.06123456789) kg m^2" in err.value.problem


def test_product_of_inertia_enters_the_rear_body_s_principal_moments():
    """Rear body IBxx = IBzz = 1, IBxz = 0.9, IByy = 1.5: positive definite (1 - 0.81 > 0), and
    its x-z block has principal moments 1 +- 0.9 = 1.9 and 0.1; 1.9 > 1.5 + 0.1 breaks the
    triangle inequality by 1.9 / 1.6 - 1 = 18.75 %, on an x-z moment, so the keys are IBxx, IBzz,
    IBxz (the diagonal alone, 1, 1.5, 1, is fine). Planted: the xz product ignored (moments
    from the diagonal); the keys of a violation always [IByy]."""
    with pytest.raises(TriangleInequalityError) as err:
        checked_table(_table(IBxx=1.0, IByy=1.5, IBzz=1.0, IBxz=0.9))
    assert err.value.key == "IBxx, IBzz, IBxz"
    assert "rear body + rider violates the triangle inequality" in err.value.problem
    assert "by 18.75%" in err.value.problem


def test_a_violation_exactly_at_the_tolerance_is_accepted_and_beyond_it_refused():
    """The tolerance is ``TRIANGLE_RTOL`` (1e-12) times the largest principal moment: with IRyy
    = 1 and IRxx = (1 - 1e-12) / 2 (exact in binary: a halving), IRxx + IRzz falls short of IRyy
    by exactly 1e-12 * 1 and is accepted; with IRyy = 0.1 and IRxx = 0.05 the shortfall 1e-12
    is ten times 1e-12 * 0.1 and is refused. Planted: ``<=`` for ``<`` (the boundary refused);
    the tolerance ``TRIANGLE_RTOL / max`` (1e-11 at 0.1 kg m^2, the violation let through)."""
    at_limit = (1.0 - TRIANGLE_RTOL) / 2.0
    assert 2.0 * at_limit == 1.0 - TRIANGLE_RTOL * 1.0
    assert checked_table(_table(IRxx=at_limit, IRyy=1.0)).IRxx == at_limit
    with pytest.raises(TriangleInequalityError) as err:
        checked_table(_table(IRxx=0.05, IRyy=0.1 + 1e-12))
    assert err.value.key == "IRyy"


# -- Table1's own errors ----------------------------------------------------------------------


def test_table1_names_memory_and_the_key_of_a_value_that_is_not_a_number():
    """``Table1(w=nan)`` (built in code) fails naming the source "<memory>" and the key "w".
    Planted: the source None; the key None."""
    with pytest.raises(ParameterError) as err:
        Table1(w=float("nan"))
    assert err.value.file == "<memory>"
    assert err.value.key == "w"
    assert str(err.value).startswith("<memory>: w: ")


# -- consistency with a stored Table 1 --------------------------------------------------------


def _xa_by_hand() -> float:
    """xa = (w + c) cos(lam) - rR sin(lam) for Table 1: the largest of the 10 lengths."""
    return 1.1 * math.cos(math.pi / 10) - 0.3 * math.sin(math.pi / 10)


def test_a_length_edited_by_more_than_the_tolerance_of_the_largest_length_is_caught():
    """The lengths' scale is the largest of the 10 geometric values (xa = 1.1 cos(pi/10) - 0.3
    sin(pi/10) = 0.9535 m for Table 1), not the masses: x3 moved by 1.5 * CONSISTENCY_RTOL * xa
    is an inconsistency. Planted: the scale taken over the first 11 names (m2 = 2 kg joins the
    lengths, the tolerance grows past the edit)."""
    values = model_values(TABLE1)
    assert max(abs(values[n]) for n in ("x3", "z3", "xa", "za", "dx4", "dz4", "x5")) == \
        pytest.approx(_xa_by_hand(), rel=1e-12)
    values["x3"] += 1.5 * CONSISTENCY_RTOL * _xa_by_hand()
    name, found, expected = inconsistency(values, TABLE1)
    assert name == "x3" and found == values["x3"]
    assert expected == pytest.approx(values["x3"], rel=1e-13)


def test_a_mass_is_judged_on_its_own_size_and_an_inertia_on_its_body_s_largest_entry():
    """m2 (2 kg) moved by half its tolerance (0.5 * CONSISTENCY_RTOL * 2) is rounding, not an
    edit; so is I3xz (-3.82 kg m^2) moved by half the tolerance of its body's largest entry
    (I3yy = IByy = 11 kg m^2). Planted: m2 judged on the lengths' scale (0.95 m, the move
    exceeds it); the bodies (4, 4) (I3xz judged on its own 3.82, the move exceeds it)."""
    values = model_values(TABLE1)
    values["m2"] += 0.5 * CONSISTENCY_RTOL * 2.0
    values["I3xz"] += 0.5 * CONSISTENCY_RTOL * 11.0
    assert values["m2"] != 2.0 and values["I3xz"] != model_values(TABLE1)["I3xz"]
    assert inconsistency(values, TABLE1) is None


def test_consistent_table_errors_name_the_benchmark_table_and_the_file():
    """A ``[benchmark]`` table with a bad entry is an error in the file given, at key
    ``benchmark.w``; a model value that does not follow from a good table is an error at
    ``geometry.x3`` whose problem and fix name the ``[benchmark]`` table. Planted: the default
    key "XXbenchmarkXX" / "BENCHMARK"; the file not passed on (None, or the default
    "<memory>"); the prefix dropped (key "w"); the fix None."""
    with pytest.raises(ParameterError) as err:
        consistent_table(model_values(TABLE1), _table(w=-1.0), source="bike.toml")
    assert err.value.file == "bike.toml"
    assert err.value.key == "benchmark.w"
    values = model_values(TABLE1)
    values["x3"] += 1e-6
    with pytest.raises(ParameterError) as err:
        consistent_table(values, TABLE1.as_dict(), source="bike.toml")
    e = err.value
    assert (e.file, e.key) == ("bike.toml", "geometry.x3")
    assert "does not follow from the [benchmark] table" in e.problem
    assert e.fix == ("regenerate the file from its benchmark parameters (bicycle-xval import), "
                     "or remove the [benchmark] table if the model's values were changed on "
                     "purpose")
    assert consistent_table(model_values(TABLE1), TABLE1.as_dict(), source="bike.toml") == TABLE1


# -- the reverse: the upright pitch at its limits ---------------------------------------------


def test_upright_pitch_when_the_front_wheel_just_reaches_the_ground():
    """Hub 0.5 m straight above the rear hub in frame axes (a = 0, b = 0.5), R_rear = 0.3,
    R_front = 0.8: 0.3 + 0.5 cos(beta) = 0.8 has the single root beta = 0 (|k| = rho, the
    tangent case). Planted: ``|k| < rho`` (the tangent case taken for no root)."""
    p = {"xa": 0.0, "x5": 0.0, "za": 0.5, "z5": 0.0, "R_rear": 0.3, "R_front": 0.8}
    assert _upright_pitch(p) == 0.0


def test_upright_pitch_takes_the_smaller_root_behind_the_rear_hub():
    """a = -1, b = 1, equal radii: -a sin(beta) + b cos(beta) = sin(beta) + cos(beta) = 0 has
    roots -pi/4 and 3pi/4; the smaller |beta| is -pi/4. Planted: the roots (1.0, +1.0) (only
    -phi + delta = 3pi/4 kept)."""
    p = {"xa": -1.0, "x5": 0.0, "za": 1.0, "z5": 0.0, "R_rear": 0.3, "R_front": 0.3}
    assert _upright_pitch(p) == pytest.approx(-math.pi / 4, abs=1e-15)
    p = dict(p, xa=1.0)         # mirrored: sin = cos at +pi/4
    assert _upright_pitch(p) == pytest.approx(math.pi / 4, abs=1e-15)


def test_a_pitch_of_exactly_a_right_angle_has_no_benchmark_counterpart():
    """Front hub 1 m along the frame's x from the rear hub (a = 1, b = 0) and R_front - R_rear =
    1: 0.3 - sin(beta) = 1.3 gives beta = -pi/2, a steer axis lying flat, not a tilt in (-pi/2,
    pi/2): the export refuses it. Planted: ``<=`` for ``<`` in the check (a flat axis let
    through)."""
    values = dict(model_values(TABLE1), xa=1.0, x5=0.0, za=0.0, z5=0.0, R_rear=0.3, R_front=1.3)
    with pytest.raises(ParameterError) as err:
        benchmark_values(values, contact="disc", name="flat", source="flat.toml")
    assert err.value.file == "flat.toml"
    assert "gives no steer axis tilt in (-pi/2, pi/2)" in err.value.problem
    assert "upright pitch beta = -1.5707963267948966 rad" in err.value.problem



# -- the checks on Table 1 (module docstring, "Checks on Table 1") ----------------------------


def _refused(**changes) -> ParameterError:
    """The error of a ``[benchmark]`` table of a file "bike.toml" with ``changes``."""
    with pytest.raises(ParameterError) as err:
        table1_from_mapping(_table(**changes), source="bike.toml", prefix="benchmark.")
    return err.value


def test_a_zero_wheel_base_is_refused_naming_the_file_key_and_fix():
    """w must be > 0: w = 0 is refused in the file given, at ``benchmark.w``, with Table 1's
    description and the fix "use a positive w". Planted: ``>= 0`` (zero accepted); the file
    None; the fix None."""
    e = _refused(w=0.0)
    assert (e.file, e.key) == ("bike.toml", "benchmark.w")
    assert e.problem == "w = 0.0 must be > 0 (wheel base, m)"
    assert e.fix == "use a positive w"


@pytest.mark.parametrize("lam", [math.pi / 2, -math.pi / 2, 2.0, -3.0])
def test_a_steer_axis_tilt_outside_the_open_right_angle_is_refused(lam):
    """|lam| < pi/2 (module docstring): pi/2 itself (a steer axis lying flat), 2 rad and -3 rad
    are refused at ``benchmark.lam`` in the file given, with the fix giving Table 1's pi/10.
    Planted: ``<=`` (pi/2 accepted); ``pi * 2`` for ``pi / 2`` (2 rad and -3 rad accepted);
    the file None; the fix None, framed in "XX" or upper-cased."""
    e = _refused(lam=lam)
    assert (e.file, e.key) == ("bike.toml", "benchmark.lam")
    assert e.problem == f"lam = {lam!r} rad is not a steer axis tilt in (-pi/2, pi/2)"
    assert e.fix == "give lam in radians (pi/2 - head angle), e.g. 0.3141592653589793"


def test_a_zero_moment_of_inertia_is_refused_naming_the_body_and_its_keys():
    """A rear wheel with IRxx = 0 (which is also its IRzz) is not positive definite: refused in
    the file given at ``benchmark.IRxx`` (named once), naming the rear wheel and the value, with
    the fix in kg m^2. Planted: ``>= 0`` (zero accepted); the list of bad keys None; the file
    None or dropped (the arguments shifted); the key None or dropped; the problem None; the fix
    None."""
    e = _refused(IRxx=0.0)
    assert (e.file, e.key) == ("bike.toml", "benchmark.IRxx")
    assert e.problem == "inertia of the rear wheel is not positive definite: IRxx = 0.0"
    assert e.fix == "use positive moments of inertia in kg m^2"
    e = _refused(IHyy=-1.0, IHzz=0.0)
    assert e.key == "benchmark.IHyy, benchmark.IHzz"
    assert e.problem == ("inertia of the front assembly is not positive definite: "
                         "IHyy = -1.0, IHzz = 0.0")


def test_a_product_of_inertia_too_large_for_its_diagonal_is_refused():
    """IBxx = 4, IBzz = 2, IBxz = 3: IBxz^2 = 9 >= IBxx*IBzz = 8, not positive definite; refused
    at the three keys with the bound sqrt(8) = 2.82843 kg m^2 in the fix. At IBxz = 2 with IBxx =
    4, IBzz = 1 the block is singular (4 = 4) and refused too; the negative product -3 is
    refused like +3 (its square). Planted: the x-z check's comparison (``>=``), the square
    (``** 3``: -3 cubed passes), the file, keys, message and fix None, altered or upper-cased."""
    e = _refused(IBxx=4.0, IBzz=2.0, IBxz=3.0)
    assert (e.file, e.key) == ("bike.toml", "benchmark.IBxz, benchmark.IBxx, benchmark.IBzz")
    assert e.problem == ("inertia of the rear body + rider is not positive definite: "
                         "IBxz^2 = 9.0 >= IBxx*IBzz = 8.0")
    assert e.fix == "make |IBxz| < sqrt(IBxx*IBzz) = 2.82843 kg m^2 (check its sign and units)"
    assert _refused(IBxx=4.0, IBzz=1.0, IBxz=2.0).key.startswith("benchmark.IBxz")
    assert _refused(IHxx=4.0, IHzz=2.0, IHxz=-3.0).problem.startswith(
        "inertia of the front assembly is not positive definite: IHxz^2 = 9.0")
    assert table1_from_mapping(_table(IBxx=4.0, IBzz=2.0, IBxz=2.8)).IBxz == 2.8


def test_table1_built_in_code_validates_naming_memory_and_the_bare_key():
    """``Table1(w=-1)`` (in code, no file, no table prefix) is refused naming "<memory>" and
    the key "w" itself. Planted: the source None; the prefix None (a TypeError, not a
    ParameterError) or "XXXX"."""
    with pytest.raises(ParameterError) as err:
        Table1(w=-1.0)
    assert (err.value.file, err.value.key) == ("<memory>", "w")


# -- reading a Table 1 mapping (table1_from_mapping's documented errors) ----------------------

NAMES_LIST = ("w, c, lam, g, rR, mR, IRxx, IRyy, xB, zB, mB, IBxx, IByy, IBzz, IBxz, xH, zH, mH, "
              "IHxx, IHyy, IHzz, IHxz, rF, mF, IFxx, IFyy")


def test_a_mapping_is_required_and_a_table1_passes_through():
    """A list is not a Table 1: refused at the table's key ``benchmark`` (the prefix without
    its dot), or "(benchmark)" without a prefix, naming the type and how to write it; a Table1
    is returned as it is. Planted: the file None; the key None; the prefix stripped of "XX.XX" (mutmut's
    survivors); the
    type's repr for its name; a Table1 copied instead of returned (by hand)."""
    with pytest.raises(ParameterError) as err:
        table1_from_mapping([1.02, 0.08], source="bike.toml", prefix="benchmark.")
    e = err.value
    assert (e.file, e.key) == ("bike.toml", "benchmark")
    assert e.problem == "expected a mapping of Table 1 names to numbers, got list"
    assert e.fix == "give w, c, lam, g, rR, ... as name = value pairs"
    with pytest.raises(ParameterError) as err:
        table1_from_mapping(3.0)
    assert (err.value.file, err.value.key) == ("<memory>", "(benchmark)")
    with pytest.raises(ParameterError) as err:
        table1_from_mapping([], prefix="bikeX.")
    assert err.value.key == "bikeX"
    assert table1_from_mapping(TABLE1) is TABLE1


def test_an_unknown_name_is_refused_with_the_closest_and_the_list_of_names():
    """An unknown key "ww" is refused at ``benchmark.ww`` suggesting "w" and listing Table 1's
    26 names in order; a key like nothing ("zzzzzz") is told to be removed. Planted (by hand): the "remove it; "
    dropped."""
    with pytest.raises(ParameterError) as err:
        table1_from_mapping(_table(ww=1.0), source="bike.toml", prefix="benchmark.")
    e = err.value
    assert (e.file, e.key) == ("bike.toml", "benchmark.ww")
    assert e.problem == "unknown benchmark parameter 'ww'"
    assert e.fix == "did you mean 'w'? Table 1's names are " + NAMES_LIST
    with pytest.raises(ParameterError) as err:
        table1_from_mapping(_table(zzzzzz=1.0))
    assert err.value.fix == "remove it; Table 1's names are " + NAMES_LIST


def test_missing_names_are_counted_listed_and_the_first_three_described():
    """One missing name (IFyy) is "1 of Table 1's 26 parameters missing: IFyy" with its
    description in the fix; four missing are all keyed and listed, the fix describing the first
    three and ending in "; ...". Planted: "; ..." after exactly three (``>= 3``) or only after
    five (``> 4``); (by hand) the first four described."""
    t = _table()
    del t["IFyy"]
    with pytest.raises(ParameterError) as err:
        table1_from_mapping(t, source="bike.toml", prefix="benchmark.")
    e = err.value
    assert (e.file, e.key) == ("bike.toml", "benchmark.IFyy")
    assert e.problem == "1 of Table 1's 26 parameters missing: IFyy"
    assert e.fix == "add IFyy (front wheel polar inertia, kg m^2)"
    for n in ("w", "c", "lam", "g"):
        del t[n]
    with pytest.raises(ParameterError) as err:
        table1_from_mapping(t)
    e = err.value
    assert e.key == "w, c, lam, g, IFyy"
    assert e.problem == "5 of Table 1's 26 parameters missing: w, c, lam, g, IFyy"
    assert e.fix == ("add w (wheel base, m); c (trail, m); lam (steer axis tilt from vertical "
                     "(pi/2 - head angle), rad); ...")
    three, four = _table(), _table()
    for n in ("w", "c", "lam"):
        del three[n], four[n]
    del four["g"]
    with pytest.raises(ParameterError) as err:
        table1_from_mapping(three)
    assert not err.value.fix.endswith("...")
    with pytest.raises(ParameterError) as err:
        table1_from_mapping(four)
    assert err.value.fix.endswith("rad); ...")


def test_decimals_and_integers_are_read_as_floats():
    """Decimal("1.02") and the integer 2 are real numbers: read as the floats 1.02 and 2.0.
    Planted (by hand): a Decimal read from its first three characters (1.0)."""
    t = table1_from_mapping(_table(w=decimal.Decimal("1.02"), mR=2))
    assert type(t.w) is float and t.w == 1.02
    assert type(t.mR) is float and t.mR == 2.0


# -- the export's blockers (benchmark_values) ------------------------------------------------


def test_every_blocker_of_an_export_is_listed_in_one_error():
    """A model with the thesis contact, drag cv = 0.1, a rear wheel with I2zz = 0.07 != I2xx =
    0.0603, a front wheel with I5zz = 0.2 != I5xx = 0.1405 and a front wheel too small to reach
    the ground (R_front = 5 m above a hub 1 m from the rear hub) has no benchmark counterpart:
    one error at "(benchmark export)" listing each, in that order, and the fix. Planted (by
    hand): the front wheel not checked; only the first blocker reported."""
    values = dict(model_values(TABLE1), cv=0.1, I2zz=0.07, I5zz=0.2, R_front=5.0)
    with pytest.raises(ParameterError) as err:
        benchmark_values(values, contact="thesis", name="odd", source="odd.toml")
    e = err.value
    assert (e.file, e.key) == ("odd.toml", "(benchmark export)")
    assert e.problem == (
        "model 'odd' has no Meijaard et al. (2007) benchmark counterpart: "
        "model.contact = 'thesis' (the benchmark's front wheel is a knife edge touching the "
        "ground at its lowest point: contact 'disc'); "
        "environment.cv = 0.1 kg/m (the benchmark has no drag); "
        "inertia.I2zz = 0.07 differs from inertia.I2xx = 0.0603 (Table 1's rear wheel has "
        "Izz = Ixx); "
        "inertia.I5zz = 0.2 differs from inertia.I5xx = 0.1405 (Table 1's front wheel has "
        "Izz = Ixx); "
        "geometry: the front wheel cannot touch the ground with the frame upright (no upright "
        "pitch beta)")
    assert e.fix == ("export a model with contact 'disc', cv = 0 and wheels with Izz = Ixx "
                     "(e.g. params.replace(cv=0.0).with_contact('disc'))")


def test_the_export_gives_table_1_back_by_the_reverse_formulas_or_exactly_from_its_table():
    """The model's values of Table 1 go back to Table 1 (to rounding) by the reverse formulas,
    and exactly (the very values) when the model carries a Table 1 that reproduces them; a
    carried table that does not reproduce them is ignored (the reverse formulas answer). Planted (by hand): a carried table returned
    unchecked; the trail's ``- s zA / c`` with its sign flipped."""
    values = model_values(TABLE1)
    back = benchmark_values(values, contact="disc", name="b", source="b.toml")
    for n, v in TABLE1.as_dict().items():
        assert back[n] == pytest.approx(v, rel=1e-12, abs=1e-14), n
    assert benchmark_values(values, contact="disc", name="b", source="b.toml",
                            table=TABLE1) == TABLE1.as_dict()
    other = Table1(w=1.1)
    got = benchmark_values(values, contact="disc", name="b", source="b.toml", table=other)
    assert got["w"] == pytest.approx(1.02, rel=1e-12)
