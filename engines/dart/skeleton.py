"""The bicycle's DART skeleton from the project's own URDF export, with DART's conventions
handled explicitly:

* **The default inertia.** DART's URDF loader (``dart.utils.DartLoader``) gives every link
  without an ``<inertial>`` its ``mDefaultInertia``, 1 kg with a unit moment of inertia unless
  told otherwise. The export's four links of the floating base (``xc_link``, ``yc_link``,
  ``yaw``, ``lean``) are massless and have none, so with the loader's default M is 4.3 % wrong
  (measured on ``thesis``). The loader's default is set to zero mass and zero inertia here.
* **The root.** The loader adds a root joint above the URDF's root link (``ground``):
  FLOATING by default (a free joint, 6 more coordinates, 14 in all); it is FIXED (welded to the
  world) here, so the skeleton has the thesis's eight joints and nothing else.
* **The coordinate order.** DART numbers the degrees of freedom depth-first along its child
  order, which puts the frame's chain before the rear wheel: xc, yc, phi, theta, beta, gamma,
  eps, psi. `Coordinates` maps them onto the thesis's q by the joints' names (the export names
  each joint after its coordinate); axes and signs are the thesis's (every joint axis is a
  positive body axis at zero angle), so the map is a permutation.
* **Gravity**: ``Skeleton.setGravity([0, 0, -g])`` from the model's g (DART's default is
  9.81).

DART prints a warning line for each zero mass it is given ("can cause invalid physical
behaviour"); the zero masses are the point here (they are intermediate links, each carrying
massive children, so the articulated inertias stay positive definite), so the build runs with
DART's output silenced at the file-descriptor level (`quiet`).
"""

from __future__ import annotations

import contextlib
import os
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from reference_model import COORDINATES
from reference_model.exports.urdf import urdf_text
from reference_model.parameters.values import Parameters

import dartpy as dart

__all__ = ["Coordinates", "build_skeleton", "load_urdf", "quiet", "run_urdf"]

N_Q = 8


@contextlib.contextmanager
def quiet():
    """DART's own output (it writes its warnings straight to the C streams) discarded during
    the block; Python's streams are flushed first so nothing of ours is lost."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)


def load_urdf(text: str, zero_default_inertia: bool = True,
              fixed_root: bool = True) -> "dart.dynamics.Skeleton":
    """DART's skeleton of a URDF text. The two flags exist for the tests, which build DART's
    defaults (a 1 kg link where the URDF has no inertial, a free root joint) to see them fail."""
    loader = dart.utils.DartLoader()
    options = loader.getOptions()
    with quiet():
        if zero_default_inertia:
            none = dart.dynamics.Inertia()
            none.setMass(0.0)
            none.setLocalCOM(np.zeros(3))
            none.setMoment(np.zeros((3, 3)))
            options.mDefaultInertia = none
        if fixed_root:
            options.mDefaultRootJointType = dart.utils.DartLoaderRootJointType.FIXED
        loader.setOptions(options)
        skeleton = loader.parseSkeletonString(text, "")
    if skeleton is None:
        raise RuntimeError("DART's URDF loader did not parse the bicycle's URDF")
    return skeleton


def run_urdf(p: Parameters) -> str:
    """The export's URDF with one more joint for a forward run on DART's contact: ``zc``, a
    prismatic z joint after ``yc`` (link ``zc_link``, massless). Without it the rear contact's
    height is held at zero by the chain, so the ground would carry no weight on the rear wheel
    and give it no friction (the MuJoCo run's chain has the same joint)."""
    root = ET.fromstring(urdf_text(p).split("?>", 1)[1])
    ET.SubElement(root, "link", name="zc_link")
    for joint in root.findall("joint"):
        if joint.get("name") == "phi":
            joint.find("parent").set("link", "zc_link")
    zc = ET.SubElement(root, "joint", name="zc", type="prismatic")
    ET.SubElement(zc, "parent", link="yc_link")
    ET.SubElement(zc, "child", link="zc_link")
    ET.SubElement(zc, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(zc, "axis", xyz="0 0 1")
    ET.SubElement(zc, "limit", lower="-1e9", upper="1e9", effort="0", velocity="1e9")
    return ET.tostring(root, encoding="unicode")


@dataclass(frozen=True)
class Coordinates:
    """DART's degrees of freedom against the thesis's coordinates: ``dof[k]`` is the DART index
    of the thesis's coordinate k (``names``: COORDINATES, plus zc in a run's skeleton)."""

    dof: np.ndarray
    names: tuple[str, ...]

    @classmethod
    def of(cls, skeleton, names: tuple[str, ...] = COORDINATES) -> "Coordinates":
        dofs = tuple(skeleton.getDof(i).getName() for i in range(skeleton.getNumDofs()))
        if sorted(dofs) != sorted(names):
            raise RuntimeError(f"DART's skeleton has the degrees of freedom {dofs}, not the "
                               f"thesis's {names}")
        return cls(np.array([dofs.index(c) for c in names]), names)

    def to_dart(self, x) -> np.ndarray:
        """A vector in the thesis's order as DART's."""
        out = np.empty(len(self.names))
        out[self.dof] = x
        return out

    def from_dart(self, x) -> np.ndarray:
        """A DART vector (or the last axis of an array) in the thesis's order."""
        return np.asarray(x)[..., self.dof]

    def matrix(self, A) -> np.ndarray:
        """A DART square matrix (dofs x dofs) in the thesis's order."""
        return np.asarray(A)[np.ix_(self.dof, self.dof)]


def build_skeleton(p: Parameters, text: str | None = None, **flags):
    """(skeleton, coordinates) of the thesis tree (``text``: a URDF, default the export of p),
    gravity -g along z."""
    skeleton = load_urdf(urdf_text(p) if text is None else text, **flags)
    skeleton.setGravity(np.array([0.0, 0.0, -p.g]))
    return skeleton, Coordinates.of(skeleton)
