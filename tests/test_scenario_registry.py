"""The built-in scenarios by name (`reference_model.scenarios.registry`): one scenario per
file of ``reference_model/scenario_data/``, in the order of its ``index.json`` (the order the
report lists them), read once; an unknown name is refused in the one line the CLI prints,
naming every choice, and is still a KeyError for code that catches one."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import reference_model
from reference_model.scenarios import SCENARIOS, UnknownScenarioError, builtin_scenarios, get_scenario

DATA = Path(reference_model.__file__).parent / "scenario_data"
INDEX = json.loads((DATA / "index.json").read_text("utf-8"))


def test_the_built_ins_are_the_files_in_the_order_of_the_index():
    assert sorted(INDEX) == sorted(p.stem for p in DATA.glob("*.toml"))
    assert list(builtin_scenarios()) == INDEX
    assert all(sc.name == name for name, sc in builtin_scenarios().items())


def test_they_are_read_once_and_shared():
    assert builtin_scenarios() is builtin_scenarios()
    assert get_scenario("zigzag") is builtin_scenarios()["zigzag"] is SCENARIOS["zigzag"]


def test_an_unknown_name_is_refused_naming_every_choice():
    with pytest.raises(KeyError) as err:
        get_scenario("zig-zag")
    assert isinstance(err.value, UnknownScenarioError)
    assert str(err.value) == ("unknown scenario 'zig-zag'; choose one of: " + ", ".join(INDEX))


def test_any_other_missing_name_is_pythons_own_attribute_error():
    """The package's lazy SCENARIOS (PEP 562) must leave every other name to Python's rule:
    the message a module without the hook gives (written here as Python words it)."""
    import reference_model.scenarios as pkg
    with pytest.raises(AttributeError) as err:
        pkg.SCENARIO
    assert str(err.value) == "module 'reference_model.scenarios' has no attribute 'SCENARIO'"
    assert not hasattr(pkg, "scenarios_by_name")
