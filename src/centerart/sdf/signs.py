"""Inside/outside tests for query points (canonical frame, metres). Two per kind of surface, independent of each
other, so that one can check the other on every sample file.

Closed meshes (generated objects, exact union of closed parts):

- sign: :func:`ray_parity_inside`, odd number of crossings along a ray, majority of a few seeded rays (one ray
  can graze an edge). Exact for a closed mesh; the hollow of a cabinet behind a closed door stays empty space.
- check: :func:`winding_number`, the generalized winding number (sum of signed solid angles of the triangles),
  1 inside and 0 outside a closed oriented mesh. No rays, no crossing counts.

Triangle soups (real PartNet-Mobility meshes: open sheets, double-sided walls, overlaps, cracks). Ray parity is
useless there: on the sample objects the seeded rays of one point disagree for 20-75% of the points, because a
single open sheet flips parity. Winding numbers need an orientation the soups lack (their double-sided walls
give 0 everywhere). So:

- sign: :func:`ray_escape_inside`, a point is outside when at least one of many evenly spread rays leaves the
  scene without a hit, i.e. when it can be seen from outside: the visibility convention of DeepSDF-style data
  (depth scans from a sphere of cameras) on exact geometry, so closed boards thinner than any voxel stay solid.
  The SDF gives every sheet a thin shell (see :mod:`centerart.sdf.sampling`), so open sheets have an inside too.
- check: :func:`flood_fill_inside`, empty space the flood from the grid border cannot reach is inside; points in
  the voxel band around the surface take the label of the first empty voxel found by walking away from their
  nearest surface point. Voxels and connectivity, no rays. The two disagree where a soup is ambiguous: bodies
  whose gaps are wider than the flood's closing but let few straight rays through (flood: outside, escape:
  inside), sheltered pockets reached by a bent path only, and boards thinner than the voxel band.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d
import trimesh
from scipy import ndimage


def raycasting_scene(mesh: trimesh.Trimesh) -> o3d.t.geometry.RaycastingScene:
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(np.asarray(mesh.vertices, np.float32)), o3d.core.Tensor(np.asarray(mesh.faces, np.uint32))
    )
    return scene


def ray_directions(count: int, seed: int = 0) -> np.ndarray:
    """``count`` fixed unit directions (count, 3), never along a coordinate axis in practice (generated objects
    are axis-aligned boxes: an axis-aligned ray can run inside a face or hit an edge exactly)."""
    # Fibonacci sphere (even coverage for the escape test) turned by a seeded random rotation.
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = np.pi * (1.0 + 5**0.5) * k
    r = np.sqrt(1.0 - z**2)
    dirs = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    a = np.random.default_rng(seed).normal(size=(3, 3))
    rot, _ = np.linalg.qr(a)
    return dirs @ rot.T


def _ray_tensor(points: np.ndarray, dirs: np.ndarray) -> o3d.core.Tensor:
    n, k = len(points), len(dirs)
    rays = np.empty((n, k, 6), np.float32)
    rays[:, :, :3] = points[:, None]
    rays[:, :, 3:] = dirs[None]
    return o3d.core.Tensor(rays)


def ray_parity_inside(
    scene: o3d.t.geometry.RaycastingScene, points: np.ndarray, rays: int = 5, seed: int = 0, chunk: int = 100_000
) -> np.ndarray:
    """Inside (bool per point) by majority of ``rays`` (odd) odd-crossing tests. For closed meshes."""
    dirs = ray_directions(rays, seed).astype(np.float32)
    points = np.asarray(points, np.float32)
    votes = np.zeros(len(points))
    for s in range(0, len(points), chunk):
        hits = scene.count_intersections(_ray_tensor(points[s : s + chunk], dirs)).numpy()
        votes[s : s + chunk] = (hits % 2 == 1).mean(axis=1)
    return votes > 0.5


def ray_escape_inside(
    scene: o3d.t.geometry.RaycastingScene, points: np.ndarray, rays: int = 256, seed: int = 1, chunk: int = 20_000
) -> np.ndarray:
    """Inside (bool per point) unless one of ``rays`` evenly spread rays leaves without a hit. For soups.

    Most outside points escape along one of the first few directions, so every point first tries a spread
    subset of 32 rays and only the points still enclosed try the rest."""
    dirs = ray_directions(rays, seed).astype(np.float32)
    first, rest = dirs[:: max(1, rays // 32)], np.delete(dirs, np.arange(0, rays, max(1, rays // 32)), axis=0)
    points = np.asarray(points, np.float32)
    inside = np.zeros(len(points), bool)
    for s in range(0, len(points), chunk):
        p = points[s : s + chunk]
        enclosed = scene.test_occlusions(_ray_tensor(p, first)).numpy().all(axis=1)
        if len(rest) and enclosed.any():
            idx = np.flatnonzero(enclosed)
            enclosed[idx] = scene.test_occlusions(_ray_tensor(p[idx], rest)).numpy().all(axis=1)
        inside[s : s + chunk] = enclosed
    return inside


def winding_number(mesh: trimesh.Trimesh, points: np.ndarray, block: int = 200_000) -> np.ndarray:
    """Generalized winding number of each point w.r.t. ``mesh`` (Jacobson et al. 2013, solid angles by the van
    Oosterom-Strackee formula). O(points x triangles): meant for a subsample and meshes of a few 1000 triangles."""
    tri = np.asarray(mesh.vertices, float)[np.asarray(mesh.faces)]  # (F, 3, 3)
    points = np.asarray(points, float)
    chunk = max(1, block // max(1, len(tri)))
    out = np.zeros(len(points))
    for s in range(0, len(points), chunk):
        p = points[s : s + chunk, None, :]
        ax, ay, az = (tri[None, :, 0, i] - p[..., i] for i in range(3))
        bx, by, bz = (tri[None, :, 1, i] - p[..., i] for i in range(3))
        cx, cy, cz = (tri[None, :, 2, i] - p[..., i] for i in range(3))
        la = np.sqrt(ax * ax + ay * ay + az * az)
        lb = np.sqrt(bx * bx + by * by + bz * bz)
        lc = np.sqrt(cx * cx + cy * cy + cz * cz)
        det = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
        ab = ax * bx + ay * by + az * bz
        bc = bx * cx + by * cy + bz * cz
        ca = cx * ax + cy * ay + cz * az
        out[s : s + chunk] = np.arctan2(det, la * lb * lc + ab * lc + bc * la + ca * lb).sum(axis=1)
    return out / (2.0 * np.pi)


@dataclass
class FloodFill:
    """Exterior flood fill of a voxelised surface: ``wall`` voxels hold the surface (grown by one voxel so no
    diagonal gap lets the flood through), ``outside`` empty voxels are reachable from the grid border."""

    lo: np.ndarray
    pitch: float
    wall: np.ndarray
    outside: np.ndarray

    @classmethod
    def build(
        cls, mesh: trimesh.Trimesh, lo: np.ndarray, hi: np.ndarray, cells: int, grow: int = 1, seed: int = 0
    ) -> FloodFill:
        pitch = float((hi - lo).max()) / cells
        shape = np.ceil((hi - lo) / pitch).astype(int) + 1
        # Surface samples a third of a voxel apart mark every voxel a triangle passes through.
        count = int(min(8e6, max(1e4, 9.0 * mesh.area / pitch**2)))
        surface, _ = trimesh.sample.sample_surface(mesh, count, seed=seed)
        wall = np.zeros(shape, bool)
        idx = np.clip(((np.concatenate([surface, mesh.vertices]) - lo) / pitch).astype(int), 0, shape - 1)
        wall[idx[:, 0], idx[:, 1], idx[:, 2]] = True
        wall = ndimage.binary_dilation(wall, structure=np.ones((3, 3, 3), bool), iterations=grow)
        labels, _ = ndimage.label(~wall)  # 6-connected empty regions
        faces = [labels[0], labels[-1], labels[:, 0], labels[:, -1], labels[:, :, 0], labels[:, :, -1]]
        border = np.unique(np.concatenate([f.ravel() for f in faces]))
        outside = np.isin(labels, border[border > 0])
        return cls(np.asarray(lo, float), pitch, wall, outside)

    def index(self, points: np.ndarray) -> tuple[np.ndarray, ...]:
        idx = np.clip(((points - self.lo) / self.pitch).astype(int), 0, np.array(self.wall.shape) - 1)
        return idx[:, 0], idx[:, 1], idx[:, 2]

    def classify(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(inside, decided)``: decided points lie in empty voxels."""
        i = self.index(points)
        decided = ~self.wall[i]
        return decided & ~self.outside[i], decided


_R = np.arange(-5, 6)
_OFFSETS = np.stack(np.meshgrid(_R, _R, _R, indexing="ij"), axis=-1).reshape(-1, 3)
_OFFSETS = _OFFSETS[np.argsort(np.linalg.norm(_OFFSETS, axis=1), kind="stable")]


def flood_fill_inside(
    mesh: trimesh.Trimesh,
    scene: o3d.t.geometry.RaycastingScene,
    points: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    cells: int = 192,
    grow: int = 1,
    seed: int = 0,
) -> np.ndarray:
    """Inside (bool per point) by exterior flood fill on a grid over [lo, hi] with ``cells`` voxels along its
    longest side. Band points walk from their nearest surface point away from it and take the label of the first
    empty voxel; points whose walk stays in the band take the label of the empty voxel nearest to them."""
    fill = FloodFill.build(mesh, lo, hi, cells, grow, seed)
    points = np.asarray(points, float)
    inside, decided = fill.classify(points)
    band = np.flatnonzero(~decided)
    if len(band):
        p = points[band]
        closest = scene.compute_closest_points(o3d.core.Tensor(p.astype(np.float32)))["points"].numpy()
        away = p - closest
        norm = np.linalg.norm(away, axis=1, keepdims=True)
        away = np.where(norm > 1e-9, away / np.maximum(norm, 1e-12), 0.0)
        label = np.zeros(len(band), bool)
        todo = np.ones(len(band), bool)
        for step in np.arange(0.5, 2 * grow + 4.01, 0.5) * fill.pitch:
            if not todo.any():
                break
            probe = closest[todo] + away[todo] * step
            probe_inside, probe_decided = fill.classify(probe)
            which = np.flatnonzero(todo)[probe_decided]
            label[which] = probe_inside[probe_decided]
            todo[which] = False
        if todo.any():
            # Stuck in the band (e.g. inside near an edge, where walking off one face runs along the other): take
            # the label of the empty voxel nearest to the point's own voxel, searched outwards up to 5 voxels.
            stuck = np.flatnonzero(todo)
            base = np.stack(fill.index(p[stuck]), axis=1)
            shape = np.array(fill.wall.shape)
            for offset in _OFFSETS:
                cell = np.clip(base + offset, 0, shape - 1)
                empty = ~fill.wall[cell[:, 0], cell[:, 1], cell[:, 2]]
                if empty.any():
                    hit = cell[empty]
                    label[stuck[empty]] = ~fill.outside[hit[:, 0], hit[:, 1], hit[:, 2]]
                    stuck, base = stuck[~empty], base[~empty]
                    if not len(stuck):
                        break
        inside[band] = label
    return inside
