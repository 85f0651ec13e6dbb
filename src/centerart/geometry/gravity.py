"""Gravity in the camera frame: from a known camera pose, or estimated from the floor seen in the depth.

Frames: OpenCV camera frame (x right, y down, z forward), metres; world z up. Gravity is a unit vector pointing
DOWN (world -z), written in the camera frame.

The estimate (:func:`estimate_gravity`) fits the scene's dominant planes in turn (deterministic RANSAC,
:func:`centerart.geometry.planes.ransac_plane`) and keeps those that could be the floor or another horizontal
support (counter top): large, the camera on their upper side, their downward normal within
:data:`PRIOR_CONE_DEG` of where gravity is expected for a camera pitched :data:`PRIOR_PITCH_DEG` down, and
lying below most of the scene, and wide in both directions (not a strip, whose tilt about its long axis is
ill-determined). The lowest such plane (fewest points under it) gives gravity. Vertical planes (walls, cabinet
fronts, doors) can never pass the cone: their normals are perpendicular to gravity, so at least ``90 - error``
degrees from the prior.
"""

from __future__ import annotations

import numpy as np

from centerart.geometry.planes import ransac_plane

#: Camera pitch (degrees, down from the horizontal) the prior assumes: the middle of the scenes' camera elevations
#: (10-40 degrees above the point of interest, :class:`centerart.scenes.cameras.ShellRanges`, roll sd 3 degrees).
PRIOR_PITCH_DEG = 25.0
#: A support plane's downward normal must lie within this angle of the prior: pitches -5..55 degrees; the scenes'
#: cameras are 15 degrees + roll from the prior at most. Wider cones let slabs that cut diagonally through the
#: scene (walls, floor and cabinets together) in: on the rendered kitchens they sit 40-45 degrees off the prior.
PRIOR_CONE_DEG = 30.0
#: RANSAC inlier distance (m): about the stereo depth's error at 2-3 m (under 3% of the depth, median ~1%).
PLANE_DISTANCE_M = 0.03
PLANE_ITERATIONS = 2000
"""Hypotheses per plane: a plane holding 10% of the remaining points is hit with probability ~0.9."""
PLANE_SAMPLE = 4000
#: Planes extracted in turn (each one's inliers removed before the next).
MAX_PLANES = 6
#: A support plane holds at least this fraction of the scene's points. Stereo depth breaks a far floor into
#: several parallel layers of 5-15% each (measured on the rendered kitchens).
MIN_PLANE_FRACTION = 0.03
MIN_PLANE_POINTS = 200
#: At most this fraction of the scene may lie more than BELOW_MARGIN_M under a support plane (a counter top with
#: cabinet fronts and floor under it passes; a tilted plane cutting through the scene does not).
MAX_BELOW_FRACTION = 0.35
BELOW_MARGIN_M = 0.1
#: A support plane holds at least this many times the points of the equally thick layer just above its inlier
#: band: a surface is denser than the space over it. A slab at the bottom of a uniform cloud scores 0.5.
MIN_CONTRAST = 1.5
#: A support plane's inliers spread at least this far (m, standard deviation) along their narrower in-plane axis.
MIN_PLANE_SPREAD_M = 0.15
#: Points the whole image is subsampled to (deterministic) before fitting.
MAX_POINTS = 60_000


def gravity_from_world_T_camera(world_T_camera: np.ndarray) -> np.ndarray:
    """Unit gravity (world -z) in the camera frame, from the camera's pose ``world_T_camera`` (4x4 or 3x3)."""
    rot = np.asarray(world_T_camera, dtype=float)[:3, :3]
    g = rot.T @ np.array([0.0, 0.0, -1.0])  # camera_R_world = world_R_camera^T
    return g / np.linalg.norm(g)


def prior_gravity() -> np.ndarray:
    """Gravity in the camera frame for a camera pitched :data:`PRIOR_PITCH_DEG` down without roll."""
    p = np.radians(PRIOR_PITCH_DEG)
    return np.array([0.0, np.cos(p), np.sin(p)])


def _spread(inliers: np.ndarray) -> float:
    """Standard deviation (m) of a plane's inliers along their narrower in-plane principal axis."""
    return float(np.linalg.svd(inliers - inliers.mean(0), compute_uv=False)[1] / np.sqrt(len(inliers)))


def support_planes(points_camera: np.ndarray, seed: int = 0) -> list[dict]:
    """The dominant planes of a scene (up to :data:`MAX_PLANES`), each a dict: ``gravity`` (unit, camera frame,
    the normal pointing away from the camera), ``offset`` (m), ``fraction`` of the points on it,
    ``below_fraction`` (points more than BELOW_MARGIN_M under it), ``prior_deg`` (angle to the prior),
    ``spread_m`` (inliers' standard deviation along their narrower in-plane axis), ``contrast`` (inliers over the
    points in the layer (d, 3d] above them, d the inlier distance) and ``plausible`` (passes every
    floor test)."""
    pts = np.asarray(points_camera, dtype=float)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) > MAX_POINTS:
        pts = pts[np.random.default_rng(seed).choice(len(pts), MAX_POINTS, replace=False)]
    total, remaining, prior, planes = len(pts), pts, prior_gravity(), []
    for k in range(MAX_PLANES):
        # Only hypotheses in the prior's cone: the largest planes overall are often walls, or, in stereo depth,
        # slabs of constant depth (fronto-parallel), whose removal would take floor points with them.
        cone = (-prior, np.radians(PRIOR_CONE_DEG))
        fit = ransac_plane(remaining, PLANE_DISTANCE_M, PLANE_ITERATIONS, PLANE_SAMPLE, seed + k, cone)
        if fit is None:
            break
        n, d, mask = fit
        # n faces the camera; gravity points from the camera's side through the plane: -n.
        height = pts @ n + d  # signed height above the plane, every scene point
        plane = {
            "gravity": -n,
            "offset": d,
            "fraction": float(mask.sum() / total),
            "below_fraction": float(np.mean(height < -BELOW_MARGIN_M)),
            "prior_deg": float(np.degrees(np.arccos(np.clip(-n @ prior, -1.0, 1.0)))),
            "spread_m": _spread(remaining[mask]),
            "contrast": float(
                mask.sum() / max(1, np.sum((height > PLANE_DISTANCE_M) & (height <= 3 * PLANE_DISTANCE_M)))
            ),
        }
        plane["plausible"] = bool(
            plane["fraction"] >= MIN_PLANE_FRACTION
            and mask.sum() >= MIN_PLANE_POINTS
            and plane["prior_deg"] <= PRIOR_CONE_DEG
            and plane["below_fraction"] <= MAX_BELOW_FRACTION
            and plane["spread_m"] >= MIN_PLANE_SPREAD_M
            and plane["contrast"] >= MIN_CONTRAST
        )
        planes.append(plane)
        remaining = remaining[~mask]
        if len(remaining) < MIN_PLANE_POINTS:
            break
    return planes


def estimate_gravity(points_camera: np.ndarray, seed: int = 0) -> np.ndarray | None:
    """Unit gravity (pointing down) in the camera frame from a scene's points, or None when no plane could be
    the floor.

    ``points_camera``: (N, 3) points of the whole image back-projected (OpenCV camera frame, m; non-finite rows
    are ignored). The lowest plausible plane (:func:`support_planes`; fewest scene points under it) gives the
    direction: the floor where it is seen, else a counter top (they are parallel). In stereo depth, slabs that cut
    through the scene can hold more points than a noisy floor, so the lowest wins rather than the largest.
    Deterministic for a given ``seed``.
    """
    plausible = [p for p in support_planes(points_camera, seed) if p["plausible"]]
    if not plausible:
        return None
    best = min(plausible, key=lambda p: (p["below_fraction"], -p["fraction"]))
    return best["gravity"] / np.linalg.norm(best["gravity"])
