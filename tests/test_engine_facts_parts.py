"""Two small parts of an engine's declared facts (engines/facts.py) that no fast test reached:
a declared option set, (name, value) pairs, becomes the keyword arguments it spells; and a
run setup labels its runs by the engine's name, or ``name-suffix`` when it has a suffix
(`RunSetup`'s docstring, and how docs/engines.md's `run_setups` appear in the report). Each
test names the planted bugs (mutmut's not-reached mutants) it fails on."""

from __future__ import annotations

from engines.facts import RunSetup, engine_facts, options_dict


def test_an_option_set_is_the_keyword_arguments_it_spells():
    """Planted: the pairs dropped (dict(None) raises)."""
    assert options_dict((("step", 0.001), ("integrator", "rk4"))) == {"step": 0.001,
                                                                     "integrator": "rk4"}
    assert options_dict(()) == {}


def test_a_run_setup_is_labelled_by_the_engine_or_the_engine_and_its_suffix():
    """Planted: the test inverted (a suffix-less setup labelled 'name-'), the label's
    separator changed."""
    facts = engine_facts("kane")
    assert facts.setup_label(RunSetup()) == "kane"
    assert facts.setup_label(RunSetup(suffix="rk4")) == "kane-rk4"
