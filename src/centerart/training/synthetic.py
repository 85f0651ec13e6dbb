"""Analytic articulated shapes with exact SDFs and known grasps, for tests and benchmarks of the decoder stage.

A *box cabinet*: a static box body (front face at +x, as in the canonical frame) and a thin door in front of it,
hinged about the vertical line at its left edge (y = -w/2, x = front), opening by angle u * pi/2 (u = the
normalized joint code). Labels: TCP poses pinching the door's free edge, approach along the door plane toward
the hinge, fingers closing across the door thickness, at a few heights. Everything in metres, object frame.
Independent of the asset generator and the SDF sampler, so decoder tests do not depend on those stages.
"""

from __future__ import annotations

import numpy as np
import trimesh

from centerart.grasps.gripper import control_points
from centerart.sdf.samples import SdfSamples
from centerart.utils.seeding import item_rng

DOOR_THICKNESS = 0.02
OPEN_ANGLE = np.pi / 2


def box_sdf(p: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Exact SDF of an axis-aligned box centred at the origin with half extents ``half``."""
    q = np.abs(p) - half
    return np.linalg.norm(np.maximum(q, 0.0), axis=-1) + np.minimum(q.max(-1), 0.0)


def sphere_sdf(p: np.ndarray, radius: float) -> np.ndarray:
    return np.linalg.norm(p, axis=-1) - radius


class BoxCabinet:
    def __init__(self, depth: float = 0.3, width: float = 0.35, height: float = 0.3):
        self.half_body = np.array([depth / 2, width / 2, height / 2])
        self.half_door = np.array([DOOR_THICKNESS / 2, width / 2, height / 2])
        self.hinge = np.array([depth / 2, -width / 2, 0.0])

    def door_T(self, u: float) -> np.ndarray:
        """object_T_door: the door frame (origin at the door centre) at joint code u."""
        a = -u * OPEN_ANGLE  # negative about z: the free edge (+y) swings out toward +x
        c, s = np.cos(a), np.sin(a)
        rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
        closed_centre = np.array([self.half_body[0] + DOOR_THICKNESS / 2, 0.0, 0.0])
        T = np.eye(4)
        T[:3, :3] = rz
        T[:3, 3] = self.hinge + rz @ (closed_centre - self.hinge)
        return T

    def sdf(self, p: np.ndarray, u: float) -> np.ndarray:
        T = self.door_T(u)
        local = (p - T[:3, 3]) @ T[:3, :3]
        return np.minimum(box_sdf(p, self.half_body), box_sdf(local, self.half_door))

    def mesh(self, u: float) -> trimesh.Trimesh:
        body = trimesh.creation.box(extents=2 * self.half_body)
        door = trimesh.creation.box(extents=2 * self.half_door, transform=self.door_T(u))
        return trimesh.util.concatenate([body, door])

    def door_mesh(self, u: float) -> trimesh.Trimesh:
        return trimesh.creation.box(extents=2 * self.half_door, transform=self.door_T(u))

    def grasps(self, u: float, n: int = 5) -> np.ndarray:
        """(n, 4, 4) TCP poses pinching the free edge of the door (object frame)."""
        T = self.door_T(u)
        poses = []
        for z in np.linspace(-0.6, 0.6, n) * self.half_door[2]:
            # In the door frame: free edge at +y; approach -y (toward the hinge), close along x (thickness).
            R_door = np.column_stack([[0, 0, -1.0], [1.0, 0, 0], [0, -1.0, 0]])  # x_tcp=-z, y_tcp=x, z_tcp=-y
            t_door = np.array([0.0, self.half_door[1] - 0.01, z])
            P = np.eye(4)
            P[:3, :3] = T[:3, :3] @ R_door
            P[:3, 3] = T[:3, :3] @ t_door + T[:3, 3]
            poses.append(P)
        return np.stack(poses)

    def samples(self, object_id: str, state_index: int, u: float, n: int = 20000, seed: int = 0) -> SdfSamples:
        """SDF samples like ``centerart sdf generate`` writes: 80% near the surface, 20% uniform in the box."""
        rng = item_rng(seed, "box_cabinet", object_id, state_index)
        mesh = self.mesh(u)
        n_near = int(0.8 * n)
        surf, _ = trimesh.sample.sample_surface(mesh, n_near, seed=int(rng.integers(1 << 31)))
        near = surf + rng.normal(0, 1, (n_near, 3)) * np.where(rng.random((n_near, 1)) < 0.5, 0.005, 0.03)
        lo, hi = mesh.bounds[0] - 0.1, mesh.bounds[1] + 0.1
        uni = rng.uniform(lo, hi, (n - n_near, 3))
        pts = np.concatenate([near, uni]).astype(np.float32)
        sdf = self.sdf(pts.astype(np.float64), u).astype(np.float32)
        poses = self.grasps(u)
        tcp = poses[:, :3, 3]
        d = np.linalg.norm(pts[:, None, :] - tcp[None], axis=-1)
        nearest = d.argmin(1)
        cps = control_points(poses)
        return SdfSamples(
            object_id=object_id,
            state_index=state_index,
            q=float(u * OPEN_ANGLE),
            q_normalized=float(u),
            joint_type="revolute",
            points=pts,
            sdf=sdf,
            grasp_points=cps[nearest].astype(np.float32),
            grasp_distance=d[np.arange(len(pts)), nearest].astype(np.float32),
        )


def write_box_cabinet_dataset(
    folder, n_objects: int = 3, n_states: int = 4, n_points: int = 20000, seed: int = 0
) -> list[BoxCabinet]:
    """Write a small SDF dataset of box cabinets of different sizes to ``folder``; returns the shapes."""
    rng = item_rng(seed, "box_cabinet_sizes")
    shapes = []
    for i in range(n_objects):
        shape = BoxCabinet(*rng.uniform([0.25, 0.3, 0.25], [0.4, 0.45, 0.4]))
        shapes.append(shape)
        for k, u in enumerate(np.linspace(0.0, 1.0, n_states)):
            shape.samples(f"box_{i:03d}", k, float(u), n_points, seed).save(folder)
    return shapes
