"""The conformance suite's models: the named ones and a bicycle without the thesis's symmetries.

The thesis and benchmark bicycles have axisymmetric wheels, the fork's centre of mass on the
steering axis and equal wheel radii, so a builder that swaps two inertia keys (I5xx <-> I5zz)
or mixes up a frame computes the same M on them. `general` breaks every such symmetry: unequal
wheel radii, the fork CoM off the steering axis (dx4, dz4), the front hub not at the rear hub's
height, and inertia tensors with every entry the parametrization has distinct and non-zero
(three distinct moments for the wheels; four distinct entries, xz included, for frame and
fork). Each tensor is positive definite and obeys the triangle inequality (the loader checks
both): wheels 0.100 + 0.125 > 0.205, 0.085 + 0.115 > 0.180; frame and fork keep the thesis's
principal-moment margins with their xz changed a little.
"""

from __future__ import annotations

from reference_model import Model, load_model

GENERAL_CHANGES = dict(
    R_rear=0.34, R_front=0.30,
    dx4=0.035, dz4=0.12, z5=-0.45,
    I2xx=0.100, I2yy=0.205, I2zz=0.125,
    I3xx=20.213, I3yy=21.769, I3zz=3.205, I3xz=-1.6,
    I4xx=0.116, I4yy=0.103, I4zz=0.031, I4xz=0.021,
    I5xx=0.085, I5yy=0.180, I5zz=0.115,
)
DEFAULT_MODELS = ("thesis", "thesis-disc", "benchmark", "general", "general-disc")
#: the forward-run checks without --model: one named and one general bicycle (each run is
#: seconds, the term checks milliseconds); every --model given is run
DEFAULT_TRAJECTORY_MODELS = ("thesis-disc", "general")


def general_model(contact: str = "thesis") -> Model:
    """The thesis bicycle made general (``GENERAL_CHANGES``), with the given front contact."""
    p = load_model("thesis").params.replace(name="general", **GENERAL_CHANGES)
    if contact != "thesis":
        p = p.with_contact(contact).replace(name=f"general-{contact}")
    return Model(p)


def conformance_model(spec: str) -> Model:
    """A named model, one of the conformance bicycles, or a parameter file."""
    if spec == "general":
        return general_model("thesis")
    if spec == "general-disc":
        return general_model("disc")
    return load_model(spec)
