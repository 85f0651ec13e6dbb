"""Grasp candidates on the movable part of an articulated object at one joint state.

Frames: every pose here is a TCP pose (:mod:`centerart.grasps.gripper`) in the object's canonical frame, metres.

Two sources, mixed by :data:`HANDLE_SHARE` when an object has annotated handles:

- **Handles** (generated objects' ``meta.json`` ``handles``): bar/U handles are grasped across the bar (TCP x
  along the bar, fingers closing across it, approach towards the front face); knobs are grasped around the knob
  head with any roll; lips are pinched across their thickness from the front.
- **Pinchable edges**, found geometrically on the moving part, so that they also work on real
  PartNet-Mobility objects, which have no handle annotation. The solid is the union of the convex hulls of the
  moving links' collision elements (exactly what pybullet simulates: it convex-hulls moving meshes). For a
  surface point with outward normal n, a ray into the solid gives the local thickness t; where
  t < :data:`MAX_PINCH_THICKNESS` the part can be pinched across n. From the mid-thickness point, rays in the
  plane perpendicular to n find a nearby free edge (closer than :data:`EDGE_REACH`, with open space beyond it):
  the hand approaches that edge from outside. This finds door edges, drawer-front and tray top edges, lips,
  handle bars and their standoffs.

Orientation = the analytic frame from the local geometry (approach against the edge direction or the front
normal, closing across the thickness or the bar) times a random rotation (:data:`EDGE_PERTURB_DEG`,
:data:`HANDLE_PERTURB_DEG`) and a random 180-degree flip about the approach axis, so orientations are
continuously diverse. The physics check decides which candidates are good.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.mesh_ops import union
from centerart.geometry.transforms import make_pose
from centerart.grasps.gripper import FINGER_THICKNESS, FINGER_WIDTH, FLIP_Z, MAX_OPENING

MAX_PINCH_THICKNESS = MAX_OPENING - 0.012  # m: leave 6 mm of finger travel on each side
MIN_PINCH_THICKNESS = 0.0003  # m: thinner is a ray artefact (PartNet doors can be 0.6 mm panels)
EDGE_REACH = 0.03  # m from the mid-thickness point to the edge it approaches
EDGE_FREE_SPACE = 0.03  # m of free space the fingers need beyond the edge
EDGE_DIRECTIONS = 12  # in-plane directions tried per surface point
SURFACE_SAMPLES = 6000  # surface points per (object, state) to look for pinchable edges
EDGE_DEPTH = (0.004, 0.010)  # m the TCP sits inside the edge (pads 2 cm long: 1.4-2 cm of them overlap)
#: Random rotation (degrees) about the TCP axes (x, y, z) for edge and handle candidates. Edges: tilting about
#: y swings the approach within the part's plane, about x tilts it out of the plane, z rolls the fingers.
EDGE_PERTURB_DEG = (20.0, 35.0, 20.0)
HANDLE_PERTURB_DEG = (50.0, 12.0, 15.0)  # about x = the bar axis: approach anywhere around the bar
HANDLE_SHARE = 0.5  # fraction of candidates drawn from annotated handles when there are any
POSITION_JITTER = 0.003  # m, uniform per axis


@dataclass(frozen=True)
class EdgeSites:
    """Pinchable edge sites: TCP centre at the edge, approach direction (unit, into the part), closing
    direction (unit, across the thickness), all (N, 3) in the canonical frame."""

    edge_points: np.ndarray
    approach: np.ndarray
    closing: np.ndarray
    thickness: np.ndarray

    def __len__(self) -> int:
        return len(self.edge_points)


def moving_pieces(obj: ArticulatedObject, q: float) -> list[trimesh.Trimesh]:
    """Convex hulls of the moving links' collision elements (visual parts if there are none), canonical frame:
    what pybullet simulates, since it convex-hulls the meshes of moving links."""
    parts = [p.mesh for p in obj.parts(q, collision=True) if p.link in obj.moving_links]
    if not parts:
        parts = [p.mesh for p in obj.parts(q) if p.link in obj.moving_links]
    with np.errstate(all="ignore"):  # flat PartNet pieces give degenerate hulls (zero volume): skipped below
        hulls = [m.convex_hull for m in parts if len(m.vertices) >= 4]
    return [h for h in hulls if h.volume > 1e-9]


def moving_solid(obj: ArticulatedObject, q: float, pieces: list[trimesh.Trimesh] | None = None) -> trimesh.Trimesh:
    """The moving part as pybullet simulates it: the union of :func:`moving_pieces` (canonical frame)."""
    hulls = moving_pieces(obj, q) if pieces is None else pieces
    try:
        return union(hulls)
    except ValueError:
        return trimesh.util.concatenate(hulls)


def _first_hits(mesh: trimesh.Trimesh, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Distance along each ray to its first hit (inf where none)."""
    out = np.full(len(origins), np.inf)
    if len(origins) == 0:
        return out
    locs, ray_idx, _ = mesh.ray.intersects_location(origins, dirs, multiple_hits=False)
    if len(ray_idx):
        out[ray_idx] = np.einsum("ij,ij->i", locs - origins[ray_idx], dirs[ray_idx])
    return out


def find_edge_sites(
    solid: trimesh.Trimesh,
    rng: np.random.Generator,
    samples: int = SURFACE_SAMPLES,
    pieces: list[trimesh.Trimesh] | None = None,
) -> EdgeSites:
    """Pinchable edges of ``solid`` (a closed, outward-oriented mesh); see the module docstring.

    Surface points are drawn area-weighted over ``solid``, or, when ``pieces`` are given, in equal numbers from
    each piece (keeping those on the outside of ``solid``), so that a small handle is not drowned by a big door.
    """
    if not pieces and solid.area <= 0:  # no solid moving geometry (a flat, zero-thickness PartNet door): no edge
        return EdgeSites(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))
    if pieces:
        per_piece = max(samples // len(pieces), 300)
        chunks = [trimesh.sample.sample_surface(m, per_piece, seed=int(rng.integers(2**31))) for m in pieces]
        pts = np.concatenate([c[0] for c in chunks])
        normals = np.concatenate([m.face_normals[c[1]] for m, c in zip(pieces, chunks, strict=True)])
        if solid.is_watertight:
            outside = ~solid.contains(pts + normals * 1e-3)
            pts, normals = pts[outside], normals[outside]
    else:
        pts, faces = trimesh.sample.sample_surface(solid, samples, seed=int(rng.integers(2**31)))
        normals = solid.face_normals[faces]
    eps = 1e-4
    t = _first_hits(solid, pts - eps * normals, -normals)
    ok = (t > MIN_PINCH_THICKNESS) & (t < MAX_PINCH_THICKNESS)
    pts, normals, t = pts[ok], normals[ok], t[ok]
    mids = pts - normals * (t[:, None] / 2)
    # In-plane directions per point: an orthonormal basis (u, v) of the plane perpendicular to n.
    helper = np.where(np.abs(normals[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    u = np.cross(normals, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normals, u)
    angles = np.linspace(0, 2 * np.pi, EDGE_DIRECTIONS, endpoint=False) + rng.uniform(0, 2 * np.pi)
    dirs = np.cos(angles)[None, :, None] * u[:, None] + np.sin(angles)[None, :, None] * v[:, None]  # (P, K, 3)
    origins = np.repeat(mids[:, None], EDGE_DIRECTIONS, axis=1)
    flat_o, flat_d = origins.reshape(-1, 3), dirs.reshape(-1, 3)
    e = _first_hits(solid, flat_o, flat_d)
    near = e < EDGE_REACH
    edge = flat_o + flat_d * np.where(near, e, 0.0)[:, None]
    beyond = _first_hits(solid, edge + flat_d * 0.002, flat_d)
    good = near & (beyond > EDGE_FREE_SPACE)
    idx = np.nonzero(good)[0]
    point_of = idx // EDGE_DIRECTIONS
    return EdgeSites(edge[idx], -flat_d[idx], normals[point_of], t[point_of])


def _frame(approach: np.ndarray, closing: np.ndarray) -> np.ndarray:
    """Rotation with z = approach and y = closing made orthogonal to it (x = y cross z)."""
    z = approach / np.linalg.norm(approach)
    y = closing - z * (closing @ z)
    y /= np.linalg.norm(y)
    return np.stack([np.cross(y, z), y, z], axis=1)


def _perturb(rng: np.random.Generator, limits_deg: tuple[float, float, float]) -> np.ndarray:
    """A random rotation (in the TCP frame) with independent uniform angles about x, y, z, plus a random flip."""
    ax, ay, az = (np.deg2rad(rng.uniform(-lim, lim)) for lim in limits_deg)
    rot = Rotation.from_euler("zyx", [az, ay, ax]).as_matrix()
    if rng.random() < 0.5:
        rot = rot @ FLIP_Z[:3, :3]
    return rot


class CandidateSampler:
    """Draws TCP-pose candidates (canonical frame) for one object at joint state ``q``."""

    def __init__(self, obj: ArticulatedObject, q: float, rng: np.random.Generator):
        self.obj, self.q, self.rng = obj, q, rng
        poses = obj.link_poses(q)
        self.handles = []
        for h in obj.meta.get("handles", []) if obj.generated else []:
            if h["link"] in obj.moving_links and h["type"] in ("bar", "u", "knob", "lip"):
                self.handles.append((h, poses[h["link"]]))
        pieces = moving_pieces(obj, q)
        # Real objects have no handle annotation: sample every collision piece equally so that handles (small
        # pieces) get candidates. Generated objects keep area-weighted sampling; their handles come from meta.
        self.sites = find_edge_sites(moving_solid(obj, q, pieces), rng, pieces=None if obj.generated else pieces)

    def sample(self, n: int) -> tuple[np.ndarray, list[str]]:
        """``n`` candidate TCP poses (n, 4, 4) and their sources ("bar", "u", "knob", "lip", "edge")."""
        poses, sources = [], []
        for _ in range(n):
            use_handle = self.handles and (len(self.sites) == 0 or self.rng.random() < HANDLE_SHARE)
            if use_handle:
                h, link_pose = self.handles[int(self.rng.integers(len(self.handles)))]
                poses.append(self._handle_pose(h, link_pose))
                sources.append(h["type"])
            elif len(self.sites):
                poses.append(self._edge_pose())
                sources.append("edge")
        if not poses:
            return np.zeros((0, 4, 4)), []
        return np.stack(poses), sources

    def _edge_pose(self) -> np.ndarray:
        rng, s = self.rng, self.sites
        i = int(rng.integers(len(s)))
        rot = _frame(s.approach[i], s.closing[i]) @ _perturb(rng, EDGE_PERTURB_DEG)
        depth = rng.uniform(*EDGE_DEPTH)
        pos = s.edge_points[i] + s.approach[i] * depth + rng.uniform(-POSITION_JITTER, POSITION_JITTER, 3)
        return make_pose(rot, pos)

    def _handle_pose(self, h: dict, link_pose: np.ndarray) -> np.ndarray:
        """Analytic grasp on an annotated handle. Link frames of generated doors/drawers have x out of the front
        face and their origin on the front-face plane (assets/builder.py)."""
        rng = self.rng
        center = np.asarray(h["center"], float)
        axis = np.asarray(h["axis"], float)
        front = np.array([1.0, 0.0, 0.0])
        if h["type"] == "knob":
            roll = rng.uniform(0, 2 * np.pi)
            closing = np.cos(roll) * np.cross(front, [0.0, 0.0, 1.0]) + np.sin(roll) * np.array([0.0, 0.0, 1.0])
            rot = _frame(-front, closing) @ _perturb(rng, (12.0, 12.0, 0.0))
            pos = center + rng.uniform(-POSITION_JITTER, POSITION_JITTER, 3)
        else:
            margin = 0.015 + FINGER_WIDTH / 2 + 0.008 if h["type"] in ("bar", "u") else FINGER_WIDTH / 2 + 0.005
            reach = max(0.0, h["length"] / 2 - margin)
            along = axis * rng.uniform(-reach, reach)
            closing = np.cross(-front, axis)
            base = _frame(-front, closing)
            pert = _perturb(rng, HANDLE_PERTURB_DEG if h["type"] != "lip" else (20.0, 12.0, 15.0))
            rot = base @ pert
            if h["type"] == "lip":
                # The lip box spans x in [0, 2 * centre_x] in the link frame: pinch 1 cm below its outer face,
                # keeping the fingertips off the front face.
                outer = 2 * center[0]
                x = max(outer - 0.010, FINGER_THICKNESS / 2 + 0.002)
                pos = np.array([x, *center[1:]]) + along
            else:
                pos = center + along
            pos = pos + rng.uniform(-POSITION_JITTER, POSITION_JITTER, 3)
        return link_pose @ make_pose(rot, pos)
