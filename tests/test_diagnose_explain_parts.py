"""`explain`'s least-squares localization (comparisons/judgments/diagnose.py), each rule of the
module docstring on differences and causes chosen here, small enough to solve by hand: the
residual ``r = engine - model`` (one state, each entry divided by a tolerance scale of 1, so
``r`` is the difference itself) and each candidate's effect ``s`` on the same entries.

The rules, as the module docstring, `_share` and `Explanation` state them: a continuous cause
is fitted (coefficient ``s.r / |s|^2``, share ``(s.r)^2 / (|s|^2 |r|^2)``), a discrete one is
taken at full size (share ``1 - |r - s|^2 / |r|^2``); a cause whose effect is zero or not
finite explains nothing; the best cause must explain at least `LOCALIZED` of the whole and of
each differing term, a tie (within `_TIE`) is settled in the order of `KINDS`; the best fitted
causes are evaluated again at their fitted size; pairs of parameters are tried when no single
cause explains `EXPLAINED`, unless the two have (nearly) the same effect; the candidates are
the five best single causes with the differing terms each leaves unexplained, and each
differing term has its own best cause. Expected numbers are worked by hand in each docstring
(estimates cross-checked with `numpy.linalg.lstsq`, an independent least-squares solver);
boundary cases use numbers for which the floating-point result is exact.

`explain` is fed the blocks and causes directly (`term_blocks` and `candidate_causes`
replaced by the test's own), so nothing here builds a model. Each test names the planted bugs
(mutmut's survivors of `explain`) it was seen failing on."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import comparisons.judgments.diagnose as diagnose
from comparisons.judgments.causes import Cause
from comparisons.judgments.diagnose import EXPLAINED, LOCALIZED, _TIE, explain
from comparisons.judgments.term_checks import Block

#: a block fails its tolerance when one entry of the difference exceeds this (scale 1)
TOL = 0.5
BODY = {"m2": 2, "m3": 3, "m4": 4, "m5": 5, "cv": 3, "I3xx": 3, "I4xx": 4, "I5xx": 5}


def block(term: str, diff) -> Block:
    """One state of ``term`` whose engine value differs from the model's (zero) by ``diff``."""
    d = np.atleast_2d(np.asarray(diff, dtype=float))
    return Block("pinocchio", term, "", d, np.zeros_like(d), np.ones(d.shape[0]), TOL)


def cause(cid: str, effects: dict, kind: str = "parameter", fixed: bool = False,
          label: str | None = None, evaluate=None) -> Cause:
    """A candidate with ``effects`` term -> its effect on that term's entries."""
    return Cause(cid, label or cid, BODY.get(cid), kind, fixed,
                 {(t, None): np.atleast_2d(np.asarray(e, dtype=float)) for t, e in effects.items()},
                 "kg" if kind != "structural" else "", 1.5 if not fixed else None,
                 evaluate=evaluate)


def flipped(term: str, effect, label: str = "a sign flipped") -> Cause:
    """A discrete (structural) mistake whose whole effect on ``term`` is ``effect``."""
    return cause(f"sign:{term}", {term: effect}, kind="structural", fixed=True, label=label)


@pytest.fixture
def run(monkeypatch):
    """explain() on the given blocks and causes; warnings are errors (none may leak)."""
    def go(blocks, causes, shared=None):
        got = {}

        def candidates(model, states, ref, blks, solves, shared_=None):
            got["shared"], got["blocks"] = shared_, blks
            return causes
        monkeypatch.setattr(diagnose, "term_blocks", lambda *args: blocks)
        monkeypatch.setattr(diagnose, "candidate_causes", candidates)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            e = explain(None, None, {}, {}, {}, shared=shared)
        go.got = got
        return e
    return go


def lstsq(cols, r) -> tuple[np.ndarray, float]:
    """Least squares by numpy: the coefficients and the fraction of |r|^2 they remove."""
    S = np.column_stack([np.ravel(c) for c in cols])
    x = np.linalg.lstsq(S, np.ravel(r), rcond=None)[0]
    left = np.ravel(r) - S @ x
    return x, 1.0 - float(left @ left) / float(np.ravel(r) @ np.ravel(r))


# -- nothing to explain ------------------------------------------------------------------------

@pytest.mark.parametrize("diff", [[0.0, 0.0], [np.inf, 0.0], [np.nan, 1.0]])
def test_no_difference_or_a_non_finite_one_is_nothing_to_explain(run, diff):
    """The engine agreeing exactly (r = 0), or a difference that is not a number, is nothing
    to explain: None. Planted: `and` for `or` in the test (a zero or infinite difference
    explained anyway), the zero test made `rr == 1`."""
    assert run([block("Qv", diff)], [cause("m3", {"Qv": [1.0, 0.0]})]) is None


# -- one cause -----------------------------------------------------------------------------------

def test_a_difference_that_is_one_causes_effect_is_named_with_its_fitted_size(run):
    """r = (1, 0) in Qv (|r|^2 = 1 exactly); m3's effect per unit (2, 0): the fit is 0.5
    (lstsq), the share 1; m4's effect (1, 1): fit 1/2, share (s.r)^2/(|s|^2 |r|^2) = 1/2, and
    subtracting 0.5 (1, 1) leaves (0.5, -0.5) of Qv, 1 - 0.5 = 0.5 < LOCALIZED: Qv is left
    unexplained by it. So: m3 alone, all of the difference, m4 the runner-up at 50%, Qv's own
    best cause m3; the model's value, label, kind, unit and body carried over; ``shared``
    handed on to candidate_causes. Planted: a residual of norm exactly 1 taken for none, the
    runner-up dropped or the best itself, the units dropped, ``shared`` not passed on."""
    r = [1.0, 0.0]
    x, frac = lstsq([[2.0, 0.0]], r)
    shared = object()
    e = run([block("Qv", r)], [cause("m3", {"Qv": [2.0, 0.0]}), cause("m4", {"Qv": [1.0, 1.0]})],
            shared=shared)
    assert run.got["shared"] is shared
    assert e.causes == ("m3",) and e.estimates == pytest.approx(tuple(x)) == (0.5,)
    assert e.explained == pytest.approx(frac) == 1.0
    assert e.body == 3 and e.model_values == (1.5,) and e.labels == ("m3",)
    assert e.kinds == ("parameter",) and e.units == ("kg",)
    assert e.runner_up == ("m4", pytest.approx(0.5))
    assert [c[:2] for c in e.candidates] == [("m3", "m3"), ("m4", "m4")]
    assert e.candidates[0][2:] == (pytest.approx(1.0), ())
    assert e.candidates[1][2:] == (pytest.approx(0.5), ("Qv",))
    assert e.unexplained == () and e.per_term == (("Qv", "m3", pytest.approx(1.0)),)


def test_a_single_candidate_has_no_runner_up(run):
    """One candidate, m3 with effect (1, 0) on r = (2, 0): fit 2, all of it, and no next
    best cause (None). Planted: the search for a runner-up without its default (StopIteration),
    the None test inverted or made always true (indexing the causes with None)."""
    e = run([block("Qv", [2.0, 0.0])], [cause("m3", {"Qv": [1.0, 0.0]})])
    assert e.causes == ("m3",) and e.estimates == (2.0,) and e.explained == 1.0
    assert e.runner_up is None


def test_a_cause_without_any_effect_explains_nothing_and_its_fit_is_zero(run):
    """cv has no effect on the compared terms (s = 0, as cv on every term but Qaero): it
    gets no share, it is not a candidate, no term is said to be explained by it, and the
    fitted size is the least-norm fit 0 (lstsq gives 0, not a 0/0), with no warning. Planted:
    a zero |s|^2 taken as a valid fit (`>=` for `>`, `|` for `&`: estimate NaN), a per-term
    cause of share 0 listed, causes of share 0 listed as candidates."""
    r = [1.0, 0.0]
    x, _ = lstsq([[0.0, 0.0]], r)
    e = run([block("Qv", r)], [cause("cv", {"Qv": [0.0, 0.0]})])
    assert e.causes == ("cv",) and e.estimates == tuple(x) == (0.0,)
    assert e.explained == 0.0 and e.candidates == () and e.per_term == ()
    assert e.unexplained == ("Qv",)


def test_a_cause_whose_effect_is_not_finite_is_no_candidate_even_where_it_is_finite(run):
    """r = (1, 0) in Qv and (1, 0) in Qgrav. m3's effect is infinite in Qv (a model that
    could not be evaluated there) and (1, 0) in Qgrav; m4's is (1, 0) in Qv only. m3 is no
    candidate at all: not overall and not as Qgrav's own cause either (where its effect alone
    would fit). m4 explains 1/2 of the whole and all of Qv. Planted: `|` for `&` in the test
    of a usable effect (an infinite |s|^2 taken as usable), `|` for `&` in the per-term one."""
    e = run([block("Qv", [1.0, 0.0]), block("Qgrav", [1.0, 0.0])],
            [cause("m3", {"Qv": [np.inf, 0.0], "Qgrav": [1.0, 0.0]}),
             cause("m4", {"Qv": [1.0, 0.0]})])
    assert e.causes == ("m4",) and e.explained == pytest.approx(0.5)
    assert [c[0] for c in e.candidates] == ["m4"]
    assert e.per_term == (("Qv", "m4", pytest.approx(1.0)),)


def test_a_fit_that_overflows_leaks_no_warning(run):
    """r = (1e150, 0): m3's effect (1e150, 0) is the difference (fit 1); m4's effect
    (1e-160, 0) would need a coefficient of 1e310, beyond the largest float: that is no reason
    for a floating-point warning (warnings are errors here), overall or per term. Planted:
    either of the two ``np.errstate(all="ignore")`` around the fits made ``all=None``."""
    e = run([block("Qv", [1e150, 0.0])],
            [cause("m3", {"Qv": [1e150, 0.0]}), cause("m4", {"Qv": [1e-160, 0.0]})])
    assert e.causes == ("m3",) and e.estimates == (1.0,) and e.explained == 1.0


# -- each term's own best cause ---------------------------------------------------------------

def test_a_discrete_mistake_is_taken_at_full_size_in_each_term_too(run):
    """r = (1, 0) in Qv; the only candidate is a discrete mistake whose effect is (2, 0),
    twice the difference: undone it leaves r - s = (-1, 0), as much as before, so it explains
    nothing of Qv (1 - 1/1 = 0) and Qv has no own cause; scaled by 1/2 it would fit exactly,
    but a discrete cause is never scaled. Planted: the per-term fit scaling discrete causes
    too, a per-term cause of share 0 listed."""
    e = run([block("Qv", [1.0, 0.0])], [flipped("Qv", [2.0, 0.0])])
    assert e.explained == 0.0 and e.per_term == () and e.candidates == ()


def test_each_differing_term_has_its_own_fitted_cause_and_the_pair_explains_both(run):
    """r = (1, 0) in Qv and (1, 0) in Qgrav. m3 acts on Qv with (2, 0), m4 on Qgrav with
    (4, 0): each alone explains half of the whole (1/2 each) but all of its own term, fitted
    there (1/2 and 1/4, not the unscaled 2 and 4 nor 1/(2*4)). No single cause explains
    EXPLAINED, so the pair is fitted: lstsq gives (0.5, 0.25) and all of the difference; the
    pair's bodies differ (3 and 4), so no one body; the runner-up is the best single cause.
    Planted: the per-term coefficient ``b * G`` or ``b / 1`` for ``b / G``, the body of a pair
    on two bodies taken from one of them, the runner-up dropped when a pair is chosen."""
    r = [1.0, 0.0, 1.0, 0.0]
    x, frac = lstsq([[2.0, 0.0, 0.0, 0.0], [0.0, 0.0, 4.0, 0.0]], r)
    e = run([block("Qv", r[:2]), block("Qgrav", r[2:])],
            [cause("m3", {"Qv": [2.0, 0.0]}), cause("m4", {"Qgrav": [4.0, 0.0]})])
    assert e.per_term == (("Qv", "m3", pytest.approx(1.0)), ("Qgrav", "m4", pytest.approx(1.0)))
    assert e.causes == ("m3", "m4") and e.estimates == pytest.approx(tuple(x))
    assert tuple(x) == pytest.approx((0.5, 0.25))
    assert e.explained == pytest.approx(frac) and frac == pytest.approx(1.0)
    assert e.body is None
    assert e.runner_up == ("m3", pytest.approx(0.5))


def test_a_terms_own_cause_ties_within_a_millionth_go_to_the_discrete_mistake(run):
    """Qv's r = (1, 0): m3 (effect (1, 0)) explains all of it, a flipped sign (effect
    (1, d), d^2 = 2e-7) all but d^2 = 2e-7 of it: the two are tied (rounded to 1e-6) and the
    tie is settled in the order of KINDS: the discrete mistake. Planted: the rounding to 7
    digits (no tie)."""
    d = np.sqrt(2e-7)
    e = run([block("Qv", [1.0, 0.0])],
            [cause("m3", {"Qv": [1.0, 0.0]}), flipped("Qv", [1.0, d], "sign of Qv flipped")])
    assert e.per_term == (("Qv", "sign of Qv flipped", pytest.approx(1.0 - 2e-7, abs=1e-12)),)


def test_a_terms_own_cause_is_the_one_that_explains_more_when_not_tied(run):
    """Qv's r = (1, 0): m3 (effect (1, 0)) explains all of it, a flipped sign of effect
    (0.5, 0) leaves (0.5, 0): 1 - 0.25 = 0.75. No tie: m3 is Qv's own cause although the
    discrete mistake comes first in KINDS. Planted: the rounding to whole numbers (0.75 and 1
    both 1: a tie), the rounding's digits dropped."""
    e = run([block("Qv", [1.0, 0.0])],
            [flipped("Qv", [0.5, 0.0]), cause("m3", {"Qv": [1.0, 0.0]})])
    assert e.per_term == (("Qv", "m3", pytest.approx(1.0)),)


# -- the whole and each differing term: LOCALIZED ----------------------------------------------

def test_a_cause_must_explain_localized_of_each_term_and_exactly_localized_is_enough(run):
    """r = (3, 1) in Qv and (3, 1) in Qgrav, |r|^2 = 20. A discrete mistake with effect
    (3, 0) in both leaves (0, 1) in each: 1 - 2/20 = 0.9 of the whole and 1 - 1/10 = 0.9 of
    each term, exactly LOCALIZED ("at least LOCALIZED": enough). m3's effect (3, 1 | 2, 0) is
    fitted: x = s.r/|s|^2 = 16/14 = 8/7, share 16^2/(14*20) = 0.914 of the whole, more, but of
    Qgrav it removes 1 - |(3, 1) - 8/7 (2, 0)|^2/10 = 1 - (74/49)/10 = 0.849 only: the
    mistake that explains every term is named, at 0.9, m3 the runner-up leaving Qgrav
    unexplained. Planted: the whole-and-each-term rule dropped (`None`), `or` for `and` in
    it, `>` for `>=` on either share, `>` for `>=` in the terms a cause leaves unexplained."""
    r = [3.0, 1.0, 3.0, 1.0]
    x, frac = lstsq([[3.0, 1.0, 2.0, 0.0]], r)
    assert x[0] == pytest.approx(8 / 7) and frac == pytest.approx(256 / 280)
    e = run([block("Qv", r[:2]), block("Qgrav", r[2:])],
            [cause("m3", {"Qv": [3.0, 1.0], "Qgrav": [2.0, 0.0]}),
             cause("sign:Qv", {"Qv": [3.0, 0.0], "Qgrav": [3.0, 0.0]}, kind="structural",
                   fixed=True, label="a mistake")])
    assert e.causes == ("sign:Qv",) and e.explained == LOCALIZED and e.unexplained == ()
    assert e.runner_up == ("m3", pytest.approx(256 / 280))
    assert e.candidates == (("sign:Qv", "a mistake", LOCALIZED, ()),
                            ("m3", "m3", pytest.approx(256 / 280), ("Qgrav",)))


# -- ties between whole causes: _TIE and KINDS -------------------------------------------------

def test_a_discrete_mistake_exactly_one_tie_below_the_best_is_tied_and_named(run):
    """r = (1, 0): m3 (effect (1, 0)) explains all of it; a flipped sign of effect (x, y),
    x = 1 - 2^-20, undone, leaves 1 - (2x - x^2 - y^2) = 1e-6 = _TIE less (y chosen so that
    this holds exactly in floating point, checked first): a tie, as `equally_good` counts it
    (within _TIE), settled in the order of KINDS: the discrete mistake is named, m3 said to
    explain it as well. Planted: `>` for `>=` in the tie (the mistake one _TIE below not
    tied)."""
    x, y = 1.0 - 2.0 ** -20, 0.0009999995452669276
    assert 2.0 * x - (x * x + y * y) == 1.0 - _TIE
    e = run([block("Qv", [1.0, 0.0])],
            [cause("m3", {"Qv": [1.0, 0.0]}), flipped("Qv", [x, y], "sign of Qv flipped")])
    assert e.causes == ("sign:Qv",) and e.explained == 1.0 - _TIE
    assert e.equally_good == ("m3",)


def test_between_tied_causes_of_one_kind_the_larger_share_is_named(run):
    """r = (1, 0): m3's effect (1, d), d^2 = 5e-7, explains 1/(1 + d^2) = 1 - 5e-7, m4's
    (1, 0) all of it: tied within _TIE, the same kind (parameters): the one that explains
    more, m4, though m3 comes first. Planted: the tie settled by the smaller share."""
    d = np.sqrt(5e-7)
    e = run([block("Qv", [1.0, 0.0])],
            [cause("m3", {"Qv": [1.0, d]}), cause("m4", {"Qv": [1.0, 0.0]})])
    assert e.causes == ("m4",) and e.explained == 1.0


# -- the fitted causes evaluated at their size -------------------------------------------------

def test_a_fitted_cause_explaining_half_of_localized_is_evaluated_at_its_size(run):
    """r = (3, 3, 1, 1), |r|^2 = 20; m3's linearized effect (1, 0, 0, 0) fits x = 3 and
    explains 9/20 = 0.45 = LOCALIZED / 2 exactly: enough to be evaluated at its fitted size
    (`evaluate(3.0)`), where the model rebuilt with m3 + 3 changes the terms by all of r: it
    explains all of the difference. Planted: `<=` for `<` at the cut (0.45 not evaluated),
    the cut LOCALIZED / 2 made 0.5 / LOCALIZED."""
    r = [3.0, 3.0, 1.0, 1.0]
    asked = []

    def evaluate(x):
        asked.append(x)
        return {("Qv", None): np.array([r])}
    e = run([block("Qv", r)], [cause("m3", {"Qv": [1.0, 0.0, 0.0, 0.0]}, evaluate=evaluate)])
    assert asked == [3.0] and LOCALIZED / 2 == 9 / 20
    assert e.causes == ("m3",) and e.estimates == (3.0,) and e.explained == 1.0
    assert e.unexplained == () and e.candidates == (("m3", "m3", 1.0, ()),)


def test_the_terms_a_cause_leaves_are_judged_on_its_evaluated_effect(run):
    """r = (1, 0) in Qv and (1, 0) in Qgrav; m3's linearized effect (1, 0 | 0.5, 0) fits
    x = 1.5/1.25 = 1.2 and explains 1.5^2/(1.25*2) = 0.9 linearly, which would leave
    1 - (1 - 0.6)^2 = 0.84 of Qgrav; evaluated at 1.2 the rebuilt model's change is all of r:
    nothing is left unexplained, in the candidates and in the explanation. Planted: the
    terms left unexplained judged on the linearized effect instead."""
    asked = []

    def evaluate(x):
        asked.append(x)
        return {("Qv", None): np.array([[1.0, 0.0]]), ("Qgrav", None): np.array([[1.0, 0.0]])}
    e = run([block("Qv", [1.0, 0.0]), block("Qgrav", [1.0, 0.0])],
            [cause("m3", {"Qv": [1.0, 0.0], "Qgrav": [0.5, 0.0]}, evaluate=evaluate)])
    assert asked == [pytest.approx(1.2)]
    assert e.causes == ("m3",) and e.explained == pytest.approx(1.0)
    assert e.unexplained == () and e.candidates == (("m3", "m3", pytest.approx(1.0), ()),)


def test_a_fitted_value_that_is_no_model_leaves_every_differing_term_unexplained(run):
    """r = (1, 0) in Qv and in Qgrav; m3's effect (1, 0 | 1, 0) fits x = 1 linearly, but
    m3 + 1 is no valid model (`evaluate` gives None): it explains nothing, and both differing
    terms are left unexplained. Planted: the terms of a cause without a model made
    `tuple(None)` (a TypeError)."""
    e = run([block("Qv", [1.0, 0.0]), block("Qgrav", [1.0, 0.0])],
            [cause("m3", {"Qv": [1.0, 0.0], "Qgrav": [1.0, 0.0]}, evaluate=lambda x: None)])
    assert e.causes == ("m3",) and e.explained == 0.0 and e.candidates == ()
    assert e.unexplained == ("Qv", "Qgrav")


# -- the candidates ----------------------------------------------------------------------------

def test_the_five_best_causes_each_label_once_are_the_candidates(run):
    """r = (8, 7, 6, 5, 4, 3, 2, 1) in Qv (|r|^2 = 204); eight parameters, the k-th with
    effect e_k, explain r_k^2/204 each, in that order; a ninth cause with the first one's label
    and the second one's effect (49/204) comes right after the second. The candidates are the
    five best, each label once: m2, m3, m4, m5 (labels L1..L4) and I3xx (L5), their shares
    64, 49, 36, 25, 16 over 204. Planted: a label seen again listed (`and` for `or`, `None`
    remembered instead of the label), stopping at the first label seen again, six
    candidates."""
    r = np.arange(8, 0, -1, dtype=float)
    ids = ["m2", "m3", "m4", "m5", "I3xx", "I4xx", "I5xx", "cv"]
    causes = [cause(cid, {"Qv": np.eye(8)[k]}, label=f"L{k + 1}") for k, cid in enumerate(ids)]
    causes.insert(2, cause("I2xx", {"Qv": np.eye(8)[1]}, label="L1"))
    e = run([block("Qv", r)], causes)
    assert [c[:2] for c in e.candidates] == [("m2", "L1"), ("m3", "L2"), ("m4", "L3"),
                                            ("m5", "L4"), ("I3xx", "L5")]
    assert [c[2] for c in e.candidates] == pytest.approx([64 / 204, 49 / 204, 36 / 204,
                                                          25 / 204, 16 / 204])


def test_a_cause_that_explains_nothing_is_no_candidate(run):
    """r = (1, 1) in Qv: m3 (effect (1, 0)) and m4 ((0, 1)) explain 1/2 each; cv's effect
    (0, 0) nothing: not a candidate, though fewer than five are listed. Planted: `<` for `<=`
    in the test of a share of nothing, `and` for `or`."""
    e = run([block("Qv", [1.0, 1.0])],
            [cause("m3", {"Qv": [1.0, 0.0]}), cause("cv", {"Qv": [0.0, 0.0]}),
             cause("m4", {"Qv": [0.0, 1.0]})])
    assert [c[0] for c in e.candidates] == ["m3", "m4"]


# -- pairs -------------------------------------------------------------------------------------

def test_pairs_are_of_parameters_only(run):
    """r = (1, 1): 'm3 in Qv only' (effect (1, 0)) and 'm4 in Qv only' ((0, 1)) explain 1/2
    each and together all of it, but a pair is tried only of parameters (and the gyroscopic
    and contact terms), not of a parameter in one term: the first of the two, at 1/2. Planted:
    every cause that is not a structural one in the pairs."""
    e = run([block("Qv", [1.0, 1.0])],
            [cause("m3@Qv", {"Qv": [1.0, 0.0]}, kind="term-parameter"),
             cause("m4@Qv", {"Qv": [0.0, 1.0]}, kind="term-parameter")])
    assert e.causes == ("m3@Qv",) and e.explained == pytest.approx(0.5)


def test_a_cause_without_effect_is_left_out_of_the_pairs_and_the_next_pair_is_tried(run):
    """r = (1, 1); cv has no effect, m3 (1, 0) and m4 (0, 1): the pairs with cv are skipped,
    and (m3, m4), tried after them, explains all of it, fitted (1, 1) (lstsq). Planted:
    `break` for `continue` after a pair with an unusable cause."""
    x, _ = lstsq([[1.0, 0.0], [0.0, 1.0]], [1.0, 1.0])
    e = run([block("Qv", [1.0, 1.0])],
            [cause("cv", {"Qv": [0.0, 0.0]}), cause("m3", {"Qv": [1.0, 0.0]}),
             cause("m4", {"Qv": [0.0, 1.0]})])
    assert e.causes == ("m3", "m4") and e.estimates == pytest.approx(tuple(x))
    assert e.explained == pytest.approx(1.0)


def test_a_cause_with_an_infinite_effect_is_left_out_of_the_pairs(run):
    """r = (1, 1); m2's effect is infinite in both entries (no usable effect), m3 (1, 2)
    and m4 (2, 1) explain 9/10 each alone and together all of it, fitted (1/3, 1/3)
    (lstsq): the pair (m3, m4) is found, m2 paired with nothing. Planted: `or` for `and` in
    the test that both causes of a pair are usable (a pair with m2 solved, its NaN fraction
    then beating nothing)."""
    x, _ = lstsq([[1.0, 2.0], [2.0, 1.0]], [1.0, 1.0])
    e = run([block("Qv", [1.0, 1.0])],
            [cause("m2", {"Qv": [np.inf, np.inf]}), cause("m3", {"Qv": [1.0, 2.0]}),
             cause("m4", {"Qv": [2.0, 1.0]})])
    assert e.causes == ("m3", "m4") and e.estimates == pytest.approx(tuple(x))
    assert e.explained == pytest.approx(1.0)


@pytest.mark.parametrize("a, b", [(1.0, 0.5), (2.0, 2.0), (1e-100, 1e-100)])
def test_two_causes_of_the_same_effect_are_no_pair(run, a, b):
    """r = (1, 1); m3's effect (a, 0) and m4's (b, 0) point the same way (at sizes 1 and
    1/2, both 2, both 1e-100, where even |s|^4 underflows): the pair says nothing more than
    one cause, it is not solved (its matrix is singular); one of them explains 1/2. Planted:
    the determinant's `-` made `+`, its `*` made `/`, its square made `* 2` or a cube,
    `<` for `<=` against the relative threshold (0 < 0 at 1e-100)."""
    e = run([block("Qv", [1.0, 1.0])],
            [cause("m3", {"Qv": [a, 0.0]}), cause("m4", {"Qv": [b, 0.0]})])
    assert len(e.causes) == 1 and e.explained == pytest.approx(0.5)


def test_a_pair_of_small_effects_is_a_pair_all_the_same(run):
    """r = (1, 1); m3's effect (1e-3, 0), m4's (0, 1e-3): independent, whatever their size
    (the threshold on the determinant is relative, 1e-9 |s_a|^2 |s_b|^2): the pair explains
    all of it at (1000, 1000) (lstsq). Planted: the threshold's product made a quotient, on
    either side."""
    x, _ = lstsq([[1e-3, 0.0], [0.0, 1e-3]], [1.0, 1.0])
    e = run([block("Qv", [1.0, 1.0])],
            [cause("m3", {"Qv": [1e-3, 0.0]}), cause("m4", {"Qv": [0.0, 1e-3]})])
    assert e.causes == ("m3", "m4") and e.estimates == pytest.approx(tuple(x))
    assert e.explained == pytest.approx(1.0)


def test_a_nearly_parallel_pair_above_the_threshold_is_a_pair(run):
    """r = (0, 1); m3's effect (1e-2, 0), m4's (1, 1e-4): nearly parallel, but the
    determinant |s_a|^2 |s_b|^2 - (s_a.s_b)^2 = 1e-4 (1 + 1e-8) - 1e-4 = 1e-12 is above 1e-9
    |s_a|^2 |s_b|^2 = 1e-13: the pair is solved and explains all of it, at (-1e6, 1e4)
    (lstsq), where m4 alone explains 1e-8. Planted: the threshold's |s_a|^2 taken from the
    off-diagonal entry s_a.s_b instead (1e-11: skipped)."""
    x, _ = lstsq([[1e-2, 0.0], [1.0, 1e-4]], [0.0, 1.0])
    e = run([block("Qv", [0.0, 1.0])],
            [cause("m3", {"Qv": [1e-2, 0.0]}), cause("m4", {"Qv": [1.0, 1e-4]})])
    assert e.causes == ("m3", "m4") and e.estimates == pytest.approx(tuple(x), rel=1e-6)
    assert e.explained == pytest.approx(1.0)


def test_a_parallel_pair_is_skipped_and_the_next_one_tried(run):
    """r = (1, 1); m3 and m4 both have effect (1, 0), m5 (0, 1): (m3, m4) is skipped, and
    (m3, m5) after it explains all of it. Planted: `break` for `continue` after a parallel
    pair."""
    e = run([block("Qv", [1.0, 1.0])],
            [cause("m3", {"Qv": [1.0, 0.0]}), cause("m4", {"Qv": [1.0, 0.0]}),
             cause("m5", {"Qv": [0.0, 1.0]})])
    assert e.causes == ("m3", "m5") and e.explained == pytest.approx(1.0)


def test_between_pairs_that_explain_as_much_the_first_is_kept(run):
    """r = (1, 1); m3 (1, 0), m4 (0, 1), m5 (0, 1): (m3, m4) and (m3, m5) both explain
    exactly all of it (2/2); the first is kept, as between single causes of one kind and
    share (m4 before m5). Planted: `>=` for `>` in the comparison of pairs (the last one
    kept)."""
    e = run([block("Qv", [1.0, 1.0])],
            [cause("m3", {"Qv": [1.0, 0.0]}), cause("m4", {"Qv": [0.0, 1.0]}),
             cause("m5", {"Qv": [0.0, 1.0]})])
    assert e.causes == ("m3", "m4") and e.explained == 1.0


def test_a_pair_that_explains_less_than_explained_is_not_named(run):
    """r = (1, 1, 1): m3 (1, 0, 0) and m4 (0, 1, 0) explain 1/3 each and 2/3 together, less
    than EXPLAINED: the best single cause is named, at 1/3. Planted: `or` for `and` in the
    pair's acceptance (any pair accepted)."""
    e = run([block("Qv", [1.0, 1.0, 1.0])],
            [cause("m3", {"Qv": [1.0, 0.0, 0.0]}), cause("m4", {"Qv": [0.0, 1.0, 0.0]})])
    assert e.causes == ("m3",) and e.explained == pytest.approx(1 / 3)


def test_a_pair_that_explains_exactly_explained_is_named(run):
    """r = (9, 3, 3, 1), |r|^2 = 100; m3's effect (1, 0, 0, 0) explains 81/100, m5's
    (0, 1, 1, 0) 36/200: no single cause explains EXPLAINED. The pair spans e1 and e2 + e3:
    it removes 81 + 6^2/2 = 99 of 100, exactly EXPLAINED ("at least": enough), fitted (9, 3),
    on two bodies (3 and 5): no one body, m3 the runner-up at 0.81. Planted: `>` for `>=` in
    the pair's acceptance."""
    r = [9.0, 3.0, 3.0, 1.0]
    x, frac = lstsq([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 1.0, 0.0]], r)
    assert tuple(x) == pytest.approx((9.0, 3.0)) and frac == pytest.approx(EXPLAINED)
    e = run([block("Qv", r)],
            [cause("m3", {"Qv": [1.0, 0.0, 0.0, 0.0]}), cause("m5", {"Qv": [0.0, 1.0, 1.0, 0.0]})])
    assert e.causes == ("m3", "m5") and e.estimates == (9.0, 3.0) and e.explained == EXPLAINED
    assert e.body is None and e.runner_up == ("m3", 0.81)
    assert e.labels == ("m3", "m5") and e.units == ("kg", "kg")


def test_a_pair_must_explain_five_points_more_than_the_best_single_cause(run):
    """r = (sqrt 0.96, sqrt 0.035, sqrt 0.005) (|r|^2 = 1): m3 (effect e1) explains 0.96,
    the pair with m4 (e2) 0.995, above EXPLAINED but not 0.96 + 0.05: m3 alone is named.
    Planted: the margin subtracted (0.91: the pair taken)."""
    r = np.sqrt([0.96, 0.035, 0.005])
    e = run([block("Qv", r)],
            [cause("m3", {"Qv": [1.0, 0.0, 0.0]}), cause("m4", {"Qv": [0.0, 1.0, 0.0]})])
    assert e.causes == ("m3",) and e.explained == pytest.approx(0.96)


def test_the_share_of_a_pair_is_never_more_than_all_of_it(run):
    """r = 1/4 s_a + 3/8 s_b with s_a = (4, 6, 6) (m3) and s_b = (-2, -1, -4) (m4): the pair
    explains all of the difference (lstsq: (1/4, 3/8)), m3 alone 0.514; the fraction
    computed from the pair's normal equations comes out a rounding above 1 here, and a share
    is at most 1. Planted: the cap at 1 made 2."""
    sa, sb = np.array([4.0, 6.0, 6.0]), np.array([-2.0, -1.0, -4.0])
    r = 0.25 * sa + 0.375 * sb
    x, _ = lstsq([sa, sb], r)
    e = run([block("Qv", r)], [cause("m3", {"Qv": sa}), cause("m4", {"Qv": sb})])
    assert e.causes == ("m3", "m4") and e.estimates == pytest.approx(tuple(x))
    assert tuple(x) == pytest.approx((0.25, 0.375))
    assert e.explained <= 1.0 and e.explained == pytest.approx(1.0)
