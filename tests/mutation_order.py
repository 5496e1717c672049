"""Run a mutant's tests cheapest file first, so the first test that fails it comes sooner.

mutmut runs each mutant with ``pytest -x`` on the tests credited to the mutated function, in
no particular order (a set's). When a slow file comes first (a Dask sweep, an engine's own
build), a mutant that any quick test would kill waits for it, and a mutant that makes the
slow file hang without using CPU is never stopped by mutmut's CPU-time limit (seen: 2 of
``engines/batching.py``'s first 8 mutants took minutes each, at 7 % CPU).

Two halves, chosen by ``MUTANT_UNDER_TEST`` (mutmut's own protocol):

- in mutmut's stats run (``"stats"``), `TestSeconds` writes each test's measured seconds
  (setup, call and teardown: a file's fixtures included) to ``mutmut-test-seconds.json``
  beside mutmut's own stats;
- in a mutant's run (a mutant's name), `CheapFilesFirst` reads them and orders the collected
  tests by file, the file whose tests took fewest seconds in all first, keeping each file's
  tests together and in their own order (so a module-scoped fixture is still set up once).

Only the order changes: the same tests run, and a surviving mutant still runs all of them.
"""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path

import pytest

__all__ = ["SECONDS_FILE", "CheapFilesFirst", "TestSeconds", "file_order"]

#: written in the stats run's working folder (mutmut's ``mutants/``), read from the same folder
SECONDS_FILE = "mutmut-test-seconds.json"


def file_order(nodeids: list[str], seconds: dict[str, float]) -> list[str]:
    """``nodeids`` grouped by file, the files in increasing total ``seconds`` (a file with a
    test not measured goes last, as does one never measured), each file's ids in their given
    order; ties keep the given order of the files."""
    by_file: dict[str, list[str]] = defaultdict(list)
    for nid in nodeids:
        by_file[_strip(nid).split("::", 1)[0]].append(nid)
    measured = {_strip(k): v for k, v in seconds.items()}

    def cost(f: str) -> float:
        times = [measured.get(_strip(i)) for i in by_file[f]]
        return float("inf") if None in times else sum(times)

    files = sorted(by_file, key=cost)          # sorted() is stable: ties keep the given order
    return [nid for f in files for nid in by_file[f]]


def _strip(nodeid: str) -> str:
    return nodeid.removeprefix("mutants/")


class TestSeconds:
    """pytest plugin (stats run): each test's seconds over its three phases, written at the end."""

    __test__ = False                           # not a test class, despite its name

    def __init__(self, path: Path) -> None:
        self._path = path
        self._seconds: dict[str, float] = defaultdict(float)

    def pytest_runtest_logreport(self, report):
        self._seconds[_strip(report.nodeid)] += report.duration

    def pytest_sessionfinish(self, session):
        tmp = self._path.with_name(self._path.name + ".tmp")
        tmp.write_text(json.dumps(dict(self._seconds), indent=0, sort_keys=True), "utf-8")
        tmp.replace(self._path)


class CheapFilesFirst:
    """pytest plugin (a mutant's run): the collected tests in `file_order`."""

    def __init__(self, seconds: dict[str, float]) -> None:
        self._seconds = seconds

    @pytest.hookimpl(trylast=True)
    def pytest_collection_modifyitems(self, session, config, items):
        where = {item.nodeid: item for item in items}
        items[:] = [where[nid] for nid in file_order([i.nodeid for i in items], self._seconds)]


def register(config, mutant: str, folder: Path = Path(".")) -> None:
    """In the stats run, record the seconds; in a mutant's run, order by them (when the stats
    run wrote them: a run without them keeps pytest's order)."""
    path = folder / SECONDS_FILE
    if mutant == "stats":
        config.pluginmanager.register(TestSeconds(path), "bicycle-xval-test-seconds")
    elif mutant != "fail" and path.is_file():
        seconds = json.loads(path.read_text("utf-8"))
        config.pluginmanager.register(CheapFilesFirst(seconds), "bicycle-xval-cheap-files-first")
