"""The report's package line (comparisons/stages/pipeline.py, `_versions`): a module an engine
declares (``REQUIRES``) is reported with the version of the distribution that installs it. Seen
failing: the example report said "pydrake not installed" while Drake had run its sections (the
module ``pydrake`` comes with the distribution ``drake``)."""

from importlib import metadata

import pytest

from comparisons.stages.pipeline import _versions


def test_a_module_installed_by_a_distribution_of_another_name_gets_that_version():
    pytest.importorskip("pydrake")
    assert _versions(("pydrake",))["pydrake"] == metadata.version("drake")


def test_a_module_nobody_installs_is_not_installed_and_the_core_is_listed():
    got = _versions(("no_such_module_here",))
    assert got["no_such_module_here"] == "not installed"
    assert got["numpy"] == metadata.version("numpy")
    assert list(got)[:6] == ["python", "numpy", "scipy", "sympy", "pandas", "matplotlib"]
