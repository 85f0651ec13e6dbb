"""``ArticulatedObject``: one articulated asset in PartNet-Mobility layout, in the canonical object frame.

A folder holds ``mobility.urdf``, the meshes it names (``textured_objs/*.obj``) and ``meta.json`` (with
``model_cat``). The same loader reads real PartNet-Mobility folders and the ones centerart generates.

Frames and units: every pose, point and mesh returned here is in the canonical object frame
(:mod:`centerart.assets.canonical_frame`), in metres. Joint states are metric: radians for revolute joints,
metres for prismatic ones (already multiplied by the object's scale).

One joint is the *target*: the door or drawer that grasps act on. Every other movable joint is held at a
stated value (``held_states``, by default its lower limit).
"""

from __future__ import annotations

import copy
import functools
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh
import yourdfpy
from lxml import etree

from centerart.assets.canonical_frame import BASE_ROTATIONS, TYPICAL_HEIGHT_M
from centerart.assets.categories import normalize_category
from centerart.assets.validation import check_mesh, check_meta, check_urdf_numbers
from centerart.errors import AssetError
from centerart.geometry.transforms import apply_transform, make_pose, rotation_about_axis

MOVABLE_TYPES = ("revolute", "prismatic", "continuous")
#: PartNet-Mobility semantics labels of parts that a grasp opens (preferred as default target joint).
OPENABLE_SEMANTICS = ("door", "rotation_door", "drawer", "translation_door")


@dataclass(frozen=True)
class Joint:
    """A URDF joint after scaling. ``origin`` is ``parent_T_joint`` (4x4, m); ``axis`` is a unit vector in the
    joint frame; ``lower``/``upper`` are metric (rad or m), ``None`` when the URDF gives no limit."""

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    lower: float | None
    upper: float | None

    @property
    def movable(self) -> bool:
        return self.type in MOVABLE_TYPES

    def motion(self, q: float) -> np.ndarray:
        """``joint_T_child`` at state q."""
        if self.type in ("revolute", "continuous"):
            return make_pose(rotation_about_axis(self.axis, q))
        if self.type == "prismatic":
            return make_pose(translation=self.axis * q)
        return np.eye(4)


@dataclass(frozen=True)
class Part:
    """One visual or collision element of a link: a mesh in the link frame plus its colour (RGBA in 0..1)."""

    link: str
    mesh: trimesh.Trimesh
    rgba: tuple[float, float, float, float]
    name: str = ""


@dataclass(frozen=True)
class JointAxis:
    """A joint's line in the canonical frame: a point on it, its unit direction and its type."""

    origin: np.ndarray
    direction: np.ndarray
    type: str


def moved_vertices(mesh: trimesh.Trimesh, pose: np.ndarray) -> np.ndarray:
    """``mesh``'s vertices moved by ``pose`` exactly as ``Trimesh.apply_transform`` moves them (same arithmetic, same
    identity shortcut), without copying the mesh: bounds computed either way are bit-identical."""
    if trimesh.util.allclose(pose, np.eye(4), 1e-8):
        return mesh.vertices
    return trimesh.transformations.transform_points(mesh.vertices, matrix=pose)


@dataclass
class ArticulatedObject:
    """An articulated object in the canonical frame. Build it with :meth:`load`."""

    path: Path
    category: str
    model_cat: str
    scale: float
    joints: dict[str, Joint]
    links: list[str]
    root: str
    target_joint: str
    held_states: dict[str, float]
    canonical_T_base: np.ndarray
    generated: bool
    visual_parts: dict[str, list[Part]] = field(repr=False)
    collision_parts: dict[str, list[Part]] = field(repr=False)
    meta: dict = field(default_factory=dict, repr=False)

    # ------------------------------------------------------------------ loading
    @classmethod
    def load(
        cls,
        path: str | Path,
        target_joint: str | None = None,
        scale: float | None = None,
        held_states: dict[str, float] | None = None,
    ) -> ArticulatedObject:
        """Load a folder in PartNet-Mobility layout.

        Args:
            path: the folder (or its ``mobility.urdf``).
            target_joint: name of the joint grasps act on. Default: ``meta.json``'s ``target_joint`` (written by
                the generator), else the first revolute/prismatic joint whose child ``semantics.txt`` calls a
                door or drawer, else the first revolute/prismatic joint.
            scale: multiplies all geometry. Default: 1 for generated objects (already metric); for real
                PartNet-Mobility objects, the scale that gives the category's typical height
                (:data:`~centerart.assets.canonical_frame.TYPICAL_HEIGHT_M`), or 1 for unknown categories.
            held_states: metric values for the non-target movable joints (default: each one's lower limit).

        Raises:
            AssetError: naming the file and the problem (missing or malformed URDF, missing mesh, a target joint
                without limits, ...).
        """
        folder, urdf_path = _object_folder(path)
        meta = _read_meta(folder)
        robot = _parse_urdf(urdf_path)
        model_cat = str(meta.get("model_cat", "Unknown"))
        category = normalize_category(model_cat)
        generated = (
            meta.get("generator", {}).get("name") == "centerart" if isinstance(meta.get("generator"), dict) else False
        )

        raw_joints = {j.name: j for j in robot.joints}
        links = [link.name for link in robot.links]
        children = {j.child for j in robot.joints}
        roots = [name for name in links if name not in children]
        if len(roots) != 1:
            raise AssetError(urdf_path, f"expected one root link, found {roots}")

        # Visual/collision parts in raw (unscaled) link coordinates; scale is applied afterwards.
        visual_parts = _load_parts(robot, folder, urdf_path, collision=False)
        collision_parts = _load_parts(robot, folder, urdf_path, collision=True)
        chosen = _checked_target(robot, raw_joints, folder, urdf_path, target_joint or meta.get("target_joint"))

        if scale is None:
            scale = 1.0 if generated else _auto_scale(robot, raw_joints, visual_parts, roots[0], category)
        scale = float(scale)
        joints = {name: _scaled_joint(j, scale) for name, j in raw_joints.items()}
        visual_parts = {k: [_scaled_part(p, scale) for p in v] for k, v in visual_parts.items()}
        collision_parts = {k: [_scaled_part(p, scale) for p in v] for k, v in collision_parts.items()}
        held = _held_values(joints, chosen, held_states, urdf_path)

        front = str(meta.get("front_axis", "+x" if generated else "-x"))
        if front not in BASE_ROTATIONS:
            raise AssetError(folder / "meta.json", f"front_axis {front!r} is not one of {sorted(BASE_ROTATIONS)}")
        obj = cls(
            path=folder,
            category=category,
            model_cat=model_cat,
            scale=scale,
            joints=joints,
            links=links,
            root=roots[0],
            target_joint=chosen,
            held_states=held,
            canonical_T_base=make_pose(BASE_ROTATIONS[front]),
            generated=generated,
            visual_parts=visual_parts,
            collision_parts=collision_parts,
            meta=meta,
        )
        lo, hi = obj.bounds(obj.joint_range[0])
        obj.canonical_T_base = make_pose(BASE_ROTATIONS[front], -(lo + hi) / 2.0)
        return obj

    def with_held_states(self, held_states: dict[str, float]) -> ArticulatedObject:
        """A shallow copy whose non-target joints are held at ``held_states`` (the others at their lower limits), in
        this object's frame. Loading the folder again with ``held_states`` would re-centre the frame on the held
        bounding box instead (see ``scenes.description.load_object_in_default_frame``)."""
        out = copy.copy(self)
        out.held_states = _held_values(self.joints, self.target_joint, held_states, self.path / "mobility.urdf")
        return out

    # ------------------------------------------------------------------ joints
    @property
    def target(self) -> Joint:
        return self.joints[self.target_joint]

    @property
    def joint_type(self) -> str:
        return self.target.type

    @property
    def joint_range(self) -> tuple[float, float]:
        """(lower, upper) of the target joint, metric."""
        return float(self.target.lower), float(self.target.upper)

    def normalize(self, q: float) -> float:
        lo, hi = self.joint_range
        return (q - lo) / (hi - lo)

    def denormalize(self, u: float) -> float:
        lo, hi = self.joint_range
        return lo + u * (hi - lo)

    def configuration(self, q: float) -> dict[str, float]:
        """Values of every movable joint with the target at ``q`` and the others at their held values."""
        return {**self.held_states, self.target_joint: float(q)}

    @functools.cached_property
    def moving_links(self) -> frozenset[str]:
        """Links that move when the target joint moves (the subtree under its child link)."""
        kids: dict[str, list[str]] = {}
        for j in self.joints.values():
            kids.setdefault(j.parent, []).append(j.child)
        out, stack = set(), [self.target.child]
        while stack:
            link = stack.pop()
            out.add(link)
            stack.extend(kids.get(link, []))
        return frozenset(out)

    # ------------------------------------------------------------------ kinematics
    def link_poses(self, q: float) -> dict[str, np.ndarray]:
        """``canonical_T_link`` for every link with the target joint at ``q``."""
        config = self.configuration(q)
        poses = {self.root: self.canonical_T_base.copy()}
        by_parent: dict[str, list[Joint]] = {}
        for j in self.joints.values():
            by_parent.setdefault(j.parent, []).append(j)
        stack = [self.root]
        while stack:
            parent = stack.pop()
            for j in by_parent.get(parent, []):
                poses[j.child] = poses[parent] @ j.origin @ j.motion(config.get(j.name, 0.0))
                stack.append(j.child)
        return poses

    def target_axis(self, q: float | None = None) -> JointAxis:
        """The target joint's line in the canonical frame at state ``q`` (default: closed).

        For a revolute joint, positive q rotates the moving part about ``direction`` by the right-hand rule; for a
        prismatic joint, positive q translates it along ``direction``.
        """
        q = self.joint_range[0] if q is None else q
        poses = self.link_poses(q)
        j = self.target
        joint_frame = poses[j.parent] @ j.origin
        direction = joint_frame[:3, :3] @ j.axis
        return JointAxis(joint_frame[:3, 3].copy(), direction / np.linalg.norm(direction), j.type)

    # ------------------------------------------------------------------ geometry
    def posed_parts(self, q: float, collision: bool = False) -> list[tuple[Part, np.ndarray]]:
        """Every visual (or collision) part as stored (link frame, not copied) with its ``canonical_T_link`` at
        state ``q``: for callers that need only the moved vertices (:func:`moved_vertices`), not moved meshes."""
        poses = self.link_poses(q)
        source = self.collision_parts if collision else self.visual_parts
        return [(part, poses[link]) for link, parts in source.items() for part in parts]

    def parts(self, q: float, collision: bool = False) -> list[Part]:
        """Every visual (or collision) part with its mesh moved into the canonical frame at state ``q``."""
        out = []
        for part, pose in self.posed_parts(q, collision):
            mesh = part.mesh.copy()
            mesh.apply_transform(pose)
            out.append(Part(part.link, mesh, part.rgba, part.name))
        return out

    def link_meshes(self, q: float, collision: bool = False) -> dict[str, trimesh.Trimesh]:
        """One mesh per link (its parts concatenated) in the canonical frame at state ``q``."""
        grouped: dict[str, list[trimesh.Trimesh]] = {}
        for part in self.parts(q, collision):
            grouped.setdefault(part.link, []).append(part.mesh)
        return {k: trimesh.util.concatenate(v) for k, v in grouped.items()}

    def moving_mesh(self, q: float) -> trimesh.Trimesh:
        """The visual mesh of the part that the target joint moves (door or drawer), canonical frame."""
        meshes = [p.mesh for p in self.parts(q) if p.link in self.moving_links]
        return trimesh.util.concatenate(meshes)

    def mesh(self, q: float) -> trimesh.Trimesh:
        """All visual parts concatenated (canonical frame). Real PartNet-Mobility meshes are triangle soups:
        use :meth:`watertight_mesh` where inside/outside matters."""
        return trimesh.util.concatenate([p.mesh for p in self.parts(q)])

    def watertight_mesh(self, q: float, pitch: float = 0.004) -> trimesh.Trimesh:
        """A closed, consistently oriented mesh of the whole object at state ``q`` (canonical frame).

        Generated objects: the exact boolean union of their parts (each part is a closed manifold). Real
        PartNet-Mobility meshes are open triangle soups with self-intersections, so a union is undefined; they
        are voxelised at ``pitch`` metres, solid regions filled, and the boundary extracted by marching cubes.
        That closes cracks narrower than a voxel and thickens walls thinner than one; details finer than
        ``pitch`` are lost.
        """
        parts = self.parts(q)
        if all(p.mesh.is_watertight for p in parts):
            from centerart.assets.mesh_ops import union

            return union([p.mesh for p in parts])
        from centerart.assets.mesh_ops import voxel_remesh

        return voxel_remesh(trimesh.util.concatenate([p.mesh for p in parts]), pitch)

    def bounds(self, q: float | None = None) -> np.ndarray:
        """Axis-aligned bounds (2, 3) of all visual parts at state ``q`` (default: closed), canonical frame."""
        q = self.joint_range[0] if q is None else q
        # Vertices only: copying every part's trimesh as parts() does was a quarter of a kitchen layout's time.
        pts = np.concatenate([moved_vertices(part.mesh, pose) for part, pose in self.posed_parts(q)])
        return np.stack([pts.min(0), pts.max(0)])

    @property
    def extents(self) -> np.ndarray:
        lo, hi = self.bounds()
        return hi - lo

    @property
    def object_id(self) -> str:
        return self.path.name

    def describe(self) -> str:
        j = self.target
        lo, hi = self.joint_range
        unit = "rad" if j.type == "revolute" else "m"
        ax = self.target_axis()
        return (
            f"{self.object_id} [{self.category}] extents {np.round(self.extents, 3).tolist()} m, "
            f"target {j.name} ({j.type}, axis {np.round(ax.direction, 3).tolist()}, range [{lo:.3f}, {hi:.3f}] "
            f"{unit}), {len(self.links)} links"
        )


# ---------------------------------------------------------------------- helpers
def _object_folder(path: str | Path) -> tuple[Path, Path]:
    """(object folder, its mobility.urdf) of a folder or URDF path; AssetError when either is missing."""
    folder = Path(path)
    if folder.name.endswith(".urdf"):
        folder = folder.parent
    urdf_path = folder / "mobility.urdf"
    if not folder.is_dir():
        raise AssetError(folder, "no such object folder")
    if not urdf_path.is_file():
        raise AssetError(urdf_path, "missing URDF (expected PartNet-Mobility layout: mobility.urdf)")
    return folder, urdf_path


def _checked_target(
    robot: yourdfpy.Robot, raw_joints: dict[str, yourdfpy.Joint], folder: Path, urdf_path: Path, requested: str | None
) -> str:
    """Name of the target joint: ``requested`` or the default one; AssetError unless it is a limited
    revolute/prismatic joint with a non-empty range."""
    chosen = requested or _default_target(robot, folder)
    if chosen is None:
        raise AssetError(urdf_path, "has no revolute or prismatic joint to act on")
    if chosen not in raw_joints:
        raise AssetError(urdf_path, f"target joint {chosen!r} not found (joints: {sorted(raw_joints)})")
    raw_target = raw_joints[chosen]
    if raw_target.type not in ("revolute", "prismatic"):
        raise AssetError(urdf_path, f"target joint {chosen!r} is {raw_target.type}, not revolute/prismatic")
    if raw_target.limit is None or raw_target.limit.lower is None or raw_target.limit.upper is None:
        raise AssetError(urdf_path, f"joint {chosen!r} has no <limit lower=... upper=...>")
    if not raw_target.limit.upper > raw_target.limit.lower:
        raise AssetError(urdf_path, f"joint {chosen!r} has an empty range {raw_target.limit}")
    return chosen


def _held_values(
    joints: dict[str, Joint], target: str, held_states: dict[str, float] | None, urdf_path: Path
) -> dict[str, float]:
    """Metric values of the non-target movable joints: ``held_states`` where given, else each lower limit (or 0)."""
    held = {n: (j.lower if j.lower is not None else 0.0) for n, j in joints.items() if j.movable}
    held.pop(target, None)
    for name, value in (held_states or {}).items():
        if name not in held:
            raise AssetError(urdf_path, f"held_states names {name!r}, which is not a non-target movable joint")
        held[name] = float(value)
    return held


def _read_meta(folder: Path) -> dict:
    meta_path = folder / "meta.json"
    if not meta_path.is_file():
        return {}
    try:
        meta = json.loads(meta_path.read_text())
    except ValueError as err:  # JSONDecodeError, or UnicodeDecodeError for a binary file
        raise AssetError(meta_path, f"malformed JSON: {err}") from None
    return check_meta(meta, meta_path)


def _parse_urdf(urdf_path: Path) -> yourdfpy.Robot:
    # Parse strictly first: yourdfpy silently falls back to a recovering parser on broken XML.
    try:
        tree = etree.parse(str(urdf_path), etree.XMLParser(recover=False, remove_comments=True))
    except etree.XMLSyntaxError as err:
        raise AssetError(urdf_path, f"malformed URDF XML: {err}") from None
    check_urdf_numbers(tree, urdf_path)
    try:
        urdf = yourdfpy.URDF.load(
            str(urdf_path), build_scene_graph=False, load_meshes=False, load_collision_meshes=False
        )
    except Exception as err:  # yourdfpy raises plain exceptions on schema problems
        raise AssetError(urdf_path, f"invalid URDF: {err}") from None
    robot = urdf.robot
    link_names = {link.name for link in robot.links}
    for j in robot.joints:
        for end in (j.parent, j.child):
            if end not in link_names:
                raise AssetError(urdf_path, f"joint {j.name!r} refers to unknown link {end!r}")
    return robot


def _default_target(robot: yourdfpy.Robot, folder: Path) -> str | None:
    movable = [j for j in robot.joints if j.type in ("revolute", "prismatic")]
    sem_path = folder / "semantics.txt"
    if sem_path.is_file():
        labels = {}
        for line in sem_path.read_text().splitlines():
            fields = line.split()
            if len(fields) >= 3:
                labels[fields[0]] = fields[2]
        for j in movable:
            if labels.get(j.child) in OPENABLE_SEMANTICS:
                return j.name
    return movable[0].name if movable else None


def _material_colors(robot: yourdfpy.Robot) -> dict[str, tuple[float, float, float, float]]:
    out = {}
    for m in robot.materials:
        if m.name and m.color is not None:
            out[m.name] = tuple(float(c) for c in m.color.rgba)
    return out


DEFAULT_RGBA = (0.7, 0.7, 0.7, 1.0)


@functools.lru_cache(maxsize=512)
def _load_mesh_file(path: str) -> trimesh.Trimesh:
    """The mesh at ``path``, checked (:func:`~centerart.assets.validation.check_mesh`); cached, so a file shared by
    several links or objects is parsed and checked once."""
    try:
        loaded = trimesh.load(path, force="mesh", process=False, skip_materials=True)
    except Exception as err:  # trimesh raises many types on damaged files
        reason = str(err).splitlines()[0] if str(err).strip() else type(err).__name__
        raise AssetError(path, f"cannot read mesh: {reason}") from None
    if not isinstance(loaded, trimesh.Trimesh):
        raise AssetError(path, "mesh is empty (no triangles): the file is damaged or not a mesh")
    return check_mesh(loaded, path)


def _load_parts(robot: yourdfpy.Robot, folder: Path, urdf_path: Path, collision: bool) -> dict[str, list[Part]]:
    named_colors = _material_colors(robot)
    out: dict[str, list[Part]] = {}
    for link in robot.links:
        elements = link.collisions if collision else link.visuals
        for k, el in enumerate(elements):
            geom = el.geometry
            origin = el.origin if el.origin is not None else np.eye(4)
            if geom.mesh is not None:
                mesh_path = (folder / geom.mesh.filename).resolve()
                if not mesh_path.is_file():
                    raise AssetError(urdf_path, f"link {link.name!r} names a missing mesh file {geom.mesh.filename}")
                mesh = _load_mesh_file(str(mesh_path)).copy()
                if geom.mesh.scale is not None:
                    mesh.apply_scale(np.broadcast_to(np.asarray(geom.mesh.scale, float), (3,)))
            elif geom.box is not None:
                mesh = trimesh.creation.box(extents=geom.box.size)
            elif geom.cylinder is not None:
                mesh = trimesh.creation.cylinder(radius=geom.cylinder.radius, height=geom.cylinder.length, sections=24)
            elif geom.sphere is not None:
                mesh = trimesh.creation.icosphere(subdivisions=2, radius=geom.sphere.radius)
            else:
                raise AssetError(urdf_path, f"link {link.name!r} has a geometry of unsupported type")
            if len(mesh.faces) == 0:
                continue
            mesh.apply_transform(origin)
            rgba = DEFAULT_RGBA
            mat = getattr(el, "material", None)
            if mat is not None:
                if mat.color is not None:
                    rgba = tuple(float(c) for c in mat.color.rgba)
                elif mat.name in named_colors:
                    rgba = named_colors[mat.name]
            name = getattr(el, "name", None) or f"{link.name}_{k}"
            out.setdefault(link.name, []).append(Part(link.name, mesh, rgba, name))
    return out


def _scaled_joint(j: yourdfpy.Joint, s: float) -> Joint:
    origin = np.array(j.origin if j.origin is not None else np.eye(4), dtype=float)
    origin[:3, 3] *= s
    axis = np.asarray(j.axis if j.axis is not None else [1.0, 0.0, 0.0], dtype=float)
    axis = axis / np.linalg.norm(axis)
    lower = upper = None
    if j.limit is not None:
        factor = s if j.type == "prismatic" else 1.0
        lower = None if j.limit.lower is None else float(j.limit.lower) * factor
        upper = None if j.limit.upper is None else float(j.limit.upper) * factor
    return Joint(j.name, j.type, j.parent, j.child, origin, axis, lower, upper)


def _scaled_part(p: Part, s: float) -> Part:
    if s == 1.0:
        return p
    mesh = p.mesh.copy()
    mesh.apply_scale(s)
    return Part(p.link, mesh, p.rgba, p.name)


def _auto_scale(robot, raw_joints, visual_parts, root, category) -> float:
    if category not in TYPICAL_HEIGHT_M:
        return 1.0
    # Height (base z) of the closed object in raw units, from joint origins and link meshes at zero state.
    poses = {root: np.eye(4)}
    by_parent: dict[str, list] = {}
    for j in raw_joints.values():
        by_parent.setdefault(j.parent, []).append(j)
    stack = [root]
    while stack:
        parent = stack.pop()
        for j in by_parent.get(parent, []):
            origin = j.origin if j.origin is not None else np.eye(4)
            poses[j.child] = poses[parent] @ origin
            stack.append(j.child)
    zs = [apply_transform(poses[link], p.mesh.vertices)[:, 2] for link, ps in visual_parts.items() for p in ps]
    if not zs:
        return 1.0
    z = np.concatenate(zs)
    height = float(z.max() - z.min())
    return TYPICAL_HEIGHT_M[category] / height if height > 0 else 1.0
