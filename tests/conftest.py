"""Shared pytest configuration: deterministic hypothesis runs, the named models, and a
general one."""

import pytest
from hypothesis import settings

from reference_model import Model, load_model

settings.register_profile("ci", derandomize=True, deadline=None, max_examples=50)
settings.load_profile("ci")

# A bicycle without the thesis's symmetries, so that a key or frame mix-up in any builder
# shows: unequal wheel radii, the fork CoM off the steering axis (dx4, dz4), the front hub not
# at the rear hub's height (za + z5 != 0), and inertia tensors with every entry the
# parametrization has distinct and non-zero (three distinct moments for the wheels, which
# have no product of inertia; four distinct entries, xz included, for frame and fork). Each
# tensor is positive definite and obeys the triangle inequality (the loader checks both):
# wheels 0.100 + 0.125 > 0.205, 0.085 + 0.115 > 0.180; frame and fork keep the thesis's
# principal-moment margins with their xz changed a little.
GENERAL_CHANGES = dict(
    R_rear=0.34, R_front=0.30,
    dx4=0.035, dz4=0.12, z5=-0.45,
    I2xx=0.100, I2yy=0.205, I2zz=0.125,
    I3xx=20.213, I3yy=21.769, I3zz=3.205, I3xz=-1.6,
    I4xx=0.116, I4yy=0.103, I4zz=0.031, I4xz=0.021,
    I5xx=0.085, I5yy=0.180, I5zz=0.115,
)


@pytest.fixture(scope="session")
def thesis():
    """The thesis model (thesis front contact), shared by every test module."""
    return load_model("thesis")


@pytest.fixture(scope="session")
def disc():
    """The thesis parameters with the true disc front contact."""
    return load_model("thesis-disc")


@pytest.fixture(scope="session")
def general(thesis):
    """The thesis bicycle made general (GENERAL_CHANGES), thesis front contact."""
    return Model(thesis.params.replace(name="general", **GENERAL_CHANGES))


@pytest.fixture(scope="session")
def general_disc(general):
    """The general bicycle with the disc front contact."""
    return general.with_params(general.params.with_contact("disc"))
