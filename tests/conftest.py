"""Shared pytest configuration: deterministic hypothesis runs, the named models, a general
one, and the one quick report the report and CLI tests read (run once per session: a report run
is the suite's most expensive object)."""

import json

import pytest
from hypothesis import settings

from reference_model import Model, load_model

settings.register_profile("ci", derandomize=True, deadline=None, max_examples=50)
settings.load_profile("ci")


def pytest_configure(config):
    """Under mutmut only: in its stats run, credit each shared fixture's work to every test
    using it (tests/mutation_credit.py: otherwise its first test alone gets it) and record each
    test's seconds; in a mutant's run, run the cheapest test files first
    (tests/mutation_order.py), in a process group of its own with a wall-clock deadline
    (tests/mutation_guard.py)."""
    import os
    mutant = os.environ.get("MUTANT_UNDER_TEST")
    if not mutant:
        return
    if mutant == "stats":
        from mutation_credit import register
        register(config)
    elif mutant != "fail":   # a mutant's run: its own process group, a wall-clock deadline
        from mutation_guard import register as register_guard
        register_guard(config)
    from mutation_order import register as register_order
    register_order(config, mutant)

# the conformance suite's general bicycle: every inertia entry distinct, unequal wheels, an
# off-axis fork CoM (comparisons/conformance/models.py)
from comparisons.conformance.models import GENERAL_CHANGES  # noqa: E402


@pytest.fixture(scope="session")
def thesis():
    """The thesis model (thesis front contact), shared by every test module."""
    return load_model("thesis")


@pytest.fixture(scope="session")
def disc():
    """The thesis parameters with the true disc front contact."""
    return load_model("thesis-disc")


#: the quick report's engines: the reference, a rigid-body engine with every term (Pinocchio), a
#: fixed-step integrator with two builds (Exudyn), a disc-only engine (Kane) and a soft contact
#: (MuJoCo): one of each kind the report's sections and tests read. Every engine, the later
#: ones included, goes through its own tests, the conformance suite and `make report`; with all
#: nine the quick report took 48 s of make test's 90 s instead of ~17 s.
QUICK_REPORT_ENGINES = ("reference", "pinocchio", "exudyn", "kane", "mujoco")


@pytest.fixture(scope="session")
def quick_report(tmp_path_factory):
    """``bicycle-xval run --quick`` (less the Exudyn-only sections) on `QUICK_REPORT_ENGINES`
    once per test session:
    (output folder, exit status,
    summary.json). Under pytest-xdist the workers share it: the first to need it makes it while
    holding a lock in the session's common temporary folder, the others read it."""
    import fcntl
    import os

    from comparisons.cli import main
    base = tmp_path_factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    out, status = root / "quick-report", root / "quick-report.exit-status"
    with open(root / "quick-report.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not status.exists():
            # the Exudyn-only sections (convergence, energy, disc builds) are tested directly
            # in test_exudyn and test_convergence: not run again here
            # every figure drawn (--quick draws only failing sections' by default): the report
            # tests read them
            status.write_text(str(main(["run", "--quick", "--sections", "terms,benchmark,faults",
                                        "--engines", ",".join(QUICK_REPORT_ENGINES),
                                        "--figures", "all", "--out", str(out)])))
    return out, int(status.read_text()), json.loads((out / "summary.json").read_text(encoding="utf-8"))


def _made_once(tmp_path_factory, name: str, make):
    """``make()``, computed once per test session and pickled for the other pytest-xdist
    workers (the first to need it makes it while holding a lock, as `quick_report` does)."""
    import fcntl
    import os
    import pickle
    base = tmp_path_factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    path = root / f"{name}.pickle"
    with open(root / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not path.exists():
            path.write_bytes(pickle.dumps(make()))
    return pickle.loads(path.read_bytes())


@pytest.fixture(scope="session")
def mujoco_quick_study(tmp_path_factory):
    """The built-in soft-contact engine's quick contact study (`stages.soft_contact`: four
    runs of 0.2 s and one of 0.5 s, ~1 s), shared by the contact tests."""
    from comparisons.stages.soft_contact import contact_study
    return _made_once(tmp_path_factory, "mujoco-quick-study",
                      lambda: contact_study("mujoco", quick=True))


@pytest.fixture(scope="session")
def twin_quick_study(tmp_path_factory):
    """The same for the tests' second soft-contact engine (tests/soft_twin.py, ~0.5 s)."""
    from comparisons.stages.soft_contact import contact_study
    from soft_twin import SPEC
    return _made_once(tmp_path_factory, "twin-quick-study", lambda: contact_study(SPEC, quick=True))


@pytest.fixture(scope="session")
def general(thesis):
    """The thesis bicycle made general (GENERAL_CHANGES), thesis front contact."""
    return Model(thesis.params.replace(name="general", **GENERAL_CHANGES))


@pytest.fixture(scope="session")
def general_disc(general):
    """The general bicycle with the disc front contact."""
    return general.with_params(general.params.with_contact("disc"))


@pytest.fixture(scope="session")
def fast_cc(tmp_path_factory) -> str:
    """A working compiler command: gcc with -O0 appended (the last -O wins). For tests of the
    cache's logic, not of the numbers: a -O0 build takes 0.5 s instead of ~4-8 s at -O2 (the
    compiler is part of the cache key, so these entries never mix with the ordinary ones)."""
    import shutil
    if shutil.which("gcc") is None:
        pytest.fail("these tests need gcc (the C backend is the one under test)")
    path = tmp_path_factory.mktemp("cc") / "fastcc"
    path.write_text('#!/bin/sh\nexec gcc "$@" -O0\n')
    path.chmod(0o755)
    return str(path)


@pytest.fixture(scope="session")
def failing_tolerances(tmp_path_factory):
    """A copy of the packaged tolerance file with every tolerance at 1e-300: any round-off
    difference (~1e-16 between two engines' terms) fails it, so every judged check that is not
    exactly equal fails."""
    import re

    from comparisons.judgments.tolerances import TOLERANCES_FILE
    path = tmp_path_factory.mktemp("tolerances") / "failing.toml"
    path.write_text(re.sub(r"(?m)^tolerance = .*$", "tolerance = 1e-300",
                           TOLERANCES_FILE.read_text()))
    return path
