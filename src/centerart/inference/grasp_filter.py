"""Drop grasps whose gripper would collide with what the camera sees.

The gripper is three boxes (palm and two fingers, :func:`centerart.grasps.gripper.gripper_boxes`, fully open). A
grasp collides when more than ``max_points`` observed points lie inside the boxes shrunk by ``margin_m`` (depth
noise on the grasped surface itself must not reject every grasp). Points behind the observed surface are unknown
space and are not checked: this filter removes grasps that hit visible geometry (a neighbouring door, the
counter), not every possible collision.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from centerart.grasps.gripper import MAX_OPENING, gripper_boxes

MIN_HALF_EXTENT_M = 0.004  # the 1 cm thin fingers keep at least 8 mm of checked thickness after the margin


@dataclass(frozen=True)
class CollisionFilterConfig:
    enabled: bool = True
    margin_m: float = 0.005
    max_points: int = 10


def collision_free(grasps: np.ndarray, points, cfg: CollisionFilterConfig) -> np.ndarray:
    """(K,) bool: which TCP poses (K, 4, 4) keep their gripper clear of ``points`` (N, 3), one frame for both.
    ``points`` may be a ``cKDTree`` of them, built once for all the objects of an image."""
    tree = points if isinstance(points, cKDTree) else cKDTree(np.asarray(points, float).reshape(-1, 3))
    points = tree.data
    if len(grasps) == 0 or len(points) == 0:
        return np.ones(len(grasps), bool)
    boxes = gripper_boxes(MAX_OPENING)
    reach = max(np.linalg.norm(t[:3, 3]) + np.linalg.norm(e) / 2 for e, t in boxes)
    keep = np.ones(len(grasps), bool)
    for k, pose in enumerate(grasps):
        near = points[tree.query_ball_point(pose[:3, 3], reach)]
        if len(near) <= cfg.max_points:
            continue
        inside = np.zeros(len(near), bool)
        for extents, tcp_T_box in boxes:
            box = pose @ tcp_T_box
            local = (near - box[:3, 3]) @ box[:3, :3]
            half = np.maximum(extents / 2 - cfg.margin_m, MIN_HALF_EXTENT_M)
            inside |= np.all(np.abs(local) < half, axis=1)
        keep[k] = inside.sum() <= cfg.max_points
    return keep
