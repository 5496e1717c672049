"""The sweep's spec (comparisons/stages/sweep_spec.py) held to its docstrings, without a sweep:
every ``--vary`` and option refused in one line naming the option and the fix, the grid's
points (N from LOW to HIGH inclusive, the first ``--vary`` slowest), a derived quantity set
through Meijaard et al.'s Table 1 (trail c = 0.08 m, lam = pi/10, w = 1.02 m for the base), the
sample's factors (every positive length and mass within [1 - P/100, 1 + P/100], zeros and the
environment kept, the wheels axisymmetric, bicycle k the same whatever else is drawn) and the
spec hash (16 hex digits of the canonical JSON). Each test names the bugs it was seen failing on
(planted by hand in the module).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from comparisons.stages.sweep_spec import (
    MAX_BICYCLES, Grid, SpecError, derived_values, grid_parameters, grid_point, make_spec,
    parse_vary, sample_parameters, spec_hash)
from reference_model import load_model

ENG = ("pinocchio",)


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark").params


@pytest.fixture(scope="module")
def thesis():
    return load_model("thesis").params


@pytest.mark.parametrize("text, message", [
    ("trail", "--vary 'trail': write NAME=LOW:HIGH:N, e.g. trail=0:0.2:41"),
    ("=0:1:2", "--vary '=0:1:2': write NAME=LOW:HIGH:N, e.g. trail=0:0.2:41"),
    ("trial=0:1:2", "--vary 'trial=0:1:2': unknown parameter 'trial'; did you mean 'trail'? use "
                    "a model parameter (bicycle-xval export --format json lists them) or trail, "
                    "head_angle, wheelbase"),
    ("qqqqqqqq=0:1:2", "--vary 'qqqqqqqq=0:1:2': unknown parameter 'qqqqqqqq'; use a model "
                       "parameter (bicycle-xval export --format json lists them) or trail, "
                       "head_angle, wheelbase"),
    ("m3=80:90", "--vary 'm3=80:90': the range must be LOW:HIGH:N (three fields), e.g. "
                 "m3=0.05:0.1:11"),
    ("m3=a:90:3", "--vary 'm3=a:90:3': LOW and HIGH must be numbers (SI units)"),
    ("m3=80:90:3.5", "--vary 'm3=80:90:3.5': N must be a whole number of points, e.g. 11"),
    ("m3=80:inf:3", "--vary 'm3=80:inf:3': LOW and HIGH must be finite numbers"),
    ("m3=80:90:0", "--vary 'm3=80:90:0': empty range; give LOW < HIGH and N >= 2 points (or "
                   "LOW:LOW:1 for one value)"),
    ("m3=90:80:3", None), ("m3=80:80:3", None),
])
def test_a_bad_vary_is_one_line_naming_it_and_the_fix(text, message):
    """Each malformed ``--vary`` (docstring of parse_vary, module docstring's grammar) is one
    SpecError quoting the option. Planted: the hint dropped; the LOW = HIGH check with N > 1
    dropped (``m3=80:80:3`` accepted); N = 0 accepted (``n < 0``)."""
    with pytest.raises(SpecError) as err:
        parse_vary(text)
    if message is None:
        assert "empty range" in str(err.value)
    else:
        assert str(err.value) == message


def test_a_grid_is_n_points_from_low_to_high_inclusive_and_prints_back():
    """``m3=80:90:3`` -> 80, 85, 90 (inclusive); ``m3=80:80:1`` -> the one value 80; the text is
    the option again (``Grid.text``). Planted: ``linspace`` without the endpoint; the name
    not trimmed of its spaces."""
    g = parse_vary(" m3 =80:90:3")
    assert g == Grid("m3", 80.0, 90.0, 3)
    assert g.points().tolist() == [80.0, 85.0, 90.0]
    assert parse_vary("m3=80:80:1").points().tolist() == [80.0]
    assert g.text() == "m3=80.0:90.0:3"


def test_the_first_vary_varies_slowest_and_a_derived_quantity_goes_through_table_1(bench):
    """``trail=0.05:0.1:2`` x ``m3=80:90:3``: 6 bicycles, k = 1 is (trail 0.05, m3 85) and k = 3
    is (trail 0.1, m3 80); bicycle 3 has Table 1's trail 0.1 m with the rest of Table 1 kept
    (head angle pi/2 - pi/10, wheel base 1.02 m) and m3 = 80 kg. Planted: the grids' order
    reversed; the derived quantity skipped."""
    spec = make_spec(bench, varies=["trail=0.05:0.1:2", "m3=80:90:3"], engines=ENG)
    assert spec.n_bicycles == 6 and spec.varied == ("trail", "m3")
    assert grid_point(spec, 1) == (("trail", 0.05), ("m3", 85.0))
    assert grid_point(spec, 3) == (("trail", 0.1), ("m3", 80.0))
    p = grid_parameters(spec, 3)
    d = derived_values(p)
    assert d["trail"] == pytest.approx(0.1, rel=1e-12)
    assert d["head_angle"] == pytest.approx(math.pi / 2 - math.pi / 10, rel=1e-12)
    assert d["wheelbase"] == pytest.approx(1.02, rel=1e-12)
    assert p.m3 == 80.0 and p.contact == "disc"


def test_a_head_angle_grid_sets_lambda_as_its_complement(bench):
    """``head_angle=1.2:1.2:1``: lambda = pi/2 - 1.2, so the bicycle's head angle comes back as
    1.2 rad. Planted: the head angle written to lam unconverted."""
    spec = make_spec(bench, varies=["head_angle=1.2:1.2:1"], engines=ENG)
    assert derived_values(grid_parameters(spec, 0))["head_angle"] == pytest.approx(1.2, rel=1e-12)


def test_derived_values_of_a_model_without_a_benchmark_counterpart_are_nan(thesis):
    """The thesis model (thesis contact, drag) has no Table 1: its trail, head angle and wheel
    base are NaN."""
    assert all(math.isnan(v) for v in derived_values(thesis).values())


@pytest.mark.parametrize("kwargs, message", [
    (dict(varies=["m3=80:90:2"], sample=3, spread=1.0),
     "--vary and --sample: give one of them (a grid or a random sample)"),
    (dict(), "nothing to sweep: give --vary NAME=LOW:HIGH:N or --sample N --spread P"),
    (dict(varies=["m3=80:90:2", "m3=1:2:2"]), "--vary m3: given twice; give each parameter one "
                                             "range"),
    (dict(sample=0, spread=1.0), "--sample 0: give at least 1 bicycle"),
    (dict(sample=3), "--sample needs --spread P (per cent around the base, e.g. 20)"),
    (dict(sample=3, spread=math.nan), "--spread nan: must be a non-negative per cent, e.g. 20"),
    (dict(sample=3, spread=100.0), "--spread 100.0: must be below 100 per cent (a factor 1 - "
                                   "P/100 must stay positive)"),
    (dict(varies=["m3=80:90:2"], spread=5.0), "--spread applies to --sample only; a grid's range "
                                              "is its own"),
    (dict(varies=["m3=80:90:2"], seed=-1), "--seed -1: must be a non-negative integer below "
                                           "2**63"),
    (dict(varies=["m3=80:90:2"], seed=2**63), f"--seed {2**63}: must be a non-negative integer "
                                              "below 2**63"),
    (dict(varies=["m3=80:90:2"], n_states=0), "--states 0: must be between 1 and 10000"),
    (dict(varies=["m3=80:90:2"], n_states=10_001), "--states 10001: must be between 1 and 10000"),
    (dict(varies=["m3=80:90:2"], checks=("terms", "wobble")),
     "--checks terms,wobble: choose from terms,eigen,runs"),
    (dict(varies=["m3=80:90:2"], checks=()), "--checks : choose from terms,eigen,runs"),
    (dict(varies=["m3=80:90:10000", "m2=1:2:1001"]),
     f"--vary: 10010000 bicycles; at most {MAX_BICYCLES} per sweep (use fewer points)"),
])
def test_a_bad_option_is_one_line_naming_it(bench, kwargs, message):
    """Each refused option combination (make_spec) is one SpecError naming the option and the
    fix. Planted: ``sample < 0`` (0 bicycles accepted); ``spread > 100``; ``seed <= 2**63``;
    ``n_states <= 10_001``; the empty checks accepted."""
    kwargs = {"engines": ENG, **kwargs}
    with pytest.raises(SpecError) as err:
        make_spec(bench, **kwargs)
    assert str(err.value) == message


def test_the_limits_of_the_options_are_accepted(bench):
    """The edges the messages allow are allowed: spread 0 and 99.9, seed 0 and 2**63 - 1,
    1 and 10000 states, a single bicycle. Planted: ``spread >= 99`` refused; ``seed < 2**63 - 1``;
    ``1 < n_states`` (one state refused)."""
    make_spec(bench, sample=1, spread=0.0, seed=2**63 - 1, n_states=1, engines=ENG)
    make_spec(bench, sample=1, spread=99.9, seed=0, n_states=10_000, engines=ENG,
              checks=("terms",))


def test_the_thesis_contact_allows_terms_only_and_no_derived_grid(thesis):
    """The thesis front contact: eigenvalues and runs are refused naming the model and the way
    out; a trail grid is refused (no Table 1 counterpart) naming the reason; terms on the
    model's own parameters are fine. Planted: the eigen check not refused on the thesis
    contact; the derived check skipped."""
    with pytest.raises(SpecError) as err:
        make_spec(thesis, varies=["m3=80:90:2"], engines=ENG, checks=("eigen",))
    assert str(err.value) == ("--checks eigen/runs: model 'thesis' has the thesis front contact; "
                              "the linearization is defined for the disc contact (use --model "
                              "thesis-disc or benchmark, or --checks terms)")
    with pytest.raises(SpecError) as err:
        make_spec(thesis, varies=["trail=0.05:0.1:2"], engines=ENG, checks=("terms",))
    assert str(err.value).startswith("--vary trail: the base model has no benchmark "
                                     "counterpart (")
    assert str(err.value).endswith("); vary the model's own parameters instead")
    spec = make_spec(thesis, varies=["m3=80:90:2"], engines=ENG, checks=("terms",))
    assert spec.checks == ("terms",) and dict(spec.base)["cv"] == thesis.cv


def test_runs_bring_the_eigenvalues_and_eigen_drops_the_drag(bench):
    """``--checks terms,runs`` becomes terms, eigen, runs (the runs need the speeds), in CHECKS
    order; with eigen a base with drag is linearized without it (cv = 0 in the spec). Planted:
    runs without eigen; the drag kept."""
    spec = make_spec(bench.replace(cv=0.5), varies=["m3=80:90:2"], engines=ENG,
                     checks=("runs", "terms"))
    assert spec.checks == ("terms", "eigen", "runs")
    assert dict(spec.base)["cv"] == 0.0


def test_an_unphysical_grid_point_names_the_vary_and_the_point(bench):
    """I3yy from 0.5 to 20 kg m^2 in 5 points: at 0.5 the rear body's principal moments break
    the triangle inequality (I3yy small against I3xx + I3zz = 12 of Table 1's frame); refused
    naming the ``--vary``, the point and "narrow the range". Planted: the point not named."""
    with pytest.raises(SpecError) as err:
        make_spec(bench, varies=["I3yy=0.5:20:5"], engines=ENG)
    msg = str(err.value)
    assert msg.startswith("--vary I3yy=0.5:20.0:5: at I3yy = 0.5 the bicycle is not physical (")
    assert msg.endswith("; narrow the range")


def test_sample_factors_stay_in_the_spread_and_keep_zeros_environment_and_wheels(bench):
    """20 % spread: every positive length and mass of a sampled bicycle is the base's times a
    factor in [0.8, 1.2], z5 = 0 stays 0, g and cv are the base's, each wheel keeps Izz = Ixx;
    bicycle 3 of seed 7 is the same in another spec with more bicycles (its own SeedSequence
    [7, 3]), another seed gives another bicycle. Planted: factors 1 +- 2f; the environment
    scaled; the wheels' d_z drawn on its own; the stream seeded by the seed alone."""
    spec = make_spec(bench, sample=5, spread=20.0, seed=7, engines=ENG, checks=("terms",))
    base = dict(spec.base)
    for k in range(5):
        p = sample_parameters(spec, k)
        for n in ("R_rear", "R_front", "x3", "xa", "x5", "m2", "m3", "m4", "m5"):
            assert 0.8 * abs(base[n]) <= abs(getattr(p, n)) <= 1.2 * abs(base[n]), n
        assert p.z5 == 0.0 and p.g == base["g"] and p.cv == base["cv"]
        assert p.I2zz == pytest.approx(p.I2xx, rel=1e-14)
        assert p.I5zz == pytest.approx(p.I5xx, rel=1e-14)
    bigger = make_spec(bench, sample=50, spread=20.0, seed=7, engines=ENG, checks=("terms",))
    assert sample_parameters(bigger, 3).m3 == sample_parameters(spec, 3).m3
    other = make_spec(bench, sample=5, spread=20.0, seed=8, engines=ENG, checks=("terms",))
    assert sample_parameters(other, 3).m3 != sample_parameters(spec, 3).m3
    assert sample_parameters(spec, 2).m3 != sample_parameters(spec, 3).m3


def test_sample_second_moments_move_by_at_most_the_spread(bench):
    """S = tr(I)/2 1 - I, the second-moment matrix, is scaled congruently by d_i^2 in [0.9,
    1.1] at 10 %: each diagonal second moment of the rear body moves by at most 10 % and the
    y axis stays principal (no xy, yz). Planted: I rebuilt as tr(S) 1 + S."""
    spec = make_spec(bench, sample=5, spread=10.0, seed=1, engines=ENG, checks=("terms",))

    def second_moments(p):
        I = np.array([[p.I3xx, 0, p.I3xz], [0, p.I3yy, 0], [p.I3xz, 0, p.I3zz]])
        return np.diag(np.trace(I) / 2 * np.eye(3) - I)

    s0 = second_moments(spec.base_parameters())
    for k in range(5):
        ratio = second_moments(sample_parameters(spec, k)) / s0
        assert np.all((ratio >= 0.9 - 1e-12) & (ratio <= 1.1 + 1e-12)), ratio


def test_the_spec_hash_is_16_hex_digits_of_the_spec_and_changes_with_it(bench):
    """Two equal specs hash alike; 16 lowercase hex digits; a different seed or grid changes it.
    A sample's varied names are the non-zero design parameters (no g, cv, z5). Planted: the
    hash cut to 8 digits; g counted as varied."""
    a = make_spec(bench, sample=3, spread=5.0, seed=1, engines=ENG, checks=("terms",))
    b = make_spec(bench, sample=3, spread=5.0, seed=1, engines=ENG, checks=("terms",))
    h = spec_hash(a)
    assert h == spec_hash(b) and len(h) == 16 and int(h, 16) >= 0 and h == h.lower()
    c = make_spec(bench, sample=3, spread=5.0, seed=2, engines=ENG, checks=("terms",))
    assert spec_hash(c) != h
    assert "g" not in a.varied and "cv" not in a.varied and "z5" not in a.varied
    assert "m3" in a.varied and a.n_bicycles == 3
