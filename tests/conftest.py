"""Shared pytest configuration: deterministic hypothesis runs, the named models, a general
one, and the one quick report the report and CLI tests read (run once per session: a report run
is the suite's most expensive object)."""

import json

import pytest
from hypothesis import settings

from reference_model import Model, load_model

settings.register_profile("ci", derandomize=True, deadline=None, max_examples=50)
settings.load_profile("ci")

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


@pytest.fixture(scope="session")
def quick_report(tmp_path_factory):
    """``bicycle-xval run --quick`` once: (output folder, exit status, summary.json)."""
    from comparisons.cli import main
    out = tmp_path_factory.mktemp("quick-report")
    code = main(["run", "--quick", "--out", str(out)])
    return out, code, json.loads((out / "summary.json").read_text(encoding="utf-8"))


@pytest.fixture(scope="session")
def general(thesis):
    """The thesis bicycle made general (GENERAL_CHANGES), thesis front contact."""
    return Model(thesis.params.replace(name="general", **GENERAL_CHANGES))


@pytest.fixture(scope="session")
def general_disc(general):
    """The general bicycle with the disc front contact."""
    return general.with_params(general.params.with_contact("disc"))
