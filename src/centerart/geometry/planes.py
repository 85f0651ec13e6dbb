"""Plane fitting in point clouds: a deterministic RANSAC, written once (used by the baseline and gravity).

A plane is ``(n, d)`` with unit normal ``n`` and ``n . p + d = 0`` for points ``p`` on it, in whatever frame the
points are given (metres). When the points are in a camera frame the normal is turned toward the camera (origin).
"""

from __future__ import annotations

import numpy as np


def ransac_plane(
    points: np.ndarray,
    distance_m: float,
    iterations: int = 500,
    sample: int = 4000,
    seed: int = 0,
    normal_cone: tuple[np.ndarray, float] | None = None,
) -> tuple[np.ndarray, float, np.ndarray] | None:
    """(unit normal toward the origin, offset d, inlier mask over ``points``) of the dominant plane, or None.

    ``points``: (N, 3), metres; ``distance_m``: inlier distance. None when there are under 50 points, every
    hypothesis is degenerate, or the winner has under 30 inliers. ``normal_cone`` ``(unit direction, max angle
    in radians)``: only hypotheses whose normal, turned toward the origin, lies within that cone are scored (the
    largest plane of an expected orientation, e.g. the floor, rather than the largest plane).

    RANSAC written here rather than open3d's ``segment_plane``: that one runs its iterations in parallel and
    returns slightly different planes from run to run even when seeded, and evaluation records must be
    reproducible. All hypotheses are scored at once on a subsample of ``sample`` points, the winner is refit (SVD)
    to its inliers among all points.
    """
    points = np.asarray(points)  # no cast: the baseline's float32 clouds keep their exact results
    if len(points) < 50:
        return None
    rng = np.random.default_rng(seed)
    subset = points if len(points) <= sample else points[rng.choice(len(points), sample, replace=False)]
    tri = subset[rng.integers(0, len(subset), (iterations, 3))]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normals, axis=1)
    keep = length > 1e-9
    if not keep.any():
        return None
    normals = normals[keep] / length[keep, None]
    offsets = -np.einsum("ij,ij->i", normals, tri[keep, 0])
    if normal_cone is not None:
        toward = np.where(offsets < 0, -1.0, 1.0)  # n . 0 + d > 0: the origin on the normal's side
        normals, offsets = normals * toward[:, None], offsets * toward
        inside = normals @ np.asarray(normal_cone[0], dtype=float) >= np.cos(normal_cone[1])
        if not inside.any():
            return None
        normals, offsets = normals[inside], offsets[inside]
    counts = (np.abs(subset @ normals.T + offsets) < distance_m).sum(axis=0)
    best = int(np.argmax(counts))
    mask = np.abs(points @ normals[best] + offsets[best]) < distance_m
    if mask.sum() < 30:
        return None
    inliers = points[mask]
    centroid = inliers.mean(axis=0)
    n = np.linalg.svd(inliers - centroid, full_matrices=False)[2][2]
    if n @ centroid > 0:  # the camera is at the origin: face the normal toward it
        n = -n
    return n, float(-n @ centroid), mask
