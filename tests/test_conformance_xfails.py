"""Expected failures an engine declares itself (`conformance_xfails`), as the plugin applies
them: the pattern language (only ``*`` is special: check ids hold brackets, which shell-style
matching would read as character sets) and ``{engine}``, the engine's label in the ids."""

from types import SimpleNamespace

import pytest

from comparisons.conformance.plugin import Candidate, declared_reason, declared_xfails


class _Declares:
    conformance_xfails = {
        "test_trajectory_to_the_meaningful_horizon[{engine}-*-stability-psid5]": "lifts off",
    }


def _item(name: str, spec: str = "acme"):
    cand = Candidate(spec, "thesis-disc", engine=_Declares())
    return SimpleNamespace(name=name, callspec=SimpleNamespace(params={"candidate": cand}))


@pytest.mark.parametrize("name, expected", [
    ("test_trajectory_to_the_meaningful_horizon[acme-thesis-disc-stability-psid5]", True),
    ("test_trajectory_to_the_meaningful_horizon[acme-benchmark-stability-psid5]", True),
    ("test_trajectory_to_the_meaningful_horizon[acme-thesis-disc-stability-psid10]", False),
    ("test_trajectory_to_the_meaningful_horizon[other-thesis-disc-stability-psid5]", False),
    ("test_term_sweep[acme-thesis-disc-mass_matrix]", False),
])
def test_declared_pattern_matches_exactly_the_named_checks(name, expected):
    reason = declared_reason(_item(name))
    assert (reason is not None) == expected
    if expected:
        assert reason == "declared by acme: lifts off"


def test_an_item_without_a_candidate_is_left_alone():
    assert declared_reason(SimpleNamespace(name="test_x", callspec=SimpleNamespace(params={}))) is None
    assert declared_reason(SimpleNamespace(name="test_x")) is None


def test_a_declared_file_is_read_like_an_xfails_file(tmp_path):
    f = tmp_path / "x.txt"
    f.write_text("# comment\ntest_a[{engine}-*]  # why\n", encoding="utf-8")
    assert declared_xfails(SimpleNamespace(conformance_xfails=f)) == {"test_a[{engine}-*]": "why"}
    assert declared_xfails(SimpleNamespace()) == {}
