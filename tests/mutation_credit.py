"""Credit a shared fixture's work to every test that uses it, while mutmut collects its stats.

mutmut runs each mutant only against the tests that called the mutated function in its stats
run, and it learns those by crediting every function called since the last test's teardown to
the test being torn down. A module or session fixture is set up once, inside the first test
that asks for it, so the functions it calls are credited to that one test: a mutant there runs
against it alone, and a test further down that reads the fixture's result and would fail is
never run ("survived", until ``tests/mutation.py``'s rerun on the whole selection, at ~10 s a
mutant). This plugin records, for each fixture set up, the functions its setup called, and adds
them to every test that uses the fixture before mutmut credits that test.

It is registered by ``tests/conftest.py`` only in mutmut's stats run (``MUTANT_UNDER_TEST`` is
``"stats"``, mutmut's own protocol), so the suite's ordinary runs never load it.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

__all__ = ["FixtureCredit"]


class FixtureCredit:
    """pytest plugin: the functions each fixture's setup called, given to the tests using it."""

    def __init__(self, stats: Callable[[], set[str]]) -> None:
        #: gives the set of functions called since the last teardown (mutmut's own)
        self._stats_of = stats
        #: fixture definition (by identity) -> the functions its setup called
        self._credit: dict[int, set[str]] = {}

    @property
    def _stats(self) -> set[str]:
        return self._stats_of()

    @pytest.hookimpl(hookwrapper=True)
    def pytest_fixture_setup(self, fixturedef, request):
        # a fixture's own dependencies are set up before this hook (pytest resolves them
        # first), so what is called inside is the fixture's own work alone
        before = set(self._stats)
        self._stats.clear()
        try:
            yield
        finally:
            self._credit.setdefault(id(fixturedef), set()).update(self._stats)
            self._stats.update(before)

    @pytest.hookimpl(tryfirst=True)
    def pytest_runtest_teardown(self, item, nextitem):
        info = getattr(item, "_fixtureinfo", None)
        if info is None:
            return
        for name in info.names_closure:
            for fixturedef in info.name2fixturedefs.get(name, ()):
                self._stats.update(self._credit.get(id(fixturedef), ()))


def register(config) -> None:
    """Register `FixtureCredit` on ``config``."""
    from mutmut.state import state
    config.pluginmanager.register(FixtureCredit(lambda: state()._stats), "bicycle-xval-fixture-credit")
