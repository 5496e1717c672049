"""The comparison row's frozen mapping (comparisons/judgments/rows.py, `FrozenMapping`, a row's
``extra``) held to the parts of its contract that tests/test_rows.py leaves open: a refused
change says, in full, that the row cannot be changed and what to do instead (``.replace()``),
and its hash is the hash of its field names (values may be lists, so only the names can be
hashed), so extras with other fields hash apart while equal ones, in any insertion order, hash
alike (Python's data model: equal objects, equal hashes). Each test names the planted bugs
(mutmut's survivors of the module's first measurement) it fails on. Pure, ~10 ms.
"""

from __future__ import annotations

import re

import pytest

from comparisons.judgments.rows import Comparison, FrozenMapping


def test_a_refused_change_says_so_and_points_to_replace_exactly():
    """Every mutating method of a row's extra raises the one sentence of the docstring's
    contract ("cannot be changed after it is made"; `Comparison.replace` makes a new row),
    exactly. Planted: the message wrapped in 'XX' (test_rows.py matches only 'cannot be
    changed')."""
    extra = Comparison("q", "s", "m", (), None, None, None, extra={"horizon": 2.5}).extra
    exact = "^" + re.escape("a comparison row cannot be changed; make a new one with "
                            ".replace()") + "$"
    for change in (lambda e: e.__setitem__("horizon", 1.0), lambda e: e.__delitem__("horizon"),
                   lambda e: e.update(horizon=1.0), lambda e: e.pop("horizon"),
                   lambda e: e.popitem(), lambda e: e.clear(),
                   lambda e: e.setdefault("why", "late")):
        with pytest.raises(TypeError, match=exact):
            change(extra)
    assert extra == {"horizon": 2.5}


def test_extras_hash_by_their_field_names():
    """Equal extras hash alike whatever the order their fields were given in (and whatever
    their values: lists cannot be hashed); extras with different field names hash apart, one
    from each other (a tuple of distinct strings: a collision here has odds of ~2^-64).
    Planted: a constant hash (hash(None)), legal but putting every extra in one bucket."""
    a = FrozenMapping({"horizon": 2.5, "why": [1.0, 2.0]})
    assert hash(a) == hash(FrozenMapping({"why": [3.0], "horizon": 9.0}))
    others = [FrozenMapping(), FrozenMapping(horizon=2.5), FrozenMapping(why="late"),
              FrozenMapping(order=2.0, slip=[0.1]), a]
    assert len({hash(m) for m in others}) == len(others)
