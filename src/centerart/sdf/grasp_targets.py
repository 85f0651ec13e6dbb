"""Per query point, the labelled grasp whose TCP is nearest: its 5 control points and that distance.

Precomputed once per (object, state) with a KD-tree over the grasps' TCP positions (canonical frame, metres), so
that training reads targets instead of searching. A grasp and the same grasp turned 180 degrees about its approach
axis are one physical grasp; the stored control points are the label's own, and the loss takes the minimum over
the finger swap (``gripper.FINGER_SWAP``).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from centerart.grasps.gripper import control_points


def nearest_grasp_targets(points: np.ndarray, tcp_poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(grasp_points (N, 5, 3), grasp_distance (N,))`` for query ``points`` (N, 3) and TCP poses (G, 4, 4),
    both in the same frame. With no poses: zeros and ``inf``."""
    points = np.asarray(points, np.float64)
    poses = np.asarray(tcp_poses, np.float64).reshape(-1, 4, 4)
    if len(poses) == 0:
        return np.zeros((len(points), 5, 3), np.float32), np.full(len(points), np.inf, np.float32)
    tree = cKDTree(poses[:, :3, 3])
    dist, idx = tree.query(points, k=1, workers=1)
    cps = control_points(poses)  # (G, 5, 3)
    return cps[idx].astype(np.float32), dist.astype(np.float32)
