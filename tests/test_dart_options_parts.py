"""Parts of the settings of a run on DART's contact (engines/dart/options.py), issue 24: the
option names `RunSettings.field_names` gives the run (`engines.dart.run` refuses any other
option and lists these in its message). Expected values come from RunSettings' docstring,
which documents the six options in order, and from DART-free construction of the settings.
Planted bugs each test was seen failing on are named in it."""

import re

from engines.dart.options import DEFAULTS, RunSettings

#: the options RunSettings' docstring documents, in its order
DOCUMENTED = ("timestep", "collision_detector", "friction", "solver", "wheel_half_width",
              "split_impulse")


def test_the_option_names_are_the_documented_settings_in_order():
    """field_names() is the tuple of the six documented options, in the docstring's order
    (the order the unknown-option message lists them in), each one a keyword the settings
    accept and round-trip through as_dict. Planted: tuple(None) (a TypeError), the fields of
    None instead of the class (a TypeError)."""
    names = RunSettings.field_names()
    assert names == DOCUMENTED
    assert tuple(re.findall(r"``(\w+)``", RunSettings.__doc__)) == DOCUMENTED
    assert RunSettings(**{n: getattr(DEFAULTS, n) for n in names}) == DEFAULTS
    assert tuple(DEFAULTS.as_dict()) == names
