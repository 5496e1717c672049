"""Parts of diagnose's cause localization (comparisons/judgments/causes.py), issue 24: the
wording of a cause in one copy of a term and of a Table 1 input, the rotations in double
precision, candidates that break the triangle inequality (still tried), the warning filter
(a ParameterWarning of a candidate silenced, any other warning kept), the finite-difference
step of a Table 1 input and an input that cannot move at all. Expected values come from
linearity (M is linear in each mass and moment of inertia), orthonormality of rotations,
Table 1's own descriptions and the validity rules of a Table 1. Planted bugs each test was
seen failing on are named in it."""

import warnings

import numpy as np
import pytest

from comparisons.judgments.causes import (body_angular_jacobians, changed_terms, table1_causes,
                                          term_sign_causes)
from comparisons.judgments.term_checks import model_terms
from comparisons.judgments.terms import random_states
from reference_model import load_model
from reference_model.benchmark import BENCHMARK_NAMES
from reference_model.parameters import Parameters, ParameterWarning

STATES = random_states(2, seed=3)


@pytest.fixture(scope="module")
def bench():
    return load_model("benchmark")


def _cause(causes, cid):
    (c,) = [c for c in causes if c.id == cid]
    return c


# -- wording ------------------------------------------------------------------------------------

def test_a_mistake_in_the_engines_own_copy_is_named_by_its_method_or_its_term():
    """M comes from the engine's mass matrix and a second time from inverse_dynamics ('ID');
    a mistake in the first copy is 'in the engine's own M' (no method name is known for M,
    so the term names it), one in Qgrav's 'in the engine's own gravity()'. Planted: the
    fallback to the term's name dropped (the label read 'in the engine's own None')."""
    ref = {"M": np.full((2, 8, 8), 5.0), "Qgrav": np.full((2, 8), 3.0)}
    got = {c.id: c.label for c in term_sign_causes(ref, {"M": ("", "ID"),
                                                         "Qgrav": ("", "F")})}
    assert got["sign:M[own]"] == "sign of M flipped in the engine's own M"
    assert got["missing:M[own]"] == "M missing in the engine's own M"
    assert got["sign:M[ID]"] == "sign of M flipped in inverse_dynamics"
    assert got["missing:Qgrav[own]"] == "Qgrav missing in the engine's own gravity()"


def test_a_table1_inputs_label_is_its_descriptions_short_form(bench):
    """The label names the input and the start of Table 1's description, before the first
    comma and without a parenthesis ('steer axis tilt from vertical (pi/2 - head angle),
    rad' -> 'steer axis tilt from vertical'). Planted: the parenthesis kept (split on a
    string the descriptions do not hold)."""
    labels = {c.id: c.label for c in table1_causes(bench, STATES, model_terms, ["M"])}
    assert labels["table1:lam"] == "Table 1's lam (steer axis tilt from vertical)"
    assert labels["table1:IRxx"] == "Table 1's IRxx (rear wheel diametral inertia)"
    assert labels["table1:IBxz"] == "Table 1's IBxz (rear body inertia xz)"
    assert labels["table1:xB"] == "Table 1's xB (rear body + rider CoM)"


# -- rotations ----------------------------------------------------------------------------------

def test_rotations_are_computed_in_double_precision_from_single_precision_states():
    """States stored in float32 (a compact file): the angles are widened before their sines
    are taken, so every body's rotation matrix is orthonormal to double precision and equals
    the one of the same angles given as float64. Planted: the conversion to float dropped
    (sines in single precision: orthonormal to ~1e-7 only)."""
    q32 = STATES.q.astype(np.float32)
    A, J = body_angular_jacobians(q32)
    A64, J64 = body_angular_jacobians(q32.astype(np.float64))
    for b in (2, 3, 4, 5):
        eye = np.broadcast_to(np.eye(3), A[b].shape)
        np.testing.assert_allclose(A[b] @ np.swapaxes(A[b], 1, 2), eye, rtol=0, atol=1e-14)
        np.testing.assert_allclose(A[b], A64[b], rtol=0, atol=1e-15)
        np.testing.assert_allclose(J[b], J64[b], rtol=0, atol=1e-15)


# -- the triangle inequality is not insisted on -------------------------------------------------

def test_a_parameter_candidate_breaking_the_triangle_inequality_is_still_tried(thesis):
    """The thesis frame's principal moments are (20.41, 21.77, 3.01) kg m^2: I3yy + 2 breaks
    I1 + I3 >= I2, yet the thesis model is strict. The candidate is evaluated all the same,
    and M is linear in I3yy: +3 moves it three times as far as +1 (a valid value). Planted:
    the copy built in the model's own (strict) mode, the candidate refused (None)."""
    v = thesis.params.I3yy
    one = changed_terms(thesis, STATES, model_terms, ["M", "Qgrav"], I3yy=v + 1.0)
    three = changed_terms(thesis, STATES, model_terms, ["M", "Qgrav"], I3yy=v + 3.0)
    assert three is not None
    assert np.abs(one[("M", None)]).max() > 0.1
    np.testing.assert_allclose(three[("M", None)], 3.0 * one[("M", None)], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(three[("Qgrav", None)], 0.0)    # gravity has no inertia


def test_a_table1_candidate_breaking_the_triangle_inequality_is_still_tried(bench):
    """The benchmark's rear body has principal moments (10, 11, 2) kg m^2 (Table 1: IBxx 9.2,
    IByy 11, IBzz 2.8, IBxz 2.4): IByy + 2 = 13 > 10 + 2, and the benchmark model is strict.
    The fit's evaluation at that size is still a change of the terms, and M is linear in
    IByy: four times the change at +0.5 (valid) and twice the derivative. Planted: the
    rebuilt model keeping the strict triangle check (the evaluation None)."""
    c = _cause(table1_causes(bench, STATES, model_terms, ["M"]), "table1:IByy")
    big, small = c.evaluate(2.0), c.evaluate(0.5)
    assert big is not None
    dM = c.effects[("M", None)]
    assert np.abs(dM).max() > 0.1
    np.testing.assert_allclose(big[("M", None)], 4.0 * small[("M", None)], rtol=0, atol=1e-9)
    np.testing.assert_allclose(big[("M", None)], 2.0 * dM, rtol=0, atol=1e-6)


# -- the warning filter: a candidate's ParameterWarning silenced, nothing else -------------------

@pytest.fixture
def replace_warns(monkeypatch):
    """Parameters.replace warning of something that is not a parameter's value (a
    RuntimeWarning, as a numerical problem in a conversion would), then doing its job."""
    original = Parameters.replace

    def replace(self, **changes):
        warnings.warn("a numerical problem", RuntimeWarning)
        return original(self, **changes)
    monkeypatch.setattr(Parameters, "replace", replace)


def _moon():
    """The benchmark bicycle on the Moon (g = 1.62 m/s^2, unusual: every candidate built
    from it raises a ParameterWarning)."""
    bench = load_model("benchmark")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ParameterWarning)
        return bench.with_params(Parameters.from_benchmark(
            {**bench.params.benchmark.as_dict(), "g": 1.62}, name="moon"))


def test_changed_terms_silences_the_parameter_warning_only(replace_warns):
    """A candidate on the Moon's bicycle: its ParameterWarning (g unusual) does not reach the
    caller, a warning of another kind raised while the candidate is built does. Planted: the
    filter ignoring every warning (its category dropped)."""
    moon = _moon()
    with pytest.warns(RuntimeWarning, match="a numerical problem") as record:
        got = changed_terms(moon, STATES, model_terms, ["M"], m3=90.0)
    assert got is not None
    assert not [w for w in record if issubclass(w.category, ParameterWarning)]


def test_table1_causes_silence_the_parameter_warning_only(replace_warns):
    """The same for the Table 1 inputs and slips on the Moon's bicycle: every candidate has
    the unusual g, none of their ParameterWarnings reaches the caller, the other warning
    does. Planted: the filter in `built` ignoring every warning (its category dropped)."""
    moon = _moon()
    with pytest.warns(RuntimeWarning, match="a numerical problem") as record:
        causes = table1_causes(moon, STATES, model_terms, ["M"])
    assert len(causes) == 26 + 4
    assert not [w for w in record if issubclass(w.category, ParameterWarning)]


# -- the step of a Table 1 input ----------------------------------------------------------------

def test_a_heavy_input_is_differentiated_with_a_step_relative_to_it(bench):
    """The rear body's mass, 85 kg: M is linear in it, so the difference over +-10 % is its
    exact derivative (computed here). The step 1e-6 mB keeps the round-off of M (~1e-16 |M|)
    over the step near 1e-10 of the derivative; an absolute step of 1e-7 kg, or one of 1e-6 /
    mB, leaves ~1e-7 of it. Planted: the step 1e-7 whatever the value, the step 1e-6 / |value|."""
    c = _cause(table1_causes(bench, STATES, model_terms, ["M"]), "table1:mB")
    table = bench.params.benchmark.as_dict()
    mB = table["mB"]
    assert (c.value, c.unit) == (85.0, "kg")

    def M(m):
        params = Parameters.from_benchmark({**table, "mB": m})
        return model_terms(bench.with_params(params), STATES)["M"]
    expected = (M(1.1 * mB) - M(0.9 * mB)) / (0.2 * mB)
    assert np.abs(expected).max() > 0.1
    np.testing.assert_allclose(c.effects[("M", None)], expected, rtol=0,
                               atol=2e-9 * np.abs(expected).max())


def test_an_input_that_cannot_move_either_way_is_skipped_and_the_scan_goes_on():
    """A rear body lumped near a point (moments 1e-8 kg m^2, IBxz = 0): IBxz cannot move by
    its step 1e-7 either way (IBxz^2 = 1e-14 > IBxx IBzz = 1e-16, no longer positive definite),
    so it is no candidate; every input after it (the front assembly, the front wheel) still is,
    and so are the four slips. Planted: break for continue (the inputs after IBxz lost)."""
    bench = load_model("benchmark")
    point = {**bench.params.benchmark.as_dict(), "IBxx": 1e-8, "IByy": 1e-8, "IBzz": 1e-8,
             "IBxz": 0.0}
    with warnings.catch_warnings():      # such small moments are unusual: a warning
        warnings.simplefilter("ignore", ParameterWarning)
        bike = bench.with_params(Parameters.from_benchmark(point, name="point"))
    ids = [c.id for c in table1_causes(bike, STATES, model_terms, ["M"])]
    assert ids == [f"table1:{n}" for n in BENCHMARK_NAMES if n != "IBxz"] + [
        "table1:c-sign", "table1:lam-deg2rad", "table1:lam-head-angle", "table1:lam-sign"]
