"""The surface an SDF is measured to: one triangle mesh per (object, joint state), canonical frame, metres.

Generated objects are built from closed manifold parts, so their surface is the exact boolean union of the parts
(closed, consistently oriented, no internal faces). Real PartNet-Mobility meshes are open triangle soups whose
walls are usually drawn double-sided (every triangle twice, once per orientation): they are kept as they are
(no voxel remesh, which costs seconds to minutes per state and blurs details finer than its pitch), with
coincident duplicate triangles removed so that a wall counts as one crossing for ray parity. A soup also keeps
its pieces, one per named part of each link, because its inside is decided part by part
(:mod:`centerart.sdf.signs`).
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np
import trimesh

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.mesh_ops import union
from centerart.geometry.transforms import invert_pose


@dataclass
class ObjectSurface:
    """An object's surface at one joint state, canonical frame."""

    mesh: trimesh.Trimesh
    """The whole surface: exact union (closed) or deduplicated soup."""
    closed: bool
    """True when ``mesh`` is the exact union of closed parts (generated objects), False for a soup."""
    pieces: list[trimesh.Trimesh] = field(default_factory=list)
    """Soups only: the deduplicated mesh of each named part of each link (PartNet-Mobility ``<visual name>``)."""
    piece_frames: list[np.ndarray] = field(default_factory=list)
    """Soups only, one 4x4 per piece: canonical frame at this state -> canonical frame at the closed state
    (``closed_T_link @ inv(state_T_link)`` of the piece's link). The flood-fill check voxelises each piece in
    that frame, so a door's grid moves with the door: at 45 degrees an axis-aligned grid of the door grew, its
    pitch coarsened from 3.3 to 4.2 mm and its 5 mm glass pane lost its interior (11700: 0.999 -> 0.986)."""


def object_surface(obj: ArticulatedObject, q: float) -> ObjectSurface:
    """The object's surface at target joint state ``q`` in the canonical frame."""
    parts = obj.parts(q)
    meshes = [p.mesh for p in parts]
    if all(m.is_watertight for m in meshes):
        try:
            return ObjectSurface(union(meshes), True)
        except ValueError:
            pass  # a part that trimesh calls watertight but manifold3d rejects: treat the object as a soup
    groups: dict[tuple[str, str], list[trimesh.Trimesh]] = defaultdict(list)
    for p in parts:
        groups[(p.link, p.name)].append(p.mesh)
    at_q, closed = obj.link_poses(q), obj.link_poses(obj.denormalize(0.0))
    pieces, frames = [], []
    for (link, _), group in groups.items():
        piece = dedupe_soup(trimesh.util.concatenate(group))
        if len(piece.faces):
            pieces.append(piece)
            frames.append(closed[link] @ invert_pose(at_q[link]))
    return ObjectSurface(dedupe_soup(trimesh.util.concatenate(meshes)), False, pieces, frames)


def dedupe_soup(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Merge coincident vertices and drop repeated triangles (whatever their orientation) and degenerate ones."""
    out = trimesh.Trimesh(np.asarray(mesh.vertices, float), np.asarray(mesh.faces), process=False)
    out.merge_vertices(merge_tex=True, merge_norm=True)
    faces = out.faces
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    faces = faces[keep]
    _, first = np.unique(np.sort(faces, axis=1), axis=0, return_index=True)
    faces = faces[np.sort(first)]
    area = trimesh.triangles.area(out.vertices[faces])
    faces = faces[area > 1e-12]
    return trimesh.Trimesh(out.vertices, faces, process=False)
