"""The eigenvalue table, curves and critical speeds (comparisons/judgments/eigenvalues.py)
against their docstrings: float speeds whatever the caller passes, ``stable`` only where every
real part is < 0 (a marginal mode is not stable), and the critical speeds looked for within
[max(0, min speeds), max speeds].

Expected values: the published speeds of Meijaard et al. 2007 (comparisons/judgments/
published.py) carried to another gravity by an exact scaling law written out below, and a
hand-built spectrum for the ``stable`` column. ~0.3 s (four critical-speed searches)."""

import warnings

import numpy as np
import pytest

from comparisons.judgments.eigenvalues import critical_speeds, eigenvalue_curves, eigenvalue_table
from comparisons.judgments.published import MEIJAARD_CAPSIZE_SPEED, MEIJAARD_WEAVE_SPEED
from reference_model import load_model
from reference_model.params import ParameterWarning

# The linearized equations M q'' + v C1 q' + (g K0 + v^2 K2) q = 0 with g -> g/k, v -> v/sqrt(k)
# and lambda -> lambda/sqrt(k) are the original ones divided by k: every eigenvalue scales by
# 1/sqrt(k) and both critical speeds by 1/sqrt(k). k = 100 brings them below 1 m/s.
K = 100.0


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


@pytest.fixture(scope="module")
def low_gravity(bench):
    with warnings.catch_warnings():      # g = 0.0981 m/s^2 is unusual on purpose
        warnings.simplefilter("ignore", ParameterWarning)
        return bench.with_params(bench.params.replace(g=bench.params.g / K))


def test_critical_speeds_below_1_m_s_are_found_from_zero(low_gravity):
    weave, capsize = critical_speeds(low_gravity, [0.0, 0.9])
    # 1e-9 m/s: the published speeds have 14 decimals and brentq's xtol is 1e-14; the
    # scaling is exact, so only the two searches' round-off separates them
    assert weave == pytest.approx(MEIJAARD_WEAVE_SPEED / np.sqrt(K), abs=1e-9)
    assert capsize == pytest.approx(MEIJAARD_CAPSIZE_SPEED / np.sqrt(K), abs=1e-9)
    # negative speeds in the grid: the search still starts at 0 m/s
    assert critical_speeds(low_gravity, [-2.0, 0.9]) == (weave, capsize)


def test_a_grid_of_one_speed_has_no_critical_speeds(bench):
    assert critical_speeds(bench, [5.0]) == (None, None)
    assert critical_speeds(bench, [5.0, 5.0]) == (None, None)
    assert critical_speeds(bench, [-3.0, 0.0]) == (None, None)


def test_the_curves_carry_the_critical_speeds_and_float_speeds(bench):
    c = eigenvalue_curves(bench, [0, 5, 10])          # integer speeds, as a user types them
    assert c["v"].dtype == np.float64 and c["v"].tolist() == [0.0, 5.0, 10.0]
    assert c["re"].shape == c["im"].shape == (3, 4) and c["model"] == "benchmark"
    # same 1e-9 m/s as above (no scaling here: the published speeds themselves)
    assert c["weave"] == pytest.approx(MEIJAARD_WEAVE_SPEED, abs=1e-9)
    assert c["capsize"] == pytest.approx(MEIJAARD_CAPSIZE_SPEED, abs=1e-9)


def test_the_table_has_float_speeds(bench):
    frame = eigenvalue_table(bench, [0, 5])
    assert frame["v"].dtype == np.float64
    assert list(frame.columns) == ["v", "re_1", "im_1", "re_2", "im_2", "re_3", "im_3",
                                   "re_4", "im_4", "stable"]
    # Table 2: unstable at 0 m/s (+5.53 /s), self-stable at 5 m/s (every real part < 0)
    assert frame["stable"].tolist() == [False, True]


def test_a_marginal_mode_is_not_stable(monkeypatch, bench):
    """A spectrum built by hand: a purely imaginary pair (real part exactly 0) and two decaying
    roots is marginally stable, not stable; with the pair at -0.1 it is stable."""
    import reference_model.linearize as linearize

    marginal = np.array([2j, -2j, -1.0, -3.0])
    decaying = np.array([-0.1 + 2j, -0.1 - 2j, -1.0, -3.0])
    monkeypatch.setattr(linearize, "eigenvalues",
                        lambda model, v: np.array([marginal, decaying][:len(v)]))
    assert eigenvalue_table(bench, [1.0, 2.0])["stable"].tolist() == [False, True]
