"""The non-learned reference row: grasp the handle found in the object's observed depth points.

What a robotics engineer would try first, given the object's true instance mask (so the baseline never misses an
object; its failures are grasp failures): back-project the masked depth pixels, fit the front face as the dominant
plane (RANSAC), call the points that stand :data:`HANDLE_MIN_HEIGHT_M`-:data:`HANDLE_MAX_HEIGHT_M` proud of it
toward the camera handle points, cluster them, and grasp each cluster (largest first) across its long axis,
approaching against the face normal. An object without a handle cluster gets no grasp (a failure).

Frames: everything in the OpenCV camera frame (metres); grasps are TCP poses (z approach, y finger closing,
:mod:`centerart.grasps.gripper`).
"""

from __future__ import annotations

import numpy as np

from centerart.geometry.planes import ransac_plane
from centerart.inference.handles import (
    CLUSTER_EPS_M,
    CLUSTER_MIN_POINTS,
    GRASP_DEPTH_M,
    HANDLE_MAX_HEIGHT_M,
    HANDLE_MIN_HEIGHT_M,
    grasp_across,
    handle_clusters,
)

#: RANSAC inlier distance (m) of the front-face plane.
PLANE_DISTANCE_M = 0.01
PLANE_ITERATIONS = 500
PLANE_SAMPLE = 4000  # points the hypotheses are scored on
MAX_POINTS = 20_000
MAX_GRASPS = 5


def thresholds() -> dict:
    return {
        "plane_distance_m": PLANE_DISTANCE_M,
        "handle_height_m": [HANDLE_MIN_HEIGHT_M, HANDLE_MAX_HEIGHT_M],
        "cluster_eps_m": CLUSTER_EPS_M,
        "cluster_min_points": CLUSTER_MIN_POINTS,
        "grasp_depth_m": GRASP_DEPTH_M,
    }


def front_plane(points: np.ndarray, seed: int = 0) -> tuple[np.ndarray, float] | None:
    """(unit normal toward the camera, offset d) with ``n . p + d = 0`` on the dominant plane, or None.

    The deterministic RANSAC of :func:`centerart.geometry.planes.ransac_plane` with the baseline's thresholds."""
    plane = ransac_plane(points, PLANE_DISTANCE_M, PLANE_ITERATIONS, PLANE_SAMPLE, seed)
    return None if plane is None else (plane[0], plane[1])


def baseline_grasps(points: np.ndarray, seed: int = 0) -> np.ndarray:
    """(G, 4, 4) ranked TCP poses (camera frame) for one object's observed points (N, 3), G <= MAX_GRASPS."""
    points = np.asarray(points, float).reshape(-1, 3)
    points = points[np.isfinite(points).all(axis=1)]
    if len(points) > MAX_POINTS:
        points = points[np.random.default_rng(seed).choice(len(points), MAX_POINTS, replace=False)]
    plane = front_plane(points, seed)
    if plane is None:
        return np.zeros((0, 4, 4))
    clusters = handle_clusters(points, *plane)[:MAX_GRASPS]
    return np.array([grasp_across(c, plane[0]) for c in clusters]).reshape(-1, 4, 4)
