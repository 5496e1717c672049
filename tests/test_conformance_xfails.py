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


class _Config:
    """What `pytest_configure` asks of pytest's config: the plugin's options, by dest."""

    def __init__(self, **options):
        self.options = {"bx_engines": ["pinocchio"], "bx_models": ["thesis"], "bx_options": [],
                        "bx_xfails": None, "bx_tolerances": None, "bx_depth": "full", **options}

    def getoption(self, name):
        return self.options[name]

    def addinivalue_line(self, *args):
        pass


def test_the_plugin_reads_its_tolerances_option_once(tmp_path, failing_tolerances):
    """``--tolerances FILE`` is read in `pytest_configure` into the session's value, which the
    checks judge by (the ``tolerances`` fixture); without it the packaged file; a file lacking a
    table is a usage error naming it. In process: no pytest subprocess (~6 s each)."""
    from comparisons.conformance.plugin import pytest_configure
    from comparisons.judgments.terms import compare_term, random_states
    from comparisons.judgments.tolerances import load_tolerances
    from engines import load_engine
    from reference_model import load_model
    failing = failing_tolerances
    config = _Config(bx_tolerances=str(failing))
    pytest_configure(config)
    tols = config._bx_conformance.tolerances
    assert tols == load_tolerances(failing) and tols["mass_matrix"].tolerance == 1e-300
    model = load_model("thesis")      # Pinocchio's M differs from the reference's by round-off
    res = compare_term("mass_matrix", load_engine("reference", model),
                       load_engine("pinocchio", model), random_states(4), tols["mass_matrix"])
    assert not res.passed
    default = _Config()
    pytest_configure(default)
    assert default._bx_conformance.tolerances == load_tolerances()
    few = tmp_path / "few.toml"
    few.write_text('[mass_matrix]\ntolerance = 1e-12\nscale = "max_abs"\nreason = "r"\n')
    with pytest.raises(pytest.UsageError, match=r"--tolerances: .*lacks \[inverse_dynamics\]"):
        pytest_configure(_Config(bx_tolerances=str(few)))
