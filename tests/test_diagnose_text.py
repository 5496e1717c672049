"""What `bicycle-xval diagnose` prints and writes (`Diagnosis.describe`, ``--json``), on
diagnoses built by hand here, so that every number, entry and cause in the expected text is
one this file chose: the table's columns (term, engine, max error to one digit, tolerance,
verdict, worst entries), the legend of the rows taken a second way, the compared quantities,
the localized cause with its fitted change, the best candidates and each term's own best cause
when nothing is localized, the differences declared against another file, the engines not
run and the verdict (docs/report.md, "Diagnose"); and the JSON's keys and values."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from comparisons.judgments.diagnose import Diagnosis, Explanation, Localization
from comparisons.judgments.term_checks import TermCheck
from comparisons.judgments.terms import TermComparison

M_BAD = TermCheck("pinocchio", "M", 3.2e-3, 1.1e-2, 1e-9, False, 4,
                  ("M[theta, theta]", "M[theta, gamma]"))
QV_BAD = TermCheck("pinocchio", "Qv", 5.0e-4, 2.0e-3, 1e-9, False, 7, ("Qv[psi]",))
QGRAV_F = TermCheck("pinocchio", "Qgrav", 2.0e-12, 1.0e-12, 1e-9, True, 0, ("Qgrav[theta]",), "F")
DDQ = TermCheck("exudyn-tree", "ddq", 1.0e-13, 1.0e-13, 1e-8, True, 2, ("ddq[gamma]",), "solve")
M_OK = TermCheck("pinocchio", "M", 1.0e-15, 1.0e-15, 1e-9, True, 1, ("M[psi, psi]",))
M_IN_ID = TermCheck("pinocchio", "M", 1.0e-15, 1.0e-15, 1e-9, True, 1, ("M[psi, psi]",), "ID")
MASS = TermComparison("mass_matrix", ("reference", "pinocchio"), 3.2e-3, 1.1e-2, 1e-9, False, 4,
                      "M[theta, theta]", 24)
GRAV = TermComparison("gravity", ("reference", "pinocchio"), 1.0e-12, 1.0e-12, 1e-9, True, 0,
                      "Qgrav[theta]", 24)
MASS_OK = TermComparison("mass_matrix", ("reference", "pinocchio"), 1.0e-15, 1.0e-15, 1e-9, True,
                         1, "M[psi, psi]", 24)

I3XX = Explanation(causes=("I3xx",), estimates=(-1.5,), explained=1.0, body=3,
                   runner_up=("m3", 0.2), model_values=(20.213,), labels=("I3xx",),
                   kinds=("parameter",), units=("kg*m^2",),
                   candidates=(("I3xx", "I3xx", 1.0, ()), ("m3", "m3", 0.2, ())))
NEITHER = Explanation(causes=("I3xx",), estimates=(-0.75,), explained=0.5, body=3,
                      runner_up=("m3", 0.2), model_values=(20.213,), labels=("I3xx",),
                      kinds=("parameter",), units=("kg*m^2",),
                      candidates=(("I3xx", "I3xx", 0.5, ("Qv",)), ("m3", "m3", 0.2, ()),
                                  ("cv", "cv", 0.1, ("M",))),
                      unexplained=("Qv",),
                      per_term=(("M", "I3xx", 0.99), ("Qv", "cv", 0.98)))


def test_a_localized_mass_fault_is_the_table_the_quantities_the_cause_and_the_verdict():
    """The engine column is as wide as the longest engine name of every row, the solve rows'
    too (it was the term rows' alone: 'exudyn-tree' on a ddq solve row pushed its columns out)."""
    d = Diagnosis("mine.toml", None, ("pinocchio", "exudyn-tree"), 24,
                  Localization((MASS, GRAV), (M_BAD, QGRAV_F), I3XX, (DDQ,)),
                  not_run=(("mujoco", "the thesis's fork-axis contact"),))
    assert d.describe().split("\n") == [
        "diagnose mine.toml against engines built from the same file (engines: pinocchio, "
        "exudyn-tree; 24 states)",
        "",
        "term       engine      max error tolerance  verdict  worst entries",
        "M          pinocchio     3.2e-03     1e-09  DIFFERS  M[theta, theta], M[theta, gamma]",
        "Qgrav in F pinocchio     2.0e-12     1e-09  ok       Qgrav[theta]",
        "ddq solve  exudyn-tree   1.0e-13     1e-08  ok       ddq[gamma]",
        "  'in F': the term taken out of generalized_forces (F = Qv + Qgrav + Qaero + S T), the "
        "other row from gravity() / inverse_dynamics()",
        "  'ddq solve': forward_acceleration against the constrained solve of the engine's own M, "
        "F, D and dD dq",
        "",
        "compared quantities (tolerances.toml): 1 of 2 within tolerance; failing: mass_matrix vs "
        "pinocchio 3.2e-03 > 1e-09 at M[theta, theta]",
        "localized: M via I3xx (body 3 frame+rider)",
        "  I3xx (body 3 frame+rider) explains 100.00% of the difference: dI3xx = -1.5 kg*m^2 "
        "(model 20.213, engines' fit 18.713 kg*m^2); next best single cause m3 (20.0%)",
        "compared: engines built from mine.toml against the reference built from mine.toml; to "
        "see how it differs from another bicycle use --against NAME",
        "not run on this model: mujoco (the thesis's fork-axis contact)",
        "verdict: DIFFERS",
    ]


def test_no_single_cause_lists_the_entries_the_candidates_and_each_terms_own_cause():
    declared = (("m3", 77.391, 80.0), ("m2", 2.612, 2.0), ("m4", 1.725, 4.0), ("m5", 2.612, 3.0),
                ("R_rear", 0.32, 0.3), ("R_front", 0.32, 0.35), ("contact", "thesis", "disc"))
    d = Diagnosis("mine.toml", "shared/benchmark.toml", ("pinocchio",), 24,
                  Localization((MASS,), (M_BAD, QV_BAD, M_IN_ID), NEITHER), declared=declared)
    lines = d.describe().split("\n")
    assert lines[0] == ("diagnose mine.toml against shared/benchmark.toml (engines: pinocchio; "
                        "24 states)")
    assert lines[2] == "term       engine     max error tolerance  verdict  worst entries"
    assert lines[5] == "M in ID    pinocchio    1.0e-15     1e-09  ok       M[psi, psi]"
    assert lines[6] == ("  'M in ID': M taken out of inverse_dynamics (column k: ID(q, 0, e_k) - "
                        "ID(q, 0, 0)), the other row from mass_matrix()")
    assert lines[8:] == [
        "compared quantities (tolerances.toml): 0 of 1 within tolerance; failing: mass_matrix vs "
        "pinocchio 3.2e-03 > 1e-09 at M[theta, theta]",
        "no single cause explains it: M, Qv differ(s) at M[theta, theta], M[theta, gamma], "
        "Qv[psi]",
        "  best candidates (share of the difference each explains alone, 90% needed): I3xx 50.0% "
        "(leaves Qv unexplained), m3 20.0%, cv 10.0% (leaves M unexplained)",
        "  term by term (more than one mistake?): M: I3xx 99.0%; Qv: cv 98.0%",
        "your file differs from shared/benchmark.toml in: m3: benchmark 80, yours 77.391 kg; "
        "m2: benchmark 2, yours 2.612 kg; m4: benchmark 4, yours 1.725 kg; m5: benchmark 3, "
        "yours 2.612 kg; R_rear: benchmark 0.3, yours 0.32 m; R_front: benchmark 0.35, yours "
        "0.32 m and 1 more (see --json)",
        "verdict: DIFFERS",
    ]


def test_an_agreeing_file_says_it_is_interpreted_consistently():
    d = Diagnosis("mine.toml", None, ("pinocchio",), 24, Localization((MASS_OK,), (M_OK,), None))
    lines = d.describe().split("\n")
    assert lines[-3:] == [
        "compared quantities (tolerances.toml): 1 of 1 within tolerance",
        "compared: engines built from mine.toml against the reference built from mine.toml: the "
        "file is interpreted consistently; to see how it differs from another bicycle use "
        "--against NAME",
        "verdict: everything agrees"]
    assert not any(line.startswith("  '") for line in lines)     # no second-way rows: no legend


def test_the_json_of_a_localized_fault():
    d = Diagnosis("mine.toml", None, ("pinocchio",), 24,
                  Localization((MASS,), (M_BAD,), I3XX), declared=(("m3", 77.391, 80.0),),
                  not_run=(("mujoco", "why"),))
    assert d.to_dict() == {
        "model": "mine.toml", "against": None, "engines": ["pinocchio"], "n_states": 24,
        "agrees": False, "localized_to": "M via I3xx (body 3 frame+rider)", "localized": True,
        "terms": [{"engine": "pinocchio", "term": "M", "max_error": 3.2e-3, "max_abs_error": 1.1e-2,
                   "tolerance": 1e-9, "passed": False, "worst_state": 4,
                   "entries": ["M[theta, theta]", "M[theta, gamma]"], "source": ""}],
        "comparisons": [{"quantity": "mass_matrix", "engines": ["reference", "pinocchio"],
                         "max_error": 3.2e-3, "tolerance": 1e-9, "passed": False,
                         "worst_entry": "M[theta, theta]"}],
        "explanation": {
            "causes": ["I3xx"], "estimates": [-1.5], "explained": 1.0, "body": 3,
            "runner_up": ["m3", 0.2], "model_values": [20.213], "labels": ["I3xx"],
            "localized": True, "unexplained": [], "per_term": [],
            "candidates": [{"cause": "I3xx", "label": "I3xx", "explained": 1.0, "unexplained": []},
                           {"cause": "m3", "label": "m3", "explained": 0.2, "unexplained": []}]},
        "declared_differences": [["m3", 77.391, 80.0]],
        "not_run": [{"engine": "mujoco", "reason": "why"}],
    }


def test_the_json_of_an_explanation_that_localizes_nothing():
    e = NEITHER.to_dict()
    assert e["localized"] is False and e["unexplained"] == ["Qv"]
    assert e["per_term"] == [{"term": "M", "label": "I3xx", "explained": 0.99},
                             {"term": "Qv", "label": "cv", "explained": 0.98}]
    assert e["candidates"][2] == {"cause": "cv", "label": "cv", "explained": 0.1,
                                  "unexplained": ["M"]}
    agreeing = Diagnosis("f", None, (), 1, Localization((MASS_OK,), (M_OK,), None)).to_dict()
    assert agreeing["localized_to"] is None and agreeing["explanation"] is None
    assert agreeing["agrees"] is True and agreeing["localized"] is False


def _one(cause, est, value, kind, unit, label, body=None, explained=1.0, candidates=()):
    return Explanation(causes=(cause,), estimates=(est,), explained=explained, body=body,
                       model_values=(value,), labels=(label,), kinds=(kind,), units=(unit,),
                       candidates=candidates)


@pytest.mark.parametrize("e, text", [
    (_one("contact", 1.0, "thesis", "structural", "", "front contact model"),
     "front contact model (all bodies) explains 100.00% of the difference: engines' front "
     "contact is the other model (coefficient 1.000; the model under test: 'thesis')"),
    (_one("gyroscopic", 0.998, "without", "structural", "", "gyroscopic terms w x (I w)"),
     "gyroscopic terms w x (I w) (all bodies) explains 100.00% of the difference: the model "
     "under test lacks the gyroscopic terms the engines have (coefficient 0.998)"),
    (_one("gyroscopic", 1.0, "with", "structural", "", "gyroscopic terms w x (I w)"),
     "gyroscopic terms w x (I w) (all bodies) explains 100.00% of the difference: the engines "
     "lack the gyroscopic terms the model under test has (coefficient 1.000)"),
    (_one("sign:Qgrav[F]", 1.0, None, "structural", "", "sign of Qgrav flipped in F"),
     "sign of Qgrav flipped in F explains 100.00% of the difference: undoing it removes that "
     "share (the whole mistake, no fitted size)"),
    (_one("m3@Qgrav", 0.5, 77.391, "term-parameter", "kg", "m3 in Qgrav", body=3),
     "m3 in Qgrav (body 3 frame+rider) explains 100.00% of the difference: dm3 = +0.5 kg in "
     "Qgrav only (model 77.391, that term's fit 77.891 kg)"),
    (_one("xa@D", -0.01, 0.90109, "term-parameter", "m", "xa in D", body=3),
     "xa in D (body 3 frame+rider) explains 100.00% of the difference: dxa = -0.01 m in D only "
     "(model 0.90109, that term's fit 0.89109 m): D and dD dq were built with different xa"),
    (_one("z5@dD dq", 0.02, -0.40779, "term-parameter", "m", "z5 in dD dq", body=4),
     "z5 in dD dq (body 4 fork/handlebar) explains 100.00% of the difference: dz5 = +0.02 m in "
     "dD dq only (model -0.40779, that term's fit -0.38779 m): D and dD dq were built with "
     "different z5"),
    (_one("table1:lam", 0.01, 0.314159, "table1", "rad", "lam (Table 1)"),
     "lam (Table 1) (all bodies) explains 100.00% of the difference: dlam = +0.01 rad in Table 1 "
     "(model built from lam = 0.314159, engines' fit 0.324159 rad)"),
    (_one("cv", 0.2, 0.8, "parameter", "kg/m", "cv", body=3, explained=0.95),
     "cv (body 3 frame+rider) explains 95.00% of the difference: dcv = +0.2 kg/m (model 0.8, "
     "engines' fit 1 kg/m); it leaves 5% of the difference, more than a linearization or "
     "round-off leaves: a near cause, perhaps not the exact one"),
    (_one("m2", 0.1, 2.612, "parameter", "kg", "m2", body=2,
          candidates=(("m2", "m2", 1.0, ()), ("R_rear", "R_rear", 1.0 - 5e-7, ()))),
     "m2 (body 2 rear wheel) explains 100.00% of the difference: dm2 = +0.1 kg (model 2.612, "
     "engines' fit 2.712 kg); R_rear explains it as well: the compared terms cannot tell the two "
     "apart, so check both"),
    (_one("m2", 0.1, 2.612, "parameter", "kg", "m2", body=2,
          candidates=(("m2", "m2", 1.0, ()), ("R_rear", "R_rear", 1.0, ()),
                      ("g", "g", 1.0, ()), ("m3", "m3", 0.5, ()))),
     "m2 (body 2 rear wheel) explains 100.00% of the difference: dm2 = +0.1 kg (model 2.612, "
     "engines' fit 2.712 kg); R_rear and g explain it as well: the compared terms cannot tell "
     "these apart, so check each"),
], ids=["contact", "gyroscopic-without", "gyroscopic-with", "structural", "term-parameter",
        "D-and-dD-dq", "dD-dq", "table1", "near-cause", "a-tie", "two-ties"])
def test_each_kind_of_cause_is_worded_as_the_report_guide_has_it(e, text):
    assert e.describe() == text


def test_two_parameters_traded_for_each_other_are_called_swapped():
    """x3 and z3 swapped: the fit moves each onto the other's value (dx3 = z3 - x3 = -dz3)."""
    x3, z3 = 0.26047, 0.94687
    pair = Explanation(causes=("x3", "z3"), estimates=(z3 - x3, x3 - z3), explained=1.0, body=3,
                       model_values=(x3, z3), labels=("x3", "z3"),
                       kinds=("parameter", "parameter"), units=("m", "m"))
    assert pair.describe() == (
        "x3 + z3 (body 3 frame+rider) explains 100.00% of the difference: dx3 = +0.6864 m (model "
        "0.26047, engines' fit 0.94687 m); dz3 = -0.6864 m (model 0.94687, engines' fit 0.26047 "
        "m); looks like x3 and z3 swapped")
    moved = dataclasses.replace(pair, estimates=(z3 - x3, 0.5 * (x3 - z3)))     # not a trade
    assert "swapped" not in moved.describe()
    apart = dataclasses.replace(pair, estimates=(0.3, -0.3))     # a trade, not onto each other
    assert "swapped" not in apart.describe()
    mixed = dataclasses.replace(pair, causes=("x3", "m3"), labels=("x3", "m3"),
                                units=("m", "kg"))              # a length and a mass: never
    assert "swapped" not in mixed.describe()


def test_best_candidates_with_none_and_a_localization_without_a_cause():
    assert dataclasses.replace(NEITHER, candidates=()).best_candidates() == "none"
    assert NEITHER.best_candidates(1) == "I3xx 50.0% (leaves Qv unexplained)"
    loc = Localization((MASS,), (M_BAD,), None)
    assert loc.describe() == "M differ(s); no cause found"
    loc = Localization((MASS,), (M_BAD, QV_BAD), NEITHER)
    assert loc.describe() == ("M, Qv differ(s); no single cause explains it (best: I3xx 50.0% "
                              "(leaves Qv unexplained), m3 20.0%)")
    assert Localization((MASS_OK,), (M_OK,), None).describe() == "everything agrees"
    partly = dataclasses.replace(I3XX, explained=0.95)
    assert Localization((MASS,), (M_BAD,), partly).describe() == (
        "M via I3xx (body 3 frame+rider), partly: it explains 95% (more than one cause?)")
    only_mass = Localization((MASS,), (), None)
    assert only_mass.describe() == "a compared quantity differ(s); no cause found"


def test_kinds_and_units_default_from_the_causes_themselves():
    """An explanation made without kinds or units (a caller's own): a structural cause is
    worded as one, a parameter gets its unit from the parameter table (I3xx in kg*m^2), and
    a runner-up that is no candidate is named by its readable label."""
    e = Explanation(causes=("contact",), estimates=(1.0,), explained=1.0, body=None,
                    model_values=("disc",), runner_up=("gyroscopic", 0.3))
    assert e.describe() == (
        "front contact model (all bodies) explains 100.00% of the difference: engines' front "
        "contact is the other model (coefficient 1.000; the model under test: 'disc'); next best "
        "single cause gyroscopic terms w x (I w) (30.0%)")
    e = Explanation(causes=("I3xx",), estimates=(0.5,), explained=1.0, body=3,
                    model_values=(20.213,))
    assert e.describe() == ("I3xx (body 3 frame+rider) explains 100.00% of the difference: "
                            "dI3xx = +0.5 kg*m^2 (model 20.213, engines' fit 20.713 kg*m^2)")


def test_a_runner_up_among_the_candidates_is_named_by_its_candidates_label():
    e = dataclasses.replace(I3XX, runner_up=("table1:lam", 0.25),
                            candidates=(("I3xx", "I3xx", 1.0, ()),
                                        ("table1:lam", "lam (Table 1)", 0.25, ())))
    assert e.describe().endswith("; next best single cause lam (Table 1) (25.0%)")
    small = dataclasses.replace(I3XX, runner_up=("m3", 0.004))   # below half a per cent
    assert "next best" not in small.describe()


def test_what_is_printed_when_only_a_compared_quantity_fails_and_nothing_explains_it():
    """Every term agrees but a compared quantity fails (no term row to name), no explanation:
    the line names 'a compared quantity' and 'no entry', the candidates 'none'; two failing
    quantities are listed apart; exactly six declared differences need no '... more'."""
    grav_bad = TermComparison("gravity", ("reference", "pinocchio"), 2.0e-3, 1.0e-3, 1e-9, False,
                              3, "Qgrav[theta]", 24)
    declared = tuple((n, 1.0, 2.0) for n in ("m2", "m3", "m4", "m5", "R_rear", "R_front"))
    d = Diagnosis("mine.toml", "their.toml", ("pinocchio",), 24,
                  Localization((MASS, grav_bad), (M_OK,), None), declared=declared)
    lines = d.describe().split("\n")
    assert lines[5] == ("compared quantities (tolerances.toml): 0 of 2 within tolerance; failing: "
                        "mass_matrix vs pinocchio 3.2e-03 > 1e-09 at M[theta, theta]; gravity vs "
                        "pinocchio 2.0e-03 > 1e-09 at Qgrav[theta]")
    assert lines[6:9] == [
        "no single cause explains it: a compared quantity differ(s) at M[theta, theta], "
        "Qgrav[theta]",
        "  best candidates (share of the difference each explains alone, 90% needed): none",
        "your file differs from their.toml in: m2: their 2, yours 1 kg; m3: their 2, yours 1 kg; "
        "m4: their 2, yours 1 kg; m5: their 2, yours 1 kg; R_rear: their 2, yours 1 m; R_front: "
        "their 2, yours 1 m"]
    assert Localization((), (), None).describe() == "everything agrees"


def test_at_most_six_differing_entries_and_one_terms_own_cause_is_not_a_breakdown():
    many = TermCheck("pinocchio", "M", 1e-3, 1e-3, 1e-9, False, 0,
                     tuple(f"M[theta, {c}]" for c in ("xc", "yc", "phi", "theta", "psi", "beta",
                                                      "gamma")))
    one_term = dataclasses.replace(NEITHER, per_term=(("M", "I3xx", 0.99),))
    d = Diagnosis("mine.toml", None, ("pinocchio",), 24,
                  Localization((MASS,), (many,), one_term))
    lines = d.describe().split("\n")
    line = next(x for x in lines if x.startswith("no single cause"))
    assert line == ("no single cause explains it: M differ(s) at M[theta, xc], M[theta, yc], "
                    "M[theta, phi], M[theta, theta], M[theta, psi], M[theta, beta]")
    assert not any("term by term" in x for x in lines)


def test_near_swaps_a_cause_that_is_no_parameter_and_the_json_flags():
    x3, z3 = 0.26047, 0.94687
    d = z3 - x3
    pair = Explanation(causes=("x3", "z3"), estimates=(d, -d), explained=1.0, body=3,
                       model_values=(x3, z3), labels=("x3", "z3"),
                       kinds=("parameter", "parameter"), units=("m", "m"))
    assert "swapped" in pair.describe()
    # 6 % of the change left over in the sum, or the fit 0.05 m (7 % of it) off the other's
    # value: past the 5 % a swap allows
    assert "swapped" not in dataclasses.replace(pair, estimates=(d, -0.94 * d)).describe()
    assert "swapped" not in dataclasses.replace(pair, estimates=(d + 0.05, -d - 0.05)).describe()
    odd = dataclasses.replace(pair, causes=("x3", "gyroscopic"), labels=("x3", "gyroscopic"),
                              kinds=("parameter", "structural"), units=("m", ""),
                              model_values=(x3, "with"))
    assert "swapped" not in odd.describe()            # no unit to compare: never, no error
    e = Explanation(causes=("I3xx",), estimates=(0.1,), explained=0.5, body=3,
                    model_values=(20.213,), candidates=(("I3xx", "I3xx", 0.5, ("Qv", "M")),))
    assert e.to_dict()["runner_up"] is None and e.to_dict()["localized"] is False
    assert e.best_candidates() == "I3xx 50.0% (leaves Qv, M unexplained)"


def test_best_candidates_shows_three_by_default():
    e = dataclasses.replace(NEITHER, candidates=NEITHER.candidates + (("g", "g", 0.05, ()),))
    assert e.best_candidates().count("%") == 3 and "g 5.0%" not in e.best_candidates()
    assert e.best_candidates(4).endswith("g 5.0%")


def test_the_share_a_removal_takes_away_worked_by_hand():
    """_removal: r = (3, 4), |r|^2 = 25; removing (3, 0) leaves (0, 4): 1 - 16/25 = 0.36 of the
    whole, and per block: the first block (3) wholly, the second (4) not at all, so the least
    is 0; removing more than r (6, 0) leaves (-3, 4): 0 of the whole, clipped at 0, and the
    first block 1 - 9/9 = 0; nothing to remove is (0, -inf); no differing block gives 1."""
    from comparisons.judgments.diagnose import _removal, _share
    r = np.array([3.0, 4.0])
    blocks = [((0, 1), "M"), ((1, 2), "Qv")]
    assert _removal(r, np.array([3.0, 0.0]), blocks) == pytest.approx((0.36, 0.0))
    assert _removal(r, np.array([3.0, 0.0]), blocks[:1]) == pytest.approx((0.36, 1.0))
    assert _removal(r, np.array([6.0, 0.0]), blocks[:1]) == pytest.approx((0.0, 0.0))
    assert _removal(r, np.array([-3.0, 8.0]), []) == (0.0, 1.0)   # worse than nothing: 0
    assert _removal(r, None, blocks) == (0.0, -np.inf)
    # _share: (2 x b - x^2 G) / rr: x = b/G is the least-squares fit, b^2/(G rr) removed
    coef, b, G = np.array([0.5, 2.0, 1.0]), np.array([2.0, 2.0, 1.0]), np.array([4.0, 1.0, 0.0])
    ok = np.array([True, True, False])
    assert np.allclose(_share(coef, b, G, 4.0, ok), [0.25, 1.0, 0.0])       # 1/4, (8-4)/4
    assert np.allclose(_share(coef, b, G, 4.0, ok, clip=False)[:2], [0.25, 1.0])
    assert _share(coef, b, G, 4.0, ok, clip=False)[2] == -np.inf             # not ok: -inf
    # clipped to [0, 1] unless asked not to: (2*3*1 - 9*1)/4 = -0.75, (2*2*3 - 4*1)/4 = 2
    coef, b, G, ok = np.array([3.0, 2.0]), np.array([1.0, 3.0]), np.array([1.0, 1.0]), np.ones(2, bool)
    assert np.array_equal(_share(coef, b, G, 4.0, ok), [0.0, 1.0])
    assert np.allclose(_share(coef, b, G, 4.0, ok, clip=False), [-0.75, 2.0])
