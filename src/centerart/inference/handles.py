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


def handle_clusters(
    points: np.ndarray, normal: np.ndarray, offset: float, min_height: float = HANDLE_MIN_HEIGHT_M
) -> list[np.ndarray]:
    """Handle point clusters (each (M, 3)), largest first: points ``min_height``-HANDLE_MAX_HEIGHT_M (m) proud of
    the plane ``(normal, offset)``, clustered by DBSCAN."""
    import open3d as o3d

    height = points @ normal + offset
    candidates = points[(height > min_height) & (height < HANDLE_MAX_HEIGHT_M)]
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


#: Robust depth noise (m) of a face: 1.4826 x the median absolute height of the points within this band of its
#: plane; a handle must stand NOISE_SIGMAS of it proud (stereo depth: about 1 cm, so 3 cm; true depth: 1.5 cm).
NOISE_BAND_M = 0.03
NOISE_SIGMAS = 3.0


def face_noise(points: np.ndarray, normal: np.ndarray, offset: float) -> float:
    """Robust spread (m) of the observed points about the face plane (see :data:`NOISE_BAND_M`); 0 without points."""
    height = np.asarray(points, float) @ normal + offset
    near = np.abs(height[np.abs(height) < NOISE_BAND_M])
    return float(1.4826 * np.median(near)) if len(near) else 0.0


def handle_min_height(noise_m: float) -> float:
    """How far (m) material must stand proud of a face whose depth noise is ``noise_m`` (:func:`face_noise`) to be a
    handle rather than depth noise: at least HANDLE_MIN_HEIGHT_M, and NOISE_SIGMAS x the noise. Why: stereo depth
    scatters a flat door by 1-2 cm (measured on rendered kitchens: median |error| 0.7-1.8 cm, 10th percentile 2-4 cm
    in front), which the fixed 1.5 cm band calls handles everywhere; real handles stand 3-6 cm proud."""
    return max(HANDLE_MIN_HEIGHT_M, NOISE_SIGMAS * noise_m)
