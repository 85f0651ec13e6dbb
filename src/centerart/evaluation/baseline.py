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

#: RANSAC inlier distance (m) of the front-face plane.
PLANE_DISTANCE_M = 0.01
PLANE_ITERATIONS = 500
PLANE_SAMPLE = 4000  # points the hypotheses are scored on
#: Height band (m, along the face normal toward the camera) of handle points.
HANDLE_MIN_HEIGHT_M = 0.015
HANDLE_MAX_HEIGHT_M = 0.09
#: DBSCAN radius (m) and minimum points of a handle cluster.
CLUSTER_EPS_M = 0.02
CLUSTER_MIN_POINTS = 15
#: How far behind the handle's observed front surface (m) the TCP goes: about half a bar's thickness.
GRASP_DEPTH_M = 0.01
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


def handle_clusters(points: np.ndarray, normal: np.ndarray, offset: float) -> list[np.ndarray]:
    """Handle point clusters (each (M, 3)), largest first."""
    import open3d as o3d

    height = points @ normal + offset
    candidates = points[(height > HANDLE_MIN_HEIGHT_M) & (height < HANDLE_MAX_HEIGHT_M)]
    if len(candidates) < CLUSTER_MIN_POINTS:
        return []
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(candidates))
    labels = np.asarray(cloud.cluster_dbscan(CLUSTER_EPS_M, CLUSTER_MIN_POINTS))
    clusters = [candidates[labels == k] for k in range(labels.max() + 1)] if len(labels) else []
    return sorted(clusters, key=len, reverse=True)


def grasp_across(cluster: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """TCP pose (4x4) closing the fingers across the cluster's long axis (in the face plane), approaching along
    ``-normal``, GRASP_DEPTH_M behind the cluster's observed surface."""
    centred = cluster - cluster.mean(axis=0)
    in_plane = centred - np.outer(centred @ normal, normal)
    _, _, vt = np.linalg.svd(in_plane, full_matrices=False)
    z = -normal
    x = vt[0] - (vt[0] @ z) * z
    x /= np.linalg.norm(x)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    pose[:3, 3] = cluster.mean(axis=0) + z * GRASP_DEPTH_M
    return pose


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
