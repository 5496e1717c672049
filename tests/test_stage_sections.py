"""What a stage's section says, from judgments built by hand: the rows summary.json carries
(docs/report.md, "comparisons": the common keys in order, then a kind's own), the tables'
headers and verdict words a reader and a script rely on, and the numbers in each cell, every
one derived here from the hand-built inputs. Report prose (its wording) is not checked: only
what a caller reads by key or a reader reads as a verdict or a number."""

from __future__ import annotations

import math

import pytest

from comparisons.judgments.linear_check import LinearCheck, MatrixCheck, SpeedCheck
from comparisons.judgments.rows import COMMON
from comparisons.stages.linear_check import ENGINES, linear_check_section
from comparisons.stages.results import Table, Text


def _tables(sec):
    return [b for b in sec.blocks if isinstance(b, Table)]


def _texts(sec):
    return [b.text for b in sec.blocks if isinstance(b, Text)]


# -- the linear check's section (comparisons/stages/linear_check.py) ------------------------

def test_a_model_without_counterpart_gets_one_reported_row_and_says_why():
    check = LinearCheck("mine", "no benchmark counterpart: the fork-axis contact", "", (0.0, 10.0))
    sec = linear_check_section(check)
    assert sec.title == "Linearization of mine against the benchmark's closed form"
    assert _texts(sec) == ["Not applicable: no benchmark counterpart: the fork-axis contact."]
    assert not _tables(sec)
    (row,) = sec.comparisons
    assert row.as_dict() == {
        "quantity": "linearization vs closed form", "scenario": "mine, upright straight running",
        "model": "mine", "engines": ["linearize", "closed form (Meijaard 2007)"],
        "max_error": None, "tolerance": None, "passed": None, "localized_to": "-",
        "note": "not applicable: no benchmark counterpart: the fork-axis contact"}
    assert list(row.as_dict()) == list(COMMON)


CHECK = LinearCheck(
    "bike", "", "bike has drag", (0.5, 9.0),
    matrices=(MatrixCheck("M", 2.0e-16, 1e-12, "M[phi, delta]"),
              MatrixCheck("K2", 3.0e-9, 1e-12, "K2[delta, delta]")),
    speeds=(SpeedCheck("weave", 4.292382536341, 4.292382536345, 1e-9),   # 4e-12 apart: pass
            SpeedCheck("capsize", 6.0, None, 1e-9),                      # one side only: FAIL
            SpeedCheck("other", None, None, 1e-9)))                      # neither: agreement


def test_the_matrix_table_rows_and_their_verdicts():
    sec = linear_check_section(CHECK)
    matrices, speeds = _tables(sec)
    assert matrices.header == ("matrix", "max relative difference", "tolerance", "verdict",
                               "worst entry")
    assert matrices.rows == (("M", "2.0e-16", "1e-12", "pass", "M[phi, delta]"),
                             ("K2", "3.0e-09", "1e-12", "FAIL", "K2[delta, delta]"))
    rows = [r.as_dict() for r in sec.comparisons]
    assert [r["quantity"] for r in rows[:2]] == ["linearization vs closed form: M",
                                                 "linearization vs closed form: K2"]
    assert [r["passed"] for r in rows] == [True, False, True, False, True]
    assert [r["max_error"] for r in rows[:2]] == [2.0e-16, 3.0e-9]
    assert [r["tolerance"] for r in rows[:2]] == [1e-12, 1e-12]
    assert [r["localized_to"] for r in rows[:2]] == ["M[phi, delta]", "K2[delta, delta]"]
    for r in rows:
        assert list(r)[:len(COMMON)] == list(COMMON)
        assert r["engines"] == ENGINES
        assert r["model"] == "bike" and r["scenario"] == "bike, upright straight running"
    assert rows[0]["note"] == "max |difference| / max |closed form| over the matrix"
    # the drag note is part of the section's text
    assert "bike has drag." in _texts(sec)[0]
    assert "0.5-9 m/s" in _texts(sec)[0]


def test_the_speed_table_rows_say_none_where_a_side_found_no_speed():
    sec = linear_check_section(CHECK)
    speeds = _tables(sec)[1]
    assert speeds.header == ("critical speed", "closed form [m/s]", "linearization [m/s]",
                             "difference [m/s]", "tolerance", "verdict")
    assert speeds.rows == (
        ("weave speed", "4.292382536341", "4.292382536345", f"{4e-12:.1e}", "1e-09", "pass"),
        ("capsize speed", "6.000000000000", "none", "-", "1e-09", "FAIL"),
        ("other speed", "none", "none", "-", "1e-09", "pass"))
    weave, capsize, other = (r.as_dict() for r in sec.comparisons[2:])
    assert weave["quantity"] == "linearization vs closed form: weave speed"
    assert math.isclose(weave["max_error"], 4e-12, rel_tol=1e-3)
    assert (weave["closed_form"], weave["linearization"]) == (4.292382536341, 4.292382536345)
    assert weave["localized_to"] == ("closed form 4.292382536341 m/s, linearization "
                                     "4.292382536345 m/s")
    assert capsize["max_error"] is None and capsize["linearization"] is None
    assert capsize["localized_to"] == "closed form 6.000000000000 m/s, linearization none m/s"
    assert other["localized_to"] == "none in 0.5-9 m/s on both"
    assert weave["note"] == "in 0.5-9 m/s; none on both counts as agreement"


@pytest.mark.parametrize("note, ends", [("", "m/s, the closed form's by its own root finding "
                                                "on its eigenvalues."),
                                        ("checked with cv = 0", ". checked with cv = 0.")])
def test_the_text_ends_with_the_note_only_when_there_is_one(note, ends):
    check = LinearCheck("bike", "", note, (0.0, 10.0))
    assert _texts(linear_check_section(check))[0].endswith(ends)


def test_the_stage_asks_one_task_per_model_and_assembles_failures_as_failing_rows():
    from types import SimpleNamespace

    from comparisons.stages.linear_check import LinearCheckStage, linear_check
    from comparisons.stages.pool import TaskResult
    from comparisons.stages.stage import Plan

    models = (SimpleNamespace(spec="a.toml", name="A"), SimpleNamespace(spec="b.toml", name="B"))
    plan = Plan(SimpleNamespace(models=models, tolerances="TOLS"), (), {})
    tasks = LinearCheckStage().tasks(plan)
    assert [(t.key, t.func, t.args) for t in tasks] == [("a.toml", linear_check, ("TOLS", "a.toml")),
                                                        ("b.toml", linear_check, ("TOLS", "b.toml"))]
    assert [t.label for t in tasks] == ["A: linearization vs the closed form",
                                        "B: linearization vs the closed form"]
    ok = linear_check_section(CHECK)
    out = LinearCheckStage().assemble(plan, {"a.toml": TaskResult("a.toml", ok, 0.1),
                                             "b.toml": TaskResult("b.toml", None, 0.1, "boom")})
    first, second = out.sections
    assert first is ok
    assert second.title == "B: linearization against the closed form"
    assert [r["passed"] for r in second.comparisons] == [False]
    assert second.comparisons[0]["localized_to"] == "boom"
    assert (LinearCheckStage.name, LinearCheckStage.section) == ("linear-check", None)
