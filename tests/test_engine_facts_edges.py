"""Two declarations of engines/facts.py an engine writes by hand (issue 24): a fixed-step
integrator's runs and an option study's reference value. Expected values are the documented
contract (their docstrings; docs/engines.md). Planted bugs are named in each test."""

import pytest

from engines.facts import FixedStep, OptionStudy


def test_fixed_step_runs_carry_the_step_the_variant_and_the_extras():
    """Each variant's label and options: the variant's own, the step at its default, and the
    caller's extras; only the variants asked for when given. Planted: the extras dropped,
    the variants asked for ignored."""
    fs = FixedStep(option="dt", step=5e-4, variants=(("", ()), ("tree", (("build", "tree"),))))
    assert fs.runs("exu", tol=1e-9) == [("exu", {"dt": 5e-4, "tol": 1e-9}),
                                        ("exu-tree", {"build": "tree", "dt": 5e-4, "tol": 1e-9})]
    assert fs.runs("exu", variants=("tree",), sep="/") == [("exu/tree", {"build": "tree",
                                                                         "dt": 5e-4})]


def test_an_option_study_whose_reference_is_not_among_its_values_is_refused_in_words():
    """Planted: the message lost."""
    with pytest.raises(ValueError) as e:
        OptionStudy(option="stiffness", quantity="contact stiffness", unit="N/m",
                    values=(1e4, 1e5), reference_value=1e6, difference="softer contact")
    assert str(e.value) == ("option study 'stiffness': reference_value 1000000.0 must be one of "
                            "values (10000.0, 100000.0)")
