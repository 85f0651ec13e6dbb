"""Pose conventions used everywhere in centerart.

- Units: metres and radians. All frames are right-handed.
- A pose is a 4x4 homogeneous matrix named ``A_T_B``: it maps coordinates expressed in frame B into frame A,
  ``p_A = A_T_B @ p_B``. Composition reads left to right: ``A_T_C = A_T_B @ B_T_C``.
- World frame: z up. Camera frame: OpenCV (x right, y down, z forward).
- Object canonical frame: see :mod:`centerart.assets.canonical_frame`.
- Grasp / TCP frame: see :mod:`centerart.grasps.gripper` (z = approach, y = finger closing direction).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def make_pose(rotation: np.ndarray | None = None, translation: np.ndarray | None = None) -> np.ndarray:
    """Build a 4x4 pose from a 3x3 rotation and a 3-vector translation (either may be omitted)."""
    pose = np.eye(4)
    if rotation is not None:
        pose[:3, :3] = rotation
    if translation is not None:
        pose[:3, 3] = translation
    return pose


def invert_pose(pose: np.ndarray) -> np.ndarray:
    """Inverse of a rigid 4x4 pose (or a stack of them, shape (..., 4, 4)) without a general matrix inverse."""
    rot = pose[..., :3, :3]
    rot_t = np.swapaxes(rot, -1, -2)
    out = np.zeros_like(pose)
    out[..., :3, :3] = rot_t
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", rot_t, pose[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def apply_transform(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map points of shape (N, 3) (or (3,)) from frame B into frame A with ``A_T_B``."""
    points = np.asarray(points, dtype=float)
    return points @ pose[:3, :3].T + pose[:3, 3]


def rotation_about_axis(axis: np.ndarray, angle: float) -> np.ndarray:
    """3x3 rotation by ``angle`` (rad, right-hand rule) about the unit direction ``axis``."""
    axis = np.asarray(axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    return Rotation.from_rotvec(axis * angle).as_matrix()


def transform_about_line(origin: np.ndarray, direction: np.ndarray, angle: float = 0.0, shift: float = 0.0):
    """Rigid motion of a revolute/prismatic joint given as a line in some frame F.

    Rotates by ``angle`` (rad) about the line through ``origin`` with unit ``direction`` and translates by
    ``shift`` (m) along it. Returns the 4x4 ``F_T_F'`` that maps a point of the moved part (in F, at the zero
    state) to where it lies after the motion.
    """
    origin = np.asarray(origin, dtype=float)
    rot = rotation_about_axis(direction, angle)
    direction = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    return make_pose(rot, origin - rot @ origin + shift * direction)


def rotation_angle_between(rot_a: np.ndarray, rot_b: np.ndarray) -> float:
    """Geodesic angle (rad) between two 3x3 rotations."""
    cos = (np.trace(rot_a.T @ rot_b) - 1.0) / 2.0
    return float(np.arccos(np.clip(cos, -1.0, 1.0)))
