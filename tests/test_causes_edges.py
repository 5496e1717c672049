"""The coordinate-swap causes' edges (comparisons/judgments/causes.py), issue 24: how many
pairs are tried, which effects count, what the swapped states carry, and the 'every term'
cause. Made-up terms with effects set by hand, so the expected causes are counted here, not
read from the code. Planted bugs each test was seen failing on are named in it."""

from itertools import combinations

import numpy as np
import pytest

from comparisons.judgments.causes import coordinate_swap_causes
from comparisons.judgments.terms import random_states
from reference_model import COORDINATES

STATES = random_states(3, seed=5)


def test_every_pair_is_tried_once():
    """A term that sees every coordinate with its own weight: each of the 28 pairs of the 8
    coordinates is a cause once, named a,b in coordinate order. Planted: j from 0 (each pair
    twice, once the other way round), j from i - 1."""
    w = np.arange(1.0, 9.0)

    def terms(model, s):
        return {"T": s.q @ w}
    causes = coordinate_swap_causes(terms, None, STATES, terms(None, STATES), ["T"])
    expected = [f"swap:T:{a},{b}" for a, b in combinations(COORDINATES, 2)]
    assert [c.id for c in causes] == expected


def test_the_swapped_states_keep_the_accelerations_and_torques():
    """A term of q, ddq and T (as the inverse dynamics is): swapping two coordinates moves
    the q part only. Planted: the swapped states built without ddq or T."""
    def terms(model, s):
        return {"ID": s.q[:, 0] + 10 * s.ddq[:, 0] + 100 * s.T[:, 0]}
    ref = terms(None, STATES)
    (c,) = [c for c in coordinate_swap_causes(terms, None, STATES, ref, ["ID"])
            if c.id == "swap:ID:xc,yc"]
    np.testing.assert_allclose(c.effects[("ID", None)], STATES.q[:, 1] - STATES.q[:, 0],
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("scale, size, counted", [
    (0.0, 1e-12, False),        # exactly at the bound 1e-12 max(1, |ref|): not an effect
    (0.0, 1.5e-12, True),       # just above it (the bound is 1e-12 for |ref| <= 1)
    (1e3, 5e-10, False),        # |ref| = 1e3: the bound is 1e-9
    (1e3, 2e-9, True),
])
def test_an_effect_counts_only_above_round_off_of_the_term(scale, size, counted):
    """The term T = scale + size q_xc-dependence set so that swapping xc and yc changes it by
    exactly ``size`` at one state. Planted: >= for > (the bound itself counted), the bound
    divided by |ref| instead of multiplied, max(2, |ref|)."""
    base = np.zeros((3, 8))
    q = base.copy()
    q[0, 0] = 1.0                                  # xc = 1, yc = 0 at the first state only

    class S:
        def __init__(self, q, dq, ddq, T):
            self.q, self.dq, self.ddq, self.T = q, dq, ddq, T
    states = S(q, base, base, np.zeros((3, 3)))

    def terms(model, s):
        return {"T": np.full(3, scale) + np.where(s.q[:, 1] == 1.0, size, 0.0)}
    ref = terms(None, states)
    ids = [c.id for c in coordinate_swap_causes(terms, None, states, ref, ["T"])]
    assert ("swap:T:xc,yc" in ids) is counted, ids


def test_a_term_without_the_pair_does_not_stop_the_others():
    """Terms A (blind to every swap) then B: B's causes are still found, and the 'every term'
    cause of a pair two terms see holds both effects as they are, taken whole (fixed).
    Planted: break for continue, the effect stored as None, the cause not fixed."""
    def terms(model, s):
        return {"A": np.zeros(3), "B": s.q[:, 0] - s.q[:, 2], "C": 3 * s.q[:, 0]}
    ref = terms(None, STATES)
    causes = {c.id: c for c in coordinate_swap_causes(terms, None, STATES, ref, ["A", "B", "C"])}
    assert "swap:B:xc,phi" in causes and not any(i.startswith("swap:A:") for i in causes)
    every = causes["swap:all:xc,phi"]
    assert every.fixed is True and every.kind == "structural"
    for t in ("B", "C"):
        np.testing.assert_array_equal(every.effects[(t, None)],
                                      causes[f"swap:{t}:xc,phi"].effects[(t, None)])


def test_each_parameter_reaching_several_terms_is_a_cause_per_term_whatever_comes_before():
    """Every parameter but the last reaches one term (or is missing): only the last gives
    causes, one per term it reaches, each evaluating its own term alone at a changed value.
    Planted: break for either continue (the parameters after the first skipped one lost).
    (The evaluator is given its term twice, as the list and as 'only': dropping either
    leaves the same evaluation.)"""
    from comparisons.judgments.causes import parameter_term_causes
    from comparisons.judgments.term_checks import model_terms
    from reference_model import load_model
    from reference_model.params import PARAMETER_NAMES
    thesis = load_model("thesis")
    states = random_states(2, seed=3)
    one, zero = {"M": np.ones((2, 8, 8))}, np.zeros((2, 8, 8))
    effects = {n: dict(one) for n in PARAMETER_NAMES[1:-1]}       # the first one missing
    last = PARAMETER_NAMES[-1]
    effects[last] = {"M": np.ones((2, 8, 8)), "Qgrav": np.ones((2, 8)), "D": zero[:, :5]}
    units = {n: "u" for n in PARAMETER_NAMES}
    causes = parameter_term_causes(effects, thesis, units, lambda n: None, states, model_terms)
    assert [c.id for c in causes] == [f"{last}@M", f"{last}@Qgrav"]
    value = float(getattr(thesis.params, last))
    moved = causes[0].evaluate(0.1 * abs(value) + 0.01)
    assert set(moved) == {("M", None)}
    assert causes[0].value == value and causes[0].unit == "u"


def test_the_rider_torque_causes_are_every_mistake_once_and_taken_whole():
    """For each of the three torques: its sign, and each of the three bodies it does not act
    on (Mdir acts on the fork, Mped on the rear wheel, Mvue on the frame: thesis section 2);
    then the three swaps of two columns. Every one is structural and taken at full size.
    Planted: a body tried twice and the rear wheel never, a flag not True, a swap's label
    lost."""
    from comparisons.judgments.causes import torque_causes
    q = random_states(2, seed=4).q
    S = np.random.default_rng(0).normal(size=(2, 8, 3))
    causes = torque_causes(S, q)
    on = {"Mdir": 4, "Mped": 2, "Mvue": 3}
    expected = []
    for name, body in on.items():
        expected.append(f"sign:S[{name}]")
        expected += [f"body:S[{name}]->{b}" for b in (2, 3, 4, 5) if b != body]
    expected += ["swap:S[Mdir,Mped]", "swap:S[Mdir,Mvue]", "swap:S[Mped,Mvue]"]
    assert [c.id for c in causes] == expected
    assert all(c.fixed is True and c.kind == "structural" for c in causes)
    swap = causes[-1]
    assert swap.label == "rider torques Mped and Mvue swapped (columns of S)"


def test_table1_units_are_the_descriptions_last_part():
    """Units as Table 1 gives them, also where the description holds a comma of its own
    ('rear body + rider CoM, forward, m'). Planted: the first comma taken, a split count of
    2, the text before the unit."""
    from comparisons.judgments.causes import table1_causes
    from comparisons.judgments.term_checks import model_terms
    from reference_model import load_model
    bench = load_model("benchmark")
    units = {c.id: c.unit for c in table1_causes(bench, random_states(1, seed=1), model_terms,
                                                 ["M"])}
    assert {k: units[f"table1:{k}"] for k in ("w", "lam", "g", "mR", "IRxx", "xB", "zH")} == \
        {"w": "m", "lam": "rad", "g": "m/s^2", "mR": "kg", "IRxx": "kg m^2", "xB": "m", "zH": "m"}


def test_a_model_without_its_own_table1_gets_one_by_conversion():
    """The benchmark bicycle with its stored Table 1 taken away (as a bicycle built from
    model parameters has none): Table 1 is recovered by converting the parameters back, and
    its wheelbase is Meijaard's 1.02 m (Table 1, to round-off). Planted: the conversion's
    input dropped."""
    import dataclasses
    from comparisons.judgments.causes import table1_of
    from reference_model import load_model
    bench = load_model("benchmark")
    bare = bench.with_params(dataclasses.replace(bench.params, benchmark=None))
    assert bare.params.benchmark is None
    table = table1_of(bare)
    assert table is not None and abs(table.as_dict()["w"] - 1.02) < 1e-12


# -- Table 1 inputs whose perturbation is invalid on one side ----------------------------------

def _table1_bike(**change):
    """The benchmark bicycle built from its Table 1 with ``change`` (the triangle inequality
    not insisted on, as a measured bicycle near a bound may need)."""
    from reference_model import load_model
    from reference_model.parameters import Parameters
    bench = load_model("benchmark")
    values = {**bench.params.benchmark.as_dict(), **change}
    return bench.with_params(Parameters.from_benchmark(values, name="edge",
                                                       allow_triangle_violation=True)), values


def _terms_at(values, states):
    """M of the bicycle of Table 1 ``values``, built here (not through the causes)."""
    from comparisons.judgments.term_checks import model_terms
    from reference_model import load_model
    from reference_model.parameters import Parameters
    bench = load_model("benchmark")
    m = bench.with_params(Parameters.from_benchmark(values, name="x", allow_triangle_violation=True))
    return model_terms(m, states)["M"]


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_an_input_at_the_edge_of_validity_gets_a_one_sided_difference(side):
    """IBxz within 3e-7 of sqrt(IBxx IBzz) (the rear body's tensor barely positive definite),
    positive or negative: one side of the 1e-6 relative perturbation is not a valid bicycle,
    so the derivative is the one-sided difference over h alone. M is linear in IBxz, so the
    expected derivative is the difference over a step 1000 times larger taken away from the
    bound, computed here (exact to round-off). Planted: the width 2h kept on one side (the
    derivative halved), the missing side's terms taken from the other side, the input
    skipped when one side is missing (`or` for `and`), the model built with the strict
    triangle (both sides refused)."""
    from comparisons.judgments.causes import table1_causes
    from comparisons.judgments.term_checks import model_terms
    import math
    from reference_model import load_model
    t = load_model("benchmark").params.benchmark.as_dict()
    edge = side * math.sqrt(t["IBxx"] * t["IBzz"]) * (1 - 3e-7)
    bike, values = _table1_bike(IBxz=edge)
    states = random_states(2, seed=3)
    (c,) = [c for c in table1_causes(bike, states, model_terms, ["M"]) if c.id == "table1:IBxz"]
    d = 1e-3 * abs(edge)
    expected = (_terms_at(values, states)
                - _terms_at({**values, "IBxz": edge - side * d}, states)) / (side * d)
    got = c.effects[("M", None)]
    assert np.abs(expected).max() > 0.1
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-6 * np.abs(expected).max())


def test_a_zero_input_is_perturbed_by_an_absolute_step():
    """IHxz = 0 (a handlebar with a symmetric tensor): the step is the absolute 1e-7 kg m^2,
    which keeps IHxx IHzz - IHxz^2 > 0 on both sides, and the derivative of M (linear in
    IHxz) is the one a larger step gives, computed here. Planted: an absolute step of ~1 kg
    m^2 (both sides refused: the cause missing), a relative step at zero (no step: 0/0)."""
    from comparisons.judgments.causes import table1_causes
    from comparisons.judgments.term_checks import model_terms
    bike, values = _table1_bike(IHxz=0.0)
    states = random_states(2, seed=4)
    (c,) = [c for c in table1_causes(bike, states, model_terms, ["M"]) if c.id == "table1:IHxz"]
    d = 1e-4
    expected = (_terms_at({**values, "IHxz": d}, states) - _terms_at({**values, "IHxz": -d}, states)) / (2 * d)
    assert np.abs(expected).max() > 0.1 and c.value == 0.0
    np.testing.assert_allclose(c.effects[("M", None)], expected, rtol=0,
                               atol=1e-6 * np.abs(expected).max())


def test_a_nonlinear_input_gets_a_small_central_difference():
    """The steer axis tilt lam enters M through sines and cosines: a step of the input's own
    size (instead of 1e-6 of it) would give a secant far from the derivative. Expected: a
    central difference with the step 1e-5 rad computed here (its error ~(1e-5)^2 of M's third
    derivative, below 1e-8 of the derivative's size). Planted: the relative step 1.000001
    (mutmut's +1 on 1e-6)."""
    from comparisons.judgments.causes import table1_causes
    from comparisons.judgments.term_checks import model_terms
    bike, values = _table1_bike()
    states = random_states(2, seed=6)
    (c,) = [c for c in table1_causes(bike, states, model_terms, ["M"]) if c.id == "table1:lam"]
    d = 1e-5
    lam = values["lam"]
    expected = (_terms_at({**values, "lam": lam + d}, states)
                - _terms_at({**values, "lam": lam - d}, states)) / (2 * d)
    np.testing.assert_allclose(c.effects[("M", None)], expected, rtol=0,
                               atol=1e-6 * np.abs(expected).max())


def test_the_slips_and_steps_raise_no_parameter_warning():
    """A slip's values are unusual by design (a trail of the other sign, lam read as degrees),
    and diagnose prints its own findings: the ParameterWarnings such candidates raise are not
    the user's, and must not reach them (on a bicycle on the Moon, g = 1.62 m/s^2, every
    candidate warns). Run with ParameterWarning an error. Planted: either
    warning filter removed (table1's `built`, `changed_terms`)."""
    import warnings
    from comparisons.judgments.causes import changed_terms, table1_causes
    from comparisons.judgments.term_checks import model_terms
    from reference_model import load_model
    from reference_model.parameters import ParameterWarning
    bench = load_model("benchmark")
    with warnings.catch_warnings():       # the user's own bicycle warns once, when loaded
        warnings.simplefilter("ignore", ParameterWarning)
        moon, _ = _table1_bike(g=1.62)    # every candidate built from it has the unusual g
    states = random_states(1, seed=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ParameterWarning)
        causes = table1_causes(moon, states, model_terms, ["M"])
        assert {"table1:g", "table1:lam-deg2rad"} <= {c.id for c in causes}
        # g = 1.62 m/s^2 (the Moon's) is valid but unusual: a warning if not filtered
        assert changed_terms(bench, states, model_terms, ["M"], g=1.62) is not None
