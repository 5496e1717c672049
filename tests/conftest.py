"""Shared pytest configuration: deterministic hypothesis runs, the two named models."""

import pytest
from hypothesis import settings

from reference_model import load_model

settings.register_profile("ci", derandomize=True, deadline=None, max_examples=50)
settings.load_profile("ci")


@pytest.fixture(scope="session")
def thesis():
    """The thesis model (thesis front contact), shared by every test module."""
    return load_model("thesis")


@pytest.fixture(scope="session")
def disc():
    """The thesis parameters with the true disc front contact."""
    return load_model("thesis-disc")
