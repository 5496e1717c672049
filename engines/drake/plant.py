"""Drake's MultibodyPlant of the bicycle, from the project's own URDF export, with the
conventions that differ from the thesis handled here, each once:

* **The root.** The URDF's tree starts at the link ``ground``. Drake gives a parsed model's
  root link a free (6-dof quaternion) joint unless it is welded: ``ground`` is welded to the
  world here (otherwise nq = 15, nv = 14).
* **Gravity.** Drake's default field is 9.81 m/s^2 along -z; it is set to the parameters' g.
* **The coordinates.** Drake numbers its generalized positions by its own tree traversal;
  `Mapping` holds, for each of the thesis's coordinates (by joint name), the index of its
  joint's position and velocity in Drake's vectors, and moves vectors and Jacobian columns
  between the two. Every joint of the export is a one-dof prismatic or revolute joint about a
  positive body axis, so q_dot = v and the signs are the thesis's (checked against the
  reference's body positions in the tests).

A run's plant (`run_urdf_text`) has one more joint, ``zc``: a slide along z between ``yc_link``
and ``yaw``. Without it the chain holds the rear contact's height at zero, the ground carries
no weight at the rear wheel and its friction transmits nothing.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from reference_model import COORDINATES
from reference_model.exports import urdf_text

from ..base import EngineError, UnsupportedModel

from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

__all__ = ["BODY_LINKS", "Mapping", "add_bicycle", "run_urdf_text", "terms_plant"]

#: the URDF's links of the thesis's bodies 2..5
BODY_LINKS = {2: "rear_wheel", 3: "frame", 4: "fork", 5: "front_wheel"}


@dataclass(frozen=True)
class Mapping:
    """Where each coordinate (in ``names`` order) sits in Drake's q and v."""

    names: tuple[str, ...]
    q_index: tuple[int, ...]
    v_index: tuple[int, ...]

    @classmethod
    def of(cls, plant: "MultibodyPlant", names: tuple[str, ...]) -> "Mapping":
        joints = [plant.GetJointByName(n) for n in names]
        bad = [j.name() for j in joints if j.num_positions() != 1 or j.num_velocities() != 1]
        if bad or plant.num_positions() != len(names) or plant.num_velocities() != len(names):
            raise EngineError(f"Drake's plant has nq = {plant.num_positions()}, nv = "
                              f"{plant.num_velocities()} (joints of more than one dof: {bad}); the "
                              f"bicycle needs {len(names)} one-dof joints {names}")
        return cls(names, tuple(j.position_start() for j in joints),
                   tuple(j.velocity_start() for j in joints))

    @cached_property
    def _q(self) -> np.ndarray:
        return np.array(self.q_index)

    @cached_property
    def _v(self) -> np.ndarray:
        return np.array(self.v_index)

    def q_to_drake(self, q: np.ndarray) -> np.ndarray:
        out = np.empty(len(self.q_index))
        out[self._q] = q
        return out

    def v_to_drake(self, v: np.ndarray) -> np.ndarray:
        out = np.empty(len(self.v_index))
        out[self._v] = v
        return out

    def q_from_drake(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x)[..., self._q]

    def v_from_drake(self, x: np.ndarray) -> np.ndarray:
        """A velocity-indexed vector (or a Jacobian's columns, last axis) in the thesis's order."""
        return np.asarray(x)[..., self._v]

    def matrix_from_drake(self, A: np.ndarray) -> np.ndarray:
        """An nv x nv matrix (M) in the thesis's order, rows and columns."""
        return np.asarray(A)[np.ix_(self._v, self._v)]


def run_urdf_text(params) -> str:
    """The export's URDF with the rear contact's height ``zc`` free (a prismatic z joint from
    ``yc_link`` to a massless ``zc_link``, which ``phi`` then hangs from) and without the
    export's nominal collision cylinders: the run registers its own wheels' geometry."""
    text = urdf_text(params)
    text, n = re.subn(r'(<joint name="phi"[^>]*>\s*<parent link=)"yc_link"', r'\1"zc_link"', text)
    if n != 1:
        raise EngineError("the URDF export's phi joint does not hang from yc_link as expected")
    text = re.sub(r"\s*<!-- wheel radius[^>]*-->\s*<collision>.*?</collision>", "", text,
                  flags=re.S)
    zc = ('  <link name="zc_link"/>\n'
          '  <joint name="zc" type="prismatic">\n'
          '    <parent link="yc_link"/>\n    <child link="zc_link"/>\n'
          '    <origin xyz="0 0 0" rpy="0 0 0"/>\n    <axis xyz="0 0 1"/>\n'
          '    <limit lower="-1e9" upper="1e9" effort="0" velocity="1e9"/>\n  </joint>\n')
    return text.replace("</robot>", zc + "</robot>")


def add_bicycle(plant: "MultibodyPlant", params, text: str | None = None, *,
                weld_root: bool = True) -> None:
    """Parse the bicycle's URDF (the export of ``params`` unless ``text``) into ``plant``, weld
    its ``ground`` to the world (unless ``weld_root`` is False: Drake then adds a free joint)
    and set gravity to -g along z. The plant is left unfinalized."""
    Parser(plant).AddModelsFromString(urdf_text(params) if text is None else text, "urdf")
    if weld_root:
        plant.WeldFrames(plant.world_frame(), plant.GetFrameByName("ground"))
    plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, -float(params.g)])


#: relative slack of the triangle check below (Drake's own test, CouldBePhysicallyValid,
#: allows round-off of the same order)
TRIANGLE_SLACK = 1e-10


def refuse_non_physical_inertia(params) -> None:
    """`UnsupportedModel` when a body's principal moments break A + B >= C: Drake's URDF parser
    does not refuse such a body, it warns and builds a different one (measured on
    BicycleParameters' Browser, whose frame and rider break it by 2.33 %: M 6.8e-2 wrong), so
    the engine declares the bicycle beyond it instead of computing wrong terms."""
    for i in (2, 3, 4, 5):
        xz = getattr(params, f"I{i}xz", 0.0)
        tensor = np.array([[getattr(params, f"I{i}xx"), 0.0, xz],
                           [0.0, getattr(params, f"I{i}yy"), 0.0],
                           [xz, 0.0, getattr(params, f"I{i}zz")]])
        moments = np.sort(np.linalg.eigvalsh(tensor))
        if moments[0] + moments[1] < moments[2] * (1.0 - TRIANGLE_SLACK):
            raise UnsupportedModel(
                f"Drake requires every body's principal moments of inertia to satisfy the "
                f"triangle inequality A + B >= C, and this bicycle's body {i} breaks it "
                f"(principal moments {', '.join(f'{m:.6g}' for m in moments)} kg m^2); Drake's "
                "parser would replace the body's inertia, not refuse it")


def terms_plant(params, *, weld_root: bool = True) -> tuple["MultibodyPlant", Mapping]:
    """The continuous plant of the thesis's tree (no contact) and its coordinate mapping."""
    plant = MultibodyPlant(0.0)
    add_bicycle(plant, params, weld_root=weld_root)
    plant.Finalize()
    return plant, Mapping.of(plant, COORDINATES)
