"""Handles in observed depth points: material standing proud of an object's front face, and the grasp across it.

Shared by the geometric baseline (``evaluation/baseline.py``) and the predictor's grasp anchoring
(:mod:`centerart.inference.grasp_anchoring`), which uses the same height band as its handle cue.

Frames: the OpenCV camera frame (metres); grasps are TCP poses (z approach, y finger closing,
:mod:`centerart.grasps.gripper`). A front plane is ``(n, d)`` with ``n . p + d = 0`` and ``n`` toward the camera.
"""

from __future__ import annotations

import numpy as np

#: Height band (m, along the face normal toward the camera) of handle points.
HANDLE_MIN_HEIGHT_M = 0.015
HANDLE_MAX_HEIGHT_M = 0.09
#: DBSCAN radius (m) and minimum points of a handle cluster.
CLUSTER_EPS_M = 0.02
CLUSTER_MIN_POINTS = 15
#: How far behind the handle's observed front surface (m) the TCP goes: about half a bar's thickness.
GRASP_DEPTH_M = 0.01


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
