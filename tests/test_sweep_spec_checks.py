"""The sweep's spec (comparisons/stages/sweep_spec.py), the parts tests/test_sweep_spec_parts.py
leaves open, held to docs/sweep.md and the module's docstrings: which ``--vary`` an unphysical
grid point is blamed on when several are given (the one whose parameter the check names) and the
whole point in the message; a sweep of exactly the 10,000,000 bicycles of docs/sweep.md's
example is not refused for its size; the defaults a spec is made with (8 states, no sample and
no spread for a grid, the installed term engines that model the base's front contact); the base
model's name and triangle-inequality mode carried to every bicycle, a Table 1 (derived) grid on a
base whose measured inertias are allowed to break the triangle inequality included; the drag
dropped whatever its value when the eigenvalues are asked for; the spec's JSON (its fields,
``base`` as [name, value] pairs, ``grids`` as their ``--vary`` texts) and its hash, the SHA-256
of that JSON written canonically (keys sorted, no spaces; a second encoder here); and
``bicycle_parameters`` choosing the grid or the sample. Each test names the planted bugs
(mutmut's survivors of the module's measurement) it was seen failing on.

Hand-computed facts used below (Meijaard et al.'s benchmark in the model's frame axes, from
reference_model/parameters/benchmark.toml): the rear body's I3xx = 7.1782, I3zz = 4.8218, I3yy =
11 kg m^2, so its x-z block has mean 6.0 and half-difference 1.1782. With I3xz = -5.6 the
principal moments are 6 +- hypot(1.1782, 5.6) = 11.723 and 0.277, beside 11: 11.723 > 11 + 0.277,
the triangle inequality is broken about the principal x axis (so the check names I3xx, I3zz and
I3xz, I3xz last), while I3xx I3zz - I3xz^2 = 34.6 - 31.4 > 0 keeps the tensor positive definite.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math

import numpy as np
import pytest

from comparisons.judgments.tolerances import load_tolerances
from comparisons.stages.sweep_spec import (
    MAX_BICYCLES, Grid, SpecError, SweepSpec, bicycle_parameters, derived_values,
    grid_parameters, make_spec, parse_vary, sample_parameters, spec_hash)
from reference_model import load_model
from reference_model.params import PARAMETER_NAMES

ENG = ("pinocchio",)


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark").params


@pytest.fixture(scope="module")
def thesis():
    return load_model("thesis").params


@pytest.fixture(scope="module")
def tolerances():
    return load_tolerances()


# -- the grid point blamed ----------------------------------------------------------------------

def test_the_vary_blamed_is_the_one_whose_parameter_breaks_the_bicycle_not_the_last(bench):
    """``--vary I3xz=-5.6:-3.8:2 --vary m3=80:90:2``: bicycle 0 (I3xz = -5.6, m3 = 80) breaks the
    rear body's triangle inequality (module docstring of this file: the check names I3xx, I3zz,
    I3xz), so the message names the I3xz ``--vary`` (not m3's, the last) and the whole point,
    "I3xz = -5.6, m3 = 80". Planted: the grid picked by ``!=`` (the first grid not named);
    the key split on whitespace or on "XX.XX" (nothing matched: the last grid blamed); the key's
    second or second-to-last part matched instead of its last; the point's pairs joined by
    "XX, XX"."""
    with pytest.raises(SpecError) as err:
        make_spec(bench, varies=["I3xz=-5.6:-3.8:2", "m3=80:90:2"], engines=ENG)
    msg = str(err.value)
    assert msg.startswith("--vary I3xz=-5.6:-3.8:2: at I3xz = -5.6, m3 = 80 the bicycle is not "
                          "physical (inertia.I3xx, inertia.I3zz, inertia.I3xz: "), msg
    assert "triangle inequality" in msg
    assert msg.endswith("; narrow the range")


def test_a_sweep_of_exactly_the_cap_is_not_refused_for_its_size(bench):
    """docs/sweep.md's own example runs 10000000 bicycles: ``--vary I3xz=-5.6:-3.8:10000 --vary
    m3=80:90:1000`` is exactly MAX_BICYCLES = 10^7, so it passes the size check and is refused
    only for its first point (I3xz = -5.6, unphysical: checked first, so no 10^7 bicycles are
    built here). Planted: ``n_bicycles >= MAX_BICYCLES`` (the cap itself refused)."""
    assert MAX_BICYCLES == 10_000 * 1000
    with pytest.raises(SpecError) as err:
        make_spec(bench, varies=["I3xz=-5.6:-3.8:10000", "m3=80:90:1000"], engines=ENG)
    assert str(err.value).startswith("--vary I3xz=-5.6:-3.8:10000: at I3xz = -5.6, m3 = 80 the "
                                     "bicycle is not physical ("), str(err.value)


# -- parsing ------------------------------------------------------------------------------------

@pytest.mark.parametrize("text, message", [
    ("m3=80:80:2", "--vary 'm3=80:80:2': empty range; give LOW < HIGH and N >= 2 points (or "
                   "LOW:LOW:1 for one value)"),
    ("m3==80:90:3", "--vary 'm3==80:90:3': LOW and HIGH must be numbers (SI units)"),
])
def test_two_points_need_two_values_and_the_name_ends_at_the_first_equals_sign(text, message):
    """``m3=80:80:2`` asks for two points of one value: an empty range (the docstring's "LOW <
    HIGH and N >= 2 points"). ``m3==80:90:3``: NAME is what comes before the first "=", m3, a
    known name; the range "=80:90:3" has a LOW that is no number. Planted: the equal-ends check
    only from N > 2 (two equal points accepted); the text split at its last "=" (the name
    "m3=" then called unknown)."""
    with pytest.raises(SpecError) as err:
        parse_vary(text)
    assert str(err.value) == message


# -- defaults and what the spec carries --------------------------------------------------------

def test_a_grid_spec_has_the_documented_defaults(bench, tolerances):
    """make_spec with only a grid (given as a Grid, as a stored spec's grids are) equals the
    SweepSpec written out by hand with docs/sweep.md's defaults: 8 states, checks terms and
    eigen, no sample (0) and no spread (0 %), seed 0; the same spec, the same hash. Planted:
    the states' default 9; a grid spec's sample 1 or spread 1.0; a Grid run through the
    ``--vary`` parser again (it is no text)."""
    grid = Grid("m3", 80.0, 90.0, 3)
    spec = make_spec(bench, varies=[grid], engines=ENG, tolerances=tolerances)
    by_hand = SweepSpec(base=tuple((n, float(getattr(bench, n))) for n in PARAMETER_NAMES),
                        base_name="benchmark", contact="disc", triangle="strict", grids=(grid,),
                        sample=0, spread=0.0, seed=0, engines=ENG,
                        checks=("terms", "eigen"), n_states=8, tolerances=tolerances)
    assert spec == by_hand
    assert spec.n_states == 8 and spec.sample == 0 and spec.spread == 0.0
    assert spec_hash(spec) == spec_hash(by_hand)


def test_a_zero_spread_sample_is_the_base_bicycle(bench):
    """``--sample 2 --spread 0``: every factor is uniform in [1, 1], so each bicycle is the
    base (inertias to rounding: S -> I is its own inverse) and the spec's spread is 0. Planted:
    a spread of 0 stored as 1.0 (``spread or 1.0``)."""
    spec = make_spec(bench, sample=2, spread=0.0, seed=3, engines=ENG, checks=("terms",))
    assert spec.spread == 0.0
    p = sample_parameters(spec, 1)
    for n in PARAMETER_NAMES:
        assert getattr(p, n) == pytest.approx(getattr(bench, n), rel=1e-12, abs=1e-15), n


def test_the_default_engines_are_those_that_model_the_base_contact(thesis):
    """No ``--engines``: every installed engine with terms that models the base's front
    contact (docs/sweep.md). The thesis contact leaves out the engines whose declared contacts
    are the disc alone (Kane's, among the built-ins). Planted: the engines asked for any
    contact (``term_engines(None)``)."""
    from engines import term_engines
    from engines.defaults import installed_facts
    contacts = {f.name: f.contacts for f in installed_facts()}
    expected = tuple(e for e in term_engines() if "thesis" in contacts[e])
    assert set(expected) < set(term_engines())       # some installed engine is disc-only
    spec = make_spec(thesis, varies=["m3=80:90:2"], checks=("terms",))
    assert spec.engines == expected


def test_no_engine_is_one_line_naming_the_option_and_the_contact(bench):
    """``--engines`` empty: one line naming the option, where to look and the base's contact.
    Planted: the message wrapped in "XX"."""
    with pytest.raises(SpecError) as err:
        make_spec(bench, varies=["m3=80:90:2"], engines=())
    assert str(err.value) == ("--engines: give at least one engine (see 'bicycle-xval engines'; "
                              "none installed computes terms on the 'disc' front contact)")


def test_runs_alone_are_refused_on_the_thesis_contact(thesis):
    """``--checks terms,runs`` on the thesis contact: the runs need the linearization (disc
    contact only), refused in one line like eigen. Planted: the "runs" of the check spelled
    "XXrunsXX" or "RUNS" (runs let through, then eigen added behind the check)."""
    with pytest.raises(SpecError) as err:
        make_spec(thesis, varies=["m3=80:90:2"], engines=ENG, checks=("terms", "runs"))
    assert str(err.value) == ("--checks eigen/runs: model 'thesis' has the thesis front contact; "
                              "the linearization is defined for the disc contact (use --model "
                              "thesis-disc or benchmark, or --checks terms)")


def test_eigen_drops_a_drag_of_one_too(bench):
    """With eigen the base is linearized without drag whatever its cv: cv = 1 kg/m becomes 0 in
    the spec. Planted: the drag dropped only when it is not 1.0 (``cv != 1.0``)."""
    spec = make_spec(bench.replace(cv=1.0), varies=["m3=80:90:2"], engines=ENG)
    assert dict(spec.base)["cv"] == 0.0


def test_the_base_name_and_strict_mode_reach_every_bicycle(bench):
    """A trail grid on the benchmark: the base rebuilt from the spec and each bicycle built
    through Table 1 keep the model's name "benchmark" and its strict triangle check; the
    bicycle has the grid's trail. Planted: the name dropped (the spec's base or the Table 1
    rebuild called "custom"); the triangle violation allowed when the base is *not* in "warn"
    mode (``!=``)."""
    spec = make_spec(bench, varies=["trail=0.06:0.1:3"], engines=ENG)
    base = spec.base_parameters()
    assert base.name == "benchmark" and base.triangle == "strict"
    p = grid_parameters(spec, 1)
    assert p.name == "benchmark" and p.triangle == "strict" and p.contact == "disc"
    assert derived_values(p)["trail"] == pytest.approx(0.08, rel=1e-12)


def test_a_warn_mode_base_keeps_its_allowed_triangle_violation_through_table_1(bench):
    """A base whose rear body breaks the triangle inequality (I3yy = 0.5 against I3xx, I3zz
    principal moments 10 and 2, hand-computed: 10 > 0.5 + 2), allowed with triangle "warn":
    its spec's base keeps the mode, and a trail grid through Table 1 builds every point (the
    violation allowed again, one warning kept per violating body) with the grid's trail and
    the base's I3yy. Planted: the spec's base rebuilt in strict mode (the triangle argument
    dropped); the Table 1 rebuild's allow_triangle_violation None, dropped, inverted or compared
    with "XXwarnXX" or "WARN" (each refuses the grid)."""
    warn = bench.replace(I3yy=0.5, triangle="warn")
    assert warn.warnings           # the violation is real, and allowed
    spec = make_spec(warn, varies=["trail=0.06:0.1:3"], engines=ENG, checks=("terms",))
    assert spec.base_parameters().triangle == "warn"
    for k, trail in enumerate((0.06, 0.08, 0.1)):
        p = grid_parameters(spec, k)
        assert p.triangle == "warn" and p.warnings and p.I3yy == 0.5
        assert derived_values(p)["trail"] == pytest.approx(trail, rel=1e-12)


# -- the spec's JSON and hash ------------------------------------------------------------------

def _canonical(value) -> str:
    """Canonical JSON written out here: objects with their keys sorted, no whitespace."""
    if isinstance(value, dict):
        return "{" + ",".join(json.dumps(str(k)) + ":" + _canonical(value[k])
                              for k in sorted(value)) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(_canonical(v) for v in value) + "]"
    return json.dumps(value)


def test_the_spec_json_has_its_fields_with_base_pairs_and_grid_texts(bench, tolerances):
    """as_json (what OUT/spec.json lists): exactly the spec's fields; ``base`` the 30 [name,
    value] pairs in PARAMETER_NAMES order; ``grids`` the ``--vary`` texts; ``tolerances``
    their values. Planted: "base" or "grids" written under "XXbaseXX"/"BASE", "XXgridsXX"/
    "GRIDS" (the raw field left under its own name beside it)."""
    spec = make_spec(bench, varies=["m3=80:90:3", "trail=0.06:0.1:2"], engines=ENG,
                     tolerances=tolerances)
    d = spec.as_json()
    assert set(d) == {f.name for f in dataclasses.fields(SweepSpec)}
    assert d["base"] == [[n, float(getattr(bench, n))] for n in PARAMETER_NAMES]
    assert d["grids"] == ["m3=80.0:90.0:3", "trail=0.06:0.1:2"]
    assert d["tolerances"] == tolerances.as_json()


@pytest.mark.parametrize("kwargs", [
    dict(varies=["m3=80:90:3", "trail=0.06:0.1:2"]),
    dict(sample=4, spread=10.0, seed=5, checks=("terms",)),
])
def test_the_hash_is_16_hex_digits_of_the_sha256_of_the_canonical_json(bench, kwargs):
    """spec_hash = the first 16 hex digits of SHA-256 of the spec's JSON in canonical form
    (keys sorted, "," and ":" with no spaces), encoded here by a second writer. Planted:
    the keys left in field order (sort_keys None, False or dropped); the default separators
    (", " and ": "); separators "XX,XX" or "XX:XX"."""
    spec = make_spec(bench, engines=ENG, **kwargs)
    text = _canonical(spec.as_json())
    assert spec_hash(spec) == hashlib.sha256(text.encode()).hexdigest()[:16]


# -- bicycle_parameters --------------------------------------------------------------------------

def test_bicycle_parameters_is_the_sample_for_a_sample_and_the_grid_for_a_grid(bench):
    """A sample's bicycle 3 is its own draw: R_rear (the first name drawn) is the base's times
    the first uniform in [0.8, 1.2] of SeedSequence([7, 3]) (module docstring), and the rest as
    sample_parameters gives it; a grid's bicycle is its grid point. Planted: the grid taken for
    a sample too (``or True``); the sample called with spec or k None, or one of them
    missing."""
    spec = make_spec(bench, sample=5, spread=20.0, seed=7, engines=ENG, checks=("terms",))
    p = bicycle_parameters(spec, 3)
    u = np.random.default_rng(np.random.SeedSequence([7, 3])).uniform(0.8, 1.2)
    assert p.R_rear == pytest.approx(bench.R_rear * u, rel=1e-15)
    assert p == sample_parameters(spec, 3)
    grid = make_spec(bench, varies=["m3=80:90:3"], engines=ENG)
    q = bicycle_parameters(grid, 2)
    assert q.m3 == 90.0 and q.m2 == bench.m2
    assert math.isclose(q.I3xz, bench.I3xz)
