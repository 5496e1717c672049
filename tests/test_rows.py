"""The comparison row (comparisons/judgments/rows.py) against its contract: the docstring's
and summary.json's (docs/report.md, "comparisons"): nine common fields in that order, a
row reads like a mapping, cannot be changed, pickles, and becomes a plain dict at the writer.
The expected values are written out from that contract, not taken from the code. Pure, ~10 ms."""

import pickle

import pytest

from comparisons.judgments.rows import COMMON, Comparison, FrozenMapping, comparison_rows

ORDER = ("quantity", "scenario", "model", "engines", "max_error", "tolerance", "passed",
         "localized_to", "note")


def _row(**extra):
    return Comparison("q_err", "s1", "thesis", ["reference", "pinocchio"], 1e-9, 1e-6, True,
                      extra=extra)


def test_the_common_fields_are_summary_jsons_in_its_order():
    assert COMMON == ORDER
    r = _row(horizon=2.5)
    assert list(r) == [*ORDER, "horizon"]
    assert list(r.as_dict()) == [*ORDER, "horizon"]
    assert len(r) == 10


def test_a_row_reads_like_the_dict_it_becomes():
    r = _row(horizon=2.5)
    d = r.as_dict()
    assert d == {"quantity": "q_err", "scenario": "s1", "model": "thesis",
                 "engines": ["reference", "pinocchio"], "max_error": 1e-9, "tolerance": 1e-6,
                 "passed": True, "localized_to": "-", "note": "", "horizon": 2.5}
    assert type(d["engines"]) is list and r.engines == ("reference", "pinocchio")
    assert r["engines"] == ["reference", "pinocchio"] and r["horizon"] == 2.5
    assert r["passed"] is True and r.get("why") is None
    with pytest.raises(KeyError):
        r["why"]
    assert r == d and r == Comparison.of(d) and r != _row(horizon=3.0)
    assert r.__eq__(3) is NotImplemented


def test_of_fills_the_absent_common_fields_and_keeps_the_rest_as_extra():
    r = Comparison.of({"quantity": "x", "localized_to": None, "note": None, "order": 2.0})
    assert (r.scenario, r.model, r.engines) == ("-", "-", ())
    assert (r.max_error, r.tolerance, r.passed) == (None, None, None)
    assert (r.localized_to, r.note) == ("-", "")
    assert dict(r.extra) == {"order": 2.0}
    assert Comparison.of(r) is r
    assert comparison_rows([{"quantity": "x"}, r])[1] is r
    assert isinstance(comparison_rows([{"quantity": "x"}])[0], Comparison)


def test_a_row_cannot_be_changed_only_replaced():
    r = _row(horizon=2.5)
    for change in (lambda e: e.__setitem__("horizon", 1), lambda e: e.__delitem__("horizon"),
                   lambda e: e.update(horizon=1), lambda e: e.pop("horizon"),
                   lambda e: e.popitem(), lambda e: e.clear(),
                   lambda e: e.setdefault("why", 1)):
        with pytest.raises(TypeError, match="cannot be changed"):
            change(r.extra)
    assert dict(r.extra) == {"horizon": 2.5}
    s = r.replace(passed=False, horizon=3.0, why="late")
    assert (s.passed, s["horizon"], s["why"]) == (False, 3.0, "late")
    assert set(s.extra) == {"horizon", "why"}
    assert (r.passed, r["horizon"]) == (True, 2.5)


def test_rows_pickle_and_hash_by_what_they_compare():
    r = _row(horizon=2.5)
    back = pickle.loads(pickle.dumps(r))
    assert back == r and isinstance(back.extra, FrozenMapping)
    with pytest.raises(TypeError):
        back.extra["horizon"] = 1
    assert hash(r) == hash(_row(horizon=9.0))
    assert hash(r) != hash(r.replace(model="benchmark"))
    # extra holds lists (series, engine names): a row's mapping must hash all the same
    assert hash(FrozenMapping(a=[1.0, 2.0])) == hash(FrozenMapping(a=[3.0]))


def test_bad_rows_are_refused_and_passed_is_a_bool():
    with pytest.raises(ValueError, match="quantity"):
        Comparison("", "s", "m", (), None, None, None)
    with pytest.raises(ValueError, match="quantity"):
        Comparison(3, "s", "m", (), None, None, None)
    with pytest.raises(ValueError, match=r"\['passed'\]"):
        _row(passed=False)
    import numpy as np
    r = Comparison("q", "s", "m", (), 1.0, 2.0, np.bool_(True))
    assert r.passed is True
    assert Comparison("q", "s", "m", (1,), 1.0, 2.0, None).passed is None
    assert Comparison("q", "s", "m", (1,), 1.0, 2.0, None).engines == ("1",)
