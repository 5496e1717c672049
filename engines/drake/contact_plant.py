"""The discrete plant of a contact run: the run's URDF (the rear height ``zc`` free), Drake's
contact solver and model, and the wheels' and the ground's collision geometry.

* The wheels: a `Cylinder` of the wheel's radius and length 2 x ``wheel_half_width`` on each
  wheel body, its axis (Drake's cylinder z) along the axle (the body's y). The model's wheel is
  a knife-edge disc: a leaned cylinder rests on its lower cap's rim, half-width x sin(lean)
  beside the disc's contact point, so the width is kept small.
* The ground: a `HalfSpace` z <= 0 on the world body.
* Both carry the Coulomb coefficient ``friction`` (static = dynamic; Drake combines the two
  geometries' coefficients as 2 a b / (a + b), so equal values stay the same) and, for point
  contact, ``point_stiffness`` and the Hunt-Crossley ``dissipation`` (Drake combines two
  stiffnesses in series: the pair's stiffness is half of one geometry's, hence twice the
  given value here, so the pair has the stiffness given). For hydroelastic contact the wheels are
  compliant (``hydroelastic_modulus``, meshed at ``HYDRO_RESOLUTION``), the ground rigid.
* Drake's regularized friction: ``stiction_tolerance`` (``set_stiction_tolerance``), the
  discrete approximation ``set_discrete_contact_approximation`` (sap, tamsi, lagged, similar),
  ``set_contact_model`` (point, hydroelastic).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from pydrake.geometry import (AddCompliantHydroelasticProperties, AddContactMaterial,
                              AddRigidHydroelasticProperties, Cylinder, HalfSpace,
                              ProximityProperties)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import (AddMultibodyPlantSceneGraph, ContactModel, CoulombFriction,
                                     DiscreteContactApproximation)
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from reference_model import COORDINATES

from .options import RunSettings
from .plant import BODY_LINKS, Mapping, add_bicycle, run_urdf_text

__all__ = ["RUN_COORDINATES", "RunPlant", "build_run_plant"]

#: the run plant's coordinates: the thesis's with zc after yc
RUN_COORDINATES = COORDINATES[:2] + ("zc",) + COORDINATES[2:]

_APPROXIMATION = {"sap": DiscreteContactApproximation.kSap,
                  "tamsi": DiscreteContactApproximation.kTamsi,
                  "lagged": DiscreteContactApproximation.kLagged,
                  "similar": DiscreteContactApproximation.kSimilar}
#: m, the compliant cylinders' mesh resolution (about 1/20 of a wheel's circumference per edge)
HYDRO_RESOLUTION = 0.1
_CONTACT_MODEL = {"point": ContactModel.kPoint, "hydroelastic": ContactModel.kHydroelastic}


@dataclass(frozen=True)
class RunPlant:
    """A built diagram: the plant, its simulator and context, the run's coordinate mapping and
    the wheels' bodies (by the thesis's body number)."""

    plant: object
    simulator: object
    context: object
    mapping: Mapping
    wheels: dict


def _properties(s: RunSettings, compliant: bool) -> ProximityProperties:
    props = ProximityProperties()
    friction = CoulombFriction(s.friction, s.friction)
    if s.contact_model == "point":
        AddContactMaterial(s.dissipation, 2.0 * s.point_stiffness, friction, props)
    else:
        AddContactMaterial(s.dissipation, None, friction, props)
        if compliant:
            AddCompliantHydroelasticProperties(HYDRO_RESOLUTION, s.hydroelastic_modulus, props)
        else:
            AddRigidHydroelasticProperties(props)
    return props


def build_run_plant(params, s: RunSettings) -> RunPlant:
    """The run's diagram. Drake logs a warning for every half-space (no deformable contact with
    it, which this plant has none of); it is kept out of the run's output, and the logger's
    level is restored after."""
    log = logging.getLogger("drake")
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        return _build(params, s)
    finally:
        log.setLevel(level)


def _build(params, s: RunSettings) -> RunPlant:
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, time_step=s.time_step)
    plant.set_discrete_contact_approximation(_APPROXIMATION[s.approximation])
    plant.set_contact_model(_CONTACT_MODEL[s.contact_model])
    plant.set_stiction_tolerance(s.stiction_tolerance)
    add_bicycle(plant, params, run_urdf_text(params))
    axle = RigidTransform(RotationMatrix.MakeXRotation(math.pi / 2), np.zeros(3))  # z -> -y
    wheels = {}
    for b, radius in ((2, params.R_rear), (5, params.R_front)):
        body = plant.GetBodyByName(BODY_LINKS[b])
        plant.RegisterCollisionGeometry(body, axle, Cylinder(float(radius), 2 * s.wheel_half_width),
                                        BODY_LINKS[b], _properties(s, True))
        wheels[b] = body
    plant.RegisterCollisionGeometry(plant.world_body(), HalfSpace.MakePose([0, 0, 1], [0, 0, 0]),
                                    HalfSpace(), "ground", _properties(s, False))
    plant.Finalize()
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = plant.GetMyMutableContextFromRoot(simulator.get_mutable_context())
    return RunPlant(plant, simulator, context, Mapping.of(plant, RUN_COORDINATES), wheels)
