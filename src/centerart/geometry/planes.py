"""Plane fitting on point clouds: a deterministic RANSAC for the dominant plane of a set of points.

Frames: any frame whose origin is the camera (the fitted normal is turned toward the origin); metres.
"""

from __future__ import annotations

import numpy as np

#: RANSAC inlier distance (m), hypotheses, and how many points each hypothesis is scored on.
PLANE_DISTANCE_M = 0.01
PLANE_ITERATIONS = 500
PLANE_SAMPLE = 4000


def dominant_plane(
    points: np.ndarray,
    seed: int = 0,
    distance: float = PLANE_DISTANCE_M,
    iterations: int = PLANE_ITERATIONS,
    sample_size: int = PLANE_SAMPLE,
) -> tuple[np.ndarray, float] | None:
    """(unit normal toward the origin (the camera), offset d) with ``n . p + d = 0`` on the plane holding the most
    of ``points`` (N, 3) within ``distance`` m, or None with too few points or inliers.

    RANSAC written here rather than open3d's ``segment_plane``: that one runs its iterations in parallel and
    returns slightly different planes from run to run even when seeded, and the evaluation's records must be
    reproducible. All hypotheses are scored at once on a subsample, the winner is refit to its inliers."""
    points = np.asarray(points, float).reshape(-1, 3)
    if len(points) < 50:
        return None
    rng = np.random.default_rng(seed)
    sample = points if len(points) <= sample_size else points[rng.choice(len(points), sample_size, replace=False)]
    tri = sample[rng.integers(0, len(sample), (iterations, 3))]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normals, axis=1)
    keep = length > 1e-9
    if not keep.any():
        return None
    normals = normals[keep] / length[keep, None]
    offsets = -np.einsum("ij,ij->i", normals, tri[keep, 0])
    counts = (np.abs(sample @ normals.T + offsets) < distance).sum(axis=0)
    best = int(np.argmax(counts))
    inliers = points[np.abs(points @ normals[best] + offsets[best]) < distance]
    if len(inliers) < 30:
        return None
    centroid = inliers.mean(axis=0)
    n = np.linalg.svd(inliers - centroid, full_matrices=False)[2][2]
    if n @ centroid > 0:  # the camera is at the origin: face the normal toward it
        n = -n
    return n, float(-n @ centroid)
