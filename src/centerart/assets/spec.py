"""In-memory description of a generated articulated object, before it is written as URDF + OBJ.

Geometry is made of primitives (boxes, cylinders). Each primitive is one collision element of its link, so
pybullet and SAPIEN simulate exact boxes and cylinders (pybullet would replace a moving link's mesh with its
convex hull and close the gap behind a handle; reference/stack-measurements.md 2.2). The visual mesh of a
group of primitives is their boolean union, a closed manifold.

Frames: the base link frame is the canonical object frame (x out of the front, z up, origin at the closed
bounding-box centre). A child link's frame sits on its joint: for doors, on the hinge line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import trimesh

from centerart.assets.mesh_ops import union
from centerart.geometry.transforms import make_pose


@dataclass
class Primitive:
    """A box (``size`` = full extents x, y, z) or a cylinder (``size`` = radius, length; axis = local z),
    placed by ``pose`` (``link_T_primitive``)."""

    kind: Literal["box", "cylinder"]
    size: tuple[float, ...]
    pose: np.ndarray

    def mesh(self) -> trimesh.Trimesh:
        if self.kind == "box":
            m = trimesh.creation.box(extents=self.size)
        else:
            m = trimesh.creation.cylinder(radius=self.size[0], height=self.size[1], sections=32)
        m.apply_transform(self.pose)
        return m

    def shifted(self, offset: np.ndarray) -> Primitive:
        return Primitive(self.kind, self.size, make_pose(self.pose[:3, :3], self.pose[:3, 3] + offset))


def box_between(lo, hi) -> Primitive:
    """Axis-aligned box from its min and max corners."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return Primitive("box", tuple((hi - lo).tolist()), make_pose(translation=(lo + hi) / 2))


def cylinder_along(axis: int, center, radius: float, length: float) -> Primitive:
    """Cylinder whose axis is the coordinate axis ``axis`` (0=x, 1=y, 2=z)."""
    rot = {
        0: np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], float),
        1: np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float),
        2: np.eye(3),
    }[axis]
    return Primitive("cylinder", (radius, length), make_pose(rot, np.asarray(center, float)))


@dataclass
class VisualGroup:
    """Primitives rendered with one material; written as one watertight OBJ."""

    name: str
    primitives: list[Primitive]
    rgba: tuple[float, float, float, float]
    material: str  # painted | wood | metal | glass | plastic

    def mesh(self) -> trimesh.Trimesh:
        return union([p.mesh() for p in self.primitives])


@dataclass
class LinkSpec:
    name: str
    groups: list[VisualGroup]
    density: float  # kg/m^3 of the solid parts

    def primitives(self) -> list[Primitive]:
        return [p for g in self.groups for p in g.primitives]

    def mesh(self) -> trimesh.Trimesh:
        return union([p.mesh() for p in self.primitives()])


@dataclass
class JointSpec:
    """``origin`` is the joint position in the parent (base) frame; the joint frame is axis-aligned with it."""

    name: str
    type: Literal["revolute", "prismatic"]
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    lower: float
    upper: float
    damping: float
    friction: float
    role: str  # door | drawer


@dataclass
class HandleSpec:
    """Where a handle is, for grasp candidates and tests. Frame: its link's frame."""

    type: str  # bar | u | knob | lip | none
    link: str
    center: np.ndarray  # grip centre
    axis: np.ndarray  # direction of the grip bar (unit); for knobs the stem direction (+x)
    length: float
    thickness: float  # bar diameter / lip thickness
    clearance: float  # free gap behind the grip, towards the front face (m); 0 for none


@dataclass
class ObjectSpec:
    category: str
    links: list[LinkSpec]
    joints: list[JointSpec]
    target_joint: str
    handles: list[HandleSpec] = field(default_factory=list)
    params: dict = field(default_factory=dict)

    def link(self, name: str) -> LinkSpec:
        return next(link for link in self.links if link.name == name)

    def joint(self, name: str) -> JointSpec:
        return next(j for j in self.joints if j.name == name)
