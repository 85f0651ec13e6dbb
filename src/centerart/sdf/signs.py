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
give 0 everywhere). Both soup methods work part by part (one piece per named part of a link, see the comment
above :func:`soup_escape_inside`): a point is inside the object when it is inside one of its parts.

- sign: :func:`ray_escape_inside`, a point is outside a piece when at least one ray leaves it without a hit,
  i.e. when it can be seen from outside: 256 evenly spread rays, then one ray aimed through each opening of the
  piece (:func:`opening_targets`, points just beyond its open edges), which finds an opening however small it
  looks from the point. The visibility convention of DeepSDF-style data (depth scans from a sphere of cameras)
  on exact geometry, so closed boards thinner than any voxel stay solid. The SDF gives every sheet a thin shell
  (see :mod:`centerart.sdf.sampling`), so open sheets have an inside too.
- check: :func:`flood_fill_inside`, empty space the flood from the grid border cannot reach is inside, on a grid
  per piece fine enough to give its thinnest side an interior (:func:`flood_pitch`) and laid out where the piece
  is when the object is closed (so a door's grid does not change as it opens); points in wall voxels take
  the label of the first empty voxel found by walking away from their nearest surface point. Voxels and
  connectivity, no rays. The two differ on pockets reached only by a bent path (flood: outside), and on
  openings between the aimed rays' offset (2 mm) and the flood's closing (one voxel). Before the aimed rays
  they also differed on slabs behind small openings (a slot for a handle, the open end of a board), which
  spread rays rarely found; ``benchmarks/sdf_sign_disagreement.py`` measures where, docs/sdf.md has the figures.

Flat pieces (:func:`encloses_volume`) have no inside and are skipped by both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d
import trimesh
from scipy import ndimage

from centerart.geometry.transforms import apply_transform


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
    scene: o3d.t.geometry.RaycastingScene,
    points: np.ndarray,
    rays: int = 256,
    seed: int = 1,
    min_escaping: int = 1,
    targets: np.ndarray | None = None,
    chunk: int = 20_000,
    chunk_rays: int = 4_000_000,
) -> np.ndarray:
    """Inside (bool per point) unless at least ``min_escaping`` rays leave without a hit: ``rays`` evenly spread
    directions, then, for points still undecided, one ray aimed at each of ``targets`` (points in the openings
    of the surface, see :func:`opening_targets`).

    ``min_escaping`` > 1 makes a crack that only a ray or two find count as closed. Most outside points escape
    along several of the first few directions, so every point first tries a spread subset of 32 rays and only
    the points still undecided try the rest. Why aimed rays: evenly spread rays miss an opening that looks small
    from the point (a 2 cm slot seen from 40 cm, the open end of a 2 cm board seen from its middle); whether
    such a point was called inside then depended on the ray seed and count (1.6-2.3% of the points of three
    real objects flipped with the seed). A ray through each opening finds it whatever its size."""
    dirs = ray_directions(rays, seed).astype(np.float32)
    stride = max(1, rays // 32)
    first, rest = dirs[::stride], np.delete(dirs, np.arange(0, rays, stride), axis=0)
    points = np.asarray(points, np.float32)
    inside = np.zeros(len(points), bool)
    for s in range(0, len(points), chunk):
        p = points[s : s + chunk]
        escaping = (~scene.test_occlusions(_ray_tensor(p, first)).numpy()).sum(axis=1)
        todo = np.flatnonzero(escaping < min_escaping)
        if len(rest) and len(todo):
            escaping[todo] += (~scene.test_occlusions(_ray_tensor(p[todo], rest)).numpy()).sum(axis=1)
        inside[s : s + chunk] = escaping < min_escaping
    if targets is not None and len(targets):
        todo = np.flatnonzero(inside)
        targets = np.asarray(targets, np.float32)
        step = max(1, chunk_rays // len(targets))
        for s in range(0, len(todo), step):
            which = todo[s : s + step]
            p = points[which]
            aim = targets[None] - p[:, None]
            aim /= np.maximum(np.linalg.norm(aim, axis=2, keepdims=True), 1e-9)
            rays_aimed = np.concatenate([np.broadcast_to(p[:, None], aim.shape), aim], axis=2)
            escaping = (~scene.test_occlusions(o3d.core.Tensor(rays_aimed)).numpy()).sum(axis=1)
            inside[which] = escaping < min_escaping
    return inside


def opening_targets(mesh: trimesh.Trimesh, spacing: float = 0.01, offset: float = 0.002) -> np.ndarray:
    """(M, 3) points in the openings of a triangle soup: along every open edge (an edge of one triangle only),
    ``spacing`` m apart, moved ``offset`` m off the edge in its triangle's plane, away from the triangle.

    An opening narrower than ``offset`` (a seam between two sheets that meet without sharing vertices) puts the
    point on or behind the neighbouring sheet, so a ray through it does not escape: such seams stay closed, as
    in the flood fill's one-voxel closing. Closed meshes have no open edges and no targets."""
    open_edges = trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1)
    if not len(open_edges):
        return np.zeros((0, 3))
    v = np.asarray(mesh.vertices, float)
    face = mesh.edges_face[open_edges]
    a, b = v[mesh.edges[open_edges, 0]], v[mesh.edges[open_edges, 1]]
    third = v[mesh.faces[face]].sum(axis=1) - a - b
    away = np.cross(mesh.face_normals[face], b - a)
    away /= np.maximum(np.linalg.norm(away, axis=1, keepdims=True), 1e-12)
    away *= np.where(np.einsum("ij,ij->i", third - a, away) > 0, -1.0, 1.0)[:, None]
    per_edge = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / spacing)).astype(int)
    edge = np.repeat(np.arange(len(open_edges)), per_edge)
    t = (np.arange(len(edge)) - np.repeat(np.cumsum(per_edge) - per_edge, per_edge) + 0.5) / per_edge[edge]
    return a[edge] + t[:, None] * (b - a)[edge] + offset * away[edge]


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
    """Exterior flood fill of a voxelised surface with a morphological closing of ``grow`` voxels.

    ``wall`` voxels hold surface samples. The flood runs from the grid border through empty voxels after the walls
    are grown by ``grow`` voxels, so cracks and holes narrower than about ``2 * grow`` voxels do not let it in; the
    flooded region is then grown back by ``grow`` voxels (never through a wall voxel), so that the exterior again
    reaches the walls. ``outside`` is that exterior: the complement of the closed solid.
    """

    lo: np.ndarray
    pitch: float
    wall: np.ndarray
    outside: np.ndarray

    @classmethod
    def build(
        cls, mesh: trimesh.Trimesh, lo: np.ndarray, hi: np.ndarray, pitch: float, grow: int = 1, seed: int = 0
    ) -> FloodFill:
        shape = np.ceil((np.asarray(hi) - lo) / pitch).astype(int) + 1
        # Surface samples a third of a voxel apart mark every voxel a triangle passes through. open3d's sampler
        # (C++) rather than trimesh's: 3-4x faster on the millions of samples a finely gridded board needs.
        count = int(min(8e6, max(1e4, 9.0 * mesh.area / pitch**2)))
        o3d.utility.random.seed(seed)
        o3d_mesh = o3d.geometry.TriangleMesh(
            o3d.utility.Vector3dVector(np.asarray(mesh.vertices, float)),
            o3d.utility.Vector3iVector(np.asarray(mesh.faces, np.int32)),
        )
        surface = np.asarray(o3d_mesh.sample_points_uniformly(count).points)
        wall = np.zeros(shape, bool)
        idx = np.clip(((np.concatenate([surface, mesh.vertices]) - lo) / pitch).astype(int), 0, shape - 1)
        wall[idx[:, 0], idx[:, 1], idx[:, 2]] = True
        cube = np.ones((3, 3, 3), bool)
        grown = ndimage.binary_dilation(wall, structure=cube, iterations=grow)
        labels, _ = ndimage.label(~grown)  # 6-connected empty regions
        faces = [labels[0], labels[-1], labels[:, 0], labels[:, -1], labels[:, :, 0], labels[:, :, -1]]
        border = np.unique(np.concatenate([f.ravel() for f in faces]))
        outside = np.isin(labels, border[border > 0])
        outside = ndimage.binary_dilation(outside, structure=cube, iterations=grow, mask=~wall)
        return cls(np.asarray(lo, float), pitch, wall, outside)

    def index(self, points: np.ndarray) -> tuple[np.ndarray, ...]:
        idx = np.clip(((points - self.lo) / self.pitch).astype(int), 0, np.array(self.wall.shape) - 1)
        return idx[:, 0], idx[:, 1], idx[:, 2]

    def classify(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(inside, decided)``: decided points lie in voxels without surface."""
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
    pitch: float,
    grow: int = 1,
    seed: int = 0,
) -> np.ndarray:
    """Inside (bool per point) by exterior flood fill (:class:`FloodFill`) on a grid of ``pitch`` m voxels over
    [lo, hi]. Points in wall voxels walk from their nearest surface point away from it and take the label of the
    first voxel without surface; points whose walk stays in the walls take the label of the nearest such voxel."""
    fill = FloodFill.build(mesh, lo, hi, pitch, grow, seed)
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
        for step in np.arange(0.5, 4.01, 0.5) * fill.pitch:
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


# Triangle soups, part by part. A real object's solid is the union of its parts' solids: each named part of a
# PartNet-Mobility link (a board, a door panel, a handle) is classified alone and a point is inside when it is
# inside any of them. Classifying the whole soup at once would call every cavity enclosed by several parts solid
# (a cabinet's interior behind a closed door, a compartment behind a fixed panel), and would change that with
# the joint state as the door opens; generated objects (exact union of closed parts) keep those cavities empty.


def _in_box(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return np.flatnonzero(np.all((points >= lo - 1e-4) & (points <= hi + 1e-4), axis=1))


def encloses_volume(piece: trimesh.Trimesh, tol: float = 1e-4) -> bool:
    """False when all of the piece's vertices lie within ``tol`` m of one plane (a flat sheet: a glass pane, a
    back panel drawn as one quad). Such a piece has no inside, so both soup methods skip it; the flood check
    would otherwise give its zero thickness a grid at the voxel cap (a quarter of the check's time on 40147)."""
    v = np.asarray(piece.vertices, float)
    v = v - v.mean(axis=0)
    normal = np.linalg.svd(v, full_matrices=False)[2][-1]
    return bool(np.ptp(v @ normal) > tol)


def soup_escape_inside(
    pieces: list[trimesh.Trimesh],
    points: np.ndarray,
    rays: int = 256,
    min_escaping: int = 1,
    seed: int = 1,
    opening_spacing: float = 0.01,
    opening_offset: float = 0.002,
) -> np.ndarray:
    """:func:`ray_escape_inside` per piece, with rays aimed through the piece's openings
    (:func:`opening_targets`; ``opening_spacing`` <= 0 turns them off); points inside any piece are inside. Only
    points within a piece's bounding box can be inside it, so each point is tested against the few pieces around
    it."""
    points = np.asarray(points, np.float32)
    inside = np.zeros(len(points), bool)
    for _, piece, sel in _pieces_and_nearby_points(pieces, points):
        targets = opening_targets(piece, opening_spacing, opening_offset) if opening_spacing > 0 else None
        inside[sel] |= ray_escape_inside(
            raycasting_scene(piece), points[sel], rays, seed, min_escaping, targets=targets
        )
    return inside


def _pieces_and_nearby_points(pieces: list[trimesh.Trimesh], points: np.ndarray):
    """(index, piece, indices of the points in its bounding box) for every piece that encloses a volume and has
    points around it."""
    for k, piece in enumerate(pieces):
        if encloses_volume(piece):
            sel = _in_box(points, *piece.bounds)
            if len(sel):
                yield k, piece, sel


def flood_pitch(extents: np.ndarray, cells: int, thin_cells: int, max_voxels: float) -> float:
    """Voxel size (m) for a piece with bounding-box ``extents``: ``cells`` voxels along its longest side and at
    least ``thin_cells`` across its thinnest (a 2 cm board must have an interior of empty voxels), but no more
    than ``max_voxels`` voxels in all."""
    ext = np.maximum(np.asarray(extents, float), 1e-3)
    pitch = min(ext.max() / cells, ext.min() / thin_cells)
    return float(max(pitch, (np.prod(ext) / max_voxels) ** (1.0 / 3.0)))


def soup_flood_fill_inside(
    pieces: list[trimesh.Trimesh],
    points: np.ndarray,
    cells: int = 256,
    thin_cells: int = 12,
    max_voxels: float = 4e6,
    grow: int = 1,
    seed: int = 0,
    frames: list[np.ndarray] | None = None,
) -> np.ndarray:
    """:func:`flood_fill_inside` per piece on a grid sized by :func:`flood_pitch`, walls closed by ``grow``
    voxels; points inside any piece are inside. ``frames`` (4x4 per piece, optional) move each piece and the
    points into the frame its grid is aligned with (see :attr:`ObjectSurface.piece_frames`)."""
    points = np.asarray(points, float)
    inside = np.zeros(len(points), bool)
    for k, piece, sel in _pieces_and_nearby_points(pieces, points):
        p = points[sel]
        if frames is not None and not np.allclose(frames[k], np.eye(4)):
            piece = piece.copy()
            piece.apply_transform(frames[k])
            p = apply_transform(frames[k], p)
        lo, hi = piece.bounds
        pitch = flood_pitch(hi - lo, cells, thin_cells, max_voxels)
        pad = (grow + 3) * pitch
        inside[sel] |= flood_fill_inside(piece, raycasting_scene(piece), p, lo - pad, hi + pad, pitch, grow, seed)
    return inside
