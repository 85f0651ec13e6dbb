"""Mesh operations on closed meshes, through manifold3d (exact, robust booleans) and voxels for soups."""

from __future__ import annotations

import manifold3d
import numpy as np
import trimesh
from scipy import ndimage
from skimage.measure import marching_cubes


def to_manifold(mesh: trimesh.Trimesh) -> manifold3d.Manifold:
    return manifold_from_arrays(mesh.vertices, mesh.faces)


def manifold_from_arrays(vertices: np.ndarray, faces: np.ndarray) -> manifold3d.Manifold:
    """A manifold3d solid from (V, 3) vertices and (F, 3) triangle indices of a closed mesh."""
    m = manifold3d.Manifold(
        manifold3d.Mesh(
            vert_properties=np.asarray(vertices, dtype=np.float32),
            tri_verts=np.asarray(faces, dtype=np.uint32),
        )
    )
    if m.status() != manifold3d.Error.NoError:
        raise ValueError(f"mesh is not a closed manifold ({m.status()})")
    return m


def from_manifold(m: manifold3d.Manifold) -> trimesh.Trimesh:
    out = m.to_mesh()
    return trimesh.Trimesh(np.asarray(out.vert_properties[:, :3], float), np.asarray(out.tri_verts), process=True)


def union(meshes: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    """Boolean union of closed meshes; the result is watertight and consistently oriented."""
    return from_manifold(manifold3d.Manifold.batch_boolean([to_manifold(m) for m in meshes], manifold3d.OpType.Add))


def intersection_volume(a: trimesh.Trimesh | manifold3d.Manifold, b: trimesh.Trimesh | manifold3d.Manifold) -> float:
    """Volume (m^3) of the overlap of two closed meshes: 0 when they only touch or are apart."""
    ma = a if isinstance(a, manifold3d.Manifold) else to_manifold(a)
    mb = b if isinstance(b, manifold3d.Manifold) else to_manifold(b)
    return float((ma ^ mb).volume())


def voxel_remesh(mesh: trimesh.Trimesh, pitch: float) -> trimesh.Trimesh:
    """Closed surface of a triangle soup: voxels that hold surface samples are walls, every voxel the outside
    cannot reach is filled, and marching cubes extracts the boundary of that solid.

    Used for real PartNet-Mobility meshes, which are open soups where a boolean union or a winding-number sign is
    unreliable. Surface samples (about four per voxel face) mark the walls instead of trimesh's ``voxelized``,
    which subdivides every triangle and took 15 s and several GB on one PartNet microwave; this takes 0.5-12 s on
    the samples at 4 mm. Cracks narrower than a voxel are closed and walls thinner than one are thickened.
    """
    lo, hi = mesh.bounds
    origin = lo - 2 * pitch
    shape = np.ceil((hi - lo) / pitch).astype(int) + 5
    count = int(mesh.area / (0.5 * pitch) ** 2) + 1000
    points, _ = trimesh.sample.sample_surface(mesh, count, seed=0)
    idx = np.floor((np.concatenate([points, mesh.vertices]) - origin) / pitch).astype(int)
    wall = np.zeros(shape, bool)
    wall[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    solid = ndimage.binary_fill_holes(wall)
    verts, faces, _, _ = marching_cubes(solid.astype(np.float32), 0.5, spacing=(pitch,) * 3)
    out = trimesh.Trimesh(verts + origin + 0.5 * pitch, faces, process=True)
    trimesh.repair.fix_normals(out)
    return out
