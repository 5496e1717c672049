"""The summary table (comparisons/judgments/summary.py) against its docstring's contract: one
row per (quantity, engine pair), the worst error over the scenarios, the tolerance(s), the
verdict (pass, FAIL (k of n), reported) with its reason, and where the worst case is. Every
expected value below is written out by hand from the rows given. Pure, a few ms."""

from comparisons.judgments.rows import Comparison
from comparisons.judgments.summary import summary_table


def _by_key(rows):
    return {(r["quantity"], r["engines"]): r for r in rows}


def test_one_row_per_quantity_and_pair_in_first_seen_order_with_its_count():
    comps = [
        {"quantity": "M", "scenario": "a", "engines": ["r", "p"], "max_error": 1e-15,
         "tolerance": 1e-12, "passed": True},
        {"quantity": "D", "scenario": "a", "engines": ["r", "p"], "max_error": 1e-15,
         "tolerance": 1e-12, "passed": True},
        {"quantity": "M", "scenario": "b", "engines": ["r", "p"], "max_error": 3e-15,
         "tolerance": 1e-12, "passed": True},
        {"quantity": "M", "scenario": "a", "engines": ["r", "e"], "max_error": 2e-15,
         "tolerance": 1e-12, "passed": True},
    ]
    rows = summary_table(comps)
    assert [(r["quantity"], r["engines"], r["n"]) for r in rows] == [
        ("M", "r vs p", 2), ("D", "r vs p", 1), ("M", "r vs e", 1)]
    # the exact row: every key the report reads, nothing else
    assert rows[0] == {"quantity": "M", "engines": "r vs p", "n": 2, "max_error": 3e-15,
                       "tolerance": 1e-12, "verdict": "pass", "reason": "",
                       "worst": "b: -"}


def test_the_worst_row_names_its_scenario_and_place_and_none_errors_are_skipped():
    comps = [
        {"quantity": "q", "scenario": "s1", "engines": ["r", "x"], "max_error": None,
         "tolerance": 1e-6, "passed": True, "localized_to": "nowhere"},
        {"quantity": "q", "scenario": "s2", "engines": ["r", "x"], "max_error": 5e-7,
         "tolerance": 1e-6, "passed": True, "localized_to": "theta at 1.00 s"},
        {"quantity": "q", "scenario": "s3", "engines": ["r", "x"], "max_error": 2e-7,
         "tolerance": 1e-6, "passed": True, "localized_to": "gamma at 0.10 s"},
    ]
    (row,) = summary_table(comps)
    assert row["max_error"] == 5e-7
    assert row["worst"] == "s2: theta at 1.00 s"
    # a group with no error at all: max_error None, the worst is the first row
    (row,) = summary_table([comps[0]])
    assert row["max_error"] is None and row["worst"] == "s1: nowhere"
    # a Comparison row reads the same way (localized_to defaults to '-')
    (row,) = summary_table([Comparison("q", "s9", "m", ("r", "x"), 1.0, 2.0, True)])
    assert row["worst"] == "s9: -" and row["engines"] == "r vs x"


def test_tolerances_one_none_or_a_range():
    def row(tol, err=1e-9):
        return {"quantity": "q", "scenario": "s", "engines": ["a", "b"], "max_error": err,
                "tolerance": tol, "passed": None}
    assert summary_table([row(1e-6), row(1e-6)])[0]["tolerance"] == 1e-6
    assert summary_table([row(None), row(None)])[0]["tolerance"] is None
    # two different tolerances: smallest..largest, written as the report writes them
    assert summary_table([row(1e-3), row(None), row(1e-8), row(1e-5)])[0]["tolerance"] \
        == "1e-08..1e-03"


def test_failures_are_counted_over_the_judged_rows_only():
    comps = [
        {"quantity": "q", "scenario": s, "engines": ["a", "b"], "max_error": e,
         "tolerance": 1e-6, "passed": p}
        for s, e, p in (("s1", 2e-6, False), ("s2", 1e-7, True), ("s3", 3e-6, False),
                        ("s4", 1e-2, None))]
    (row,) = summary_table(comps)
    assert row["verdict"] == "FAIL (2 of 3)" and row["reason"] == ""
    assert row["n"] == 4 and row["max_error"] == 1e-2 and row["worst"] == "s4: -"


def test_a_reported_group_says_who_judges_it():
    base = {"quantity": "trajectory", "engines": ["r", "x"], "max_error": 1e-3,
            "tolerance": None, "passed": None}
    comps = [dict(base, scenario="s1", why="judged by its convergence order"),
             dict(base, scenario="s2", note="reported, not judged: a declared model difference"),
             dict(base, scenario="s3", note="", why="")]
    (row,) = summary_table(comps)
    assert row["verdict"] == "reported"
    # the reasons, prefix removed, sorted: 'a declared...' < 'judged by...'
    assert row["reason"] == "a declared model difference"
    # 'why' is preferred to the note when both are given
    (row,) = summary_table([dict(base, scenario="s", why="judged elsewhere",
                                 note="reported, not judged: aaa")])
    assert row["reason"] == "judged elsewhere"
    # nothing said: no reason
    (row,) = summary_table([dict(base, scenario="s")])
    assert (row["verdict"], row["reason"]) == ("reported", "")


def test_a_pass_that_is_a_declared_difference_says_so_but_not_for_physics_outcomes():
    base = {"quantity": "q", "engines": ["r", "x"], "max_error": 1e-3, "tolerance": 1e-2,
            "passed": True}
    comps = [dict(base, scenario="s1", expected="model difference"),
             dict(base, scenario="s2", expected="converges"),
             dict(base, scenario="s3", expected="weave grows"),
             dict(base, scenario="s4", expected="slow capsize"),
             dict(base, scenario="s5", expected=None),
             dict(base, scenario="s6", expected="another difference"),
             dict(base, scenario="s7")]
    (row,) = summary_table(comps)
    assert row["verdict"] == "pass"
    assert row["reason"] == ("expected 'another difference, model difference': a declared "
                             "model difference")
    # only outcomes the physics predicts: a plain pass
    (row,) = summary_table(comps[1:5])
    assert (row["verdict"], row["reason"]) == ("pass", "")
