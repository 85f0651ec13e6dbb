"""Grasps rooted in the observed depth: candidates made where the material is, verified and ranked on it.

The decoder proposes; what the robot executes must agree with what the camera sees (ARCHITECTURE.md). Per
detected object, with its observed points (its predicted mask back-projected, OpenCV camera frame, metres):

1. Candidates (camera frame), from three sources:
   - ``decoder``: the grasps decoded on the predicted surface (:mod:`~.decoder_grasps`), mapped with the pose;
   - ``observed``: the SGDF queried at the object's observed points (and 1.5 / 3 cm in front of them along the
     camera ray), mapped into its canonical frame: each point's predicted offset and rotation are a grasp, as the
     field was trained to give (the nearest grasp to any point); this makes candidates where the camera saw
     material even when the decoded shape is centimetres off;
   - ``handle``: the grasp across each cluster of material standing proud of the object's front plane
     (:mod:`~.handles`, the baseline's handle finder, on the predicted mask).
   Each decoder / observed candidate also comes squared to the front plane (approach against its normal, closing
   axis kept in the plane), since the regressed pose's rotation is 15-25 degrees off.
2. Snap (:func:`~.observed_checks.snap_to_material`): each candidate is moved onto the observed material in front
   of its pads, by a bounded shift along its approach and closing axes.
3. Checks: the closing pads must sweep observed points of the object; the open fingers and palm must stay clear of
   every observed point at the grasp and along the approach (:mod:`~.observed_checks`).
4. Ranking: the grasp critic's physics success probability (its features read from the decoder at the grasp's
   object-frame pose, the same features it was fitted on), times cues a person would use: material proud of the
   front plane (a handle), leverage about the predicted hinge, and an approach from the camera's side.

Every step is counted per object (``AnchoredGrasps.counts``), and the rejected candidates are kept with their
reason for pictures.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from centerart.geometry.planes import ransac_plane
from centerart.geometry.transforms import apply_transform
from centerart.inference.decoder_grasps import (
    GraspExtractionConfig,
    grasp_features,
    grasp_support,
    joint_sdf_change,
    nms_grasps,
)
from centerart.inference.handles import (
    HANDLE_MAX_HEIGHT_M,
    face_noise,
    grasp_across,
    handle_clusters,
    handle_min_height,
)
from centerart.inference.observed_checks import (
    ObservedCheckConfig,
    closing_points,
    collision_points,
    points_between_pads,
    snap_to_material,
)
from centerart.inference.reconstruction import decoder_field
from centerart.models.decoder import decode_outputs
from centerart.models.grasp_critic import ANCHOR_FEATURES, GRASP_FEATURES

SOURCES = ("decoder", "observed", "handle")
#: RANSAC inlier distance (m) of an object's front plane (the baseline's).
FRONT_PLANE_DISTANCE_M = 0.01
#: Depth noise (m) assumed where an object has no front plane to measure it on (stereo-like: the safer guess).
DEFAULT_NOISE_M = 0.01


@dataclass(frozen=True)
class AnchoringConfig:
    """Grasps made on, verified against and re-anchored to the observed points (module doc). On by default."""

    enabled: bool = True
    """Anchor the grasps in the observed depth; off: the decoder's grasps alone, through the proposal's collision
    filter (``PredictorConfig.collision``)."""
    observed_candidates: bool = True
    """Query the SGDF at the object's observed points for candidates (beside the decoded-surface ones)."""
    handle_candidates: bool = True
    """Grasp across material proud of the object's front plane (the baseline's handle finder) as candidates."""
    square: bool = True
    """Also try each decoder / observed candidate squared to the object's front plane."""
    snap: bool = True
    """Move candidates onto the observed material (bounded shift); off: check them where they are."""
    checks: ObservedCheckConfig = field(default_factory=ObservedCheckConfig)
    observed_queries: int = 1200
    """Observed points (subsampled, seeded) at which the SGDF is queried."""
    ray_steps_m: tuple[float, ...] = (0.0, 0.015, 0.03)
    """Each query point also moved this far toward the camera (grasp centres sit in front of a closed door)."""
    max_offset_m: float = 0.03
    """An observed query whose predicted grasp is further away votes for none (the field means "elsewhere")."""
    observed_at_point: bool = False
    """Place each observed candidate at its query point (oriented by the field) instead of at the grasp the field
    points to."""
    observed_pool: int = 40
    """Observed candidates kept after non-maximum suppression."""
    handle_weight: float = 1.0
    """Rank factor 1 + w * (handle cue in [0, 1]): material 0.5-2 cm proud of the front plane between the pads."""
    leverage_floor: float = 0.3
    """Rank factor floor + (1 - floor) * r, r = distance from the predicted hinge / the object's largest (revolute)."""
    facing_floor: float = 0.2
    """Rank factor floor + (1 - floor) * cos, cos = how far the approach points away from the camera (>= 0)."""
    use_ranker: bool = True
    """Rank by the checkpoint's anchored-grasp ranker (``<checkpoint>.anchor_critic.json``) where it has one;
    the factors above rank otherwise."""
    seed: int = 0


@dataclass
class AnchoredGrasps:
    """The kept grasps of one object (camera frame, ranked best first) and what happened to every candidate."""

    poses: np.ndarray
    scores: np.ndarray
    sources: list[str]
    closing_points: np.ndarray
    """(K,) observed points of the object between each kept grasp's pads."""
    features: np.ndarray
    """(K, len(ANCHOR_FEATURES)) what the ranking read of each kept grasp (``grasp_critic.ANCHOR_FEATURES``)."""
    rejected_poses: np.ndarray
    rejected_reasons: list[str]
    counts: dict = field(default_factory=dict)
    """Candidates per source, and how many survived each step: snapped, material between the pads, clear."""


@dataclass
class ObjectView:
    """What anchoring knows of one object: decoder inputs, pose, joint, and its observed points (camera frame)."""

    decoder: object
    code: np.ndarray
    joint: float
    camera_T_object: np.ndarray
    observed: np.ndarray
    joint_type: str
    axis_point: np.ndarray
    axis_direction: np.ndarray
    device: object = "cpu"


def observed_field_candidates(view: ObjectView, cfg: AnchoringConfig) -> np.ndarray:
    """(C, 4, 4) camera-frame grasps the SGDF predicts at the object's observed points (module doc, source
    ``observed``), on the moving part, non-maximum suppressed to ``observed_pool``."""
    rng = np.random.default_rng(cfg.seed)
    pts = view.observed
    if len(pts) > cfg.observed_queries:
        pts = pts[rng.choice(len(pts), cfg.observed_queries, replace=False)]
    rays = pts / np.maximum(np.linalg.norm(pts, axis=1, keepdims=True), 1e-9)
    queries = np.concatenate([pts - s * rays for s in cfg.ray_steps_m])
    object_T_camera = np.linalg.inv(view.camera_T_object)
    q = apply_transform(object_T_camera, queries)
    sdf, raw = decoder_field(view.decoder, view.code, view.joint, device=view.device)(q.astype(np.float32))
    out = decode_outputs(raw)
    offset, rot = out.offset.numpy().astype(float), out.rotation.numpy().astype(float)
    off = np.linalg.norm(offset, axis=1)
    ext = GraspExtractionConfig()
    if cfg.observed_at_point:  # the grasp at the observed point itself, oriented by the field (snapped later)
        keep = np.flatnonzero(np.abs(sdf) < ext.surface_band)
        pos = q[keep]
    else:
        keep = np.flatnonzero((off < cfg.max_offset_m) & (np.abs(sdf) < ext.surface_band))
        pos = q[keep] + offset[keep]
    if len(keep) == 0:
        return np.zeros((0, 4, 4))
    rot, off = rot[keep], off[keep]
    _, change = joint_sdf_change(view.decoder, view.code, view.joint, pos, ext.moving_delta, view.device)
    moving = change > ext.moving_sdf_change
    pos, rot, off = pos[moving], rot[moving], off[moving]
    if len(pos) == 0:
        return np.zeros((0, 4, 4))
    support = grasp_support(pos, rot, ext)
    chosen = nms_grasps(pos, rot, support / (support + ext.support_half) * np.exp(-off / ext.offset_scale), ext,
                        cfg.observed_pool)  # fmt: skip
    poses = np.tile(np.eye(4), (len(chosen), 1, 1))
    poses[:, :3, :3], poses[:, :3, 3] = rot[chosen], pos[chosen]
    return view.camera_T_object @ poses


def front_plane(points: np.ndarray, seed: int) -> tuple[np.ndarray, float] | None:
    """(normal toward the camera, offset) of the object's dominant plane in its observed points (camera frame), at
    the baseline's RANSAC settings (1 cm inliers), or None."""
    plane = ransac_plane(points, FRONT_PLANE_DISTANCE_M, seed=seed)
    return None if plane is None else (plane[0], plane[1])


def squared_to_plane(poses: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """TCP poses (K, 4, 4) turned to approach along ``-normal`` (the front plane's normal, toward the camera),
    keeping the closing axis' direction in the plane and the TCP where it was."""
    out = poses.copy()
    z = -np.asarray(normal, float)
    for k, pose in enumerate(poses):
        y = pose[:3, 1] - (pose[:3, 1] @ z) * z
        if np.linalg.norm(y) < 1e-6:  # closing along the normal: any in-plane direction is as good
            y = np.cross(z, [1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.cross(z, [0.0, 1.0, 0.0])
        y /= np.linalg.norm(y)
        out[k, :3, :3] = np.column_stack([np.cross(y, z), y, z])
    return out


def candidate_set(view: ObjectView, decoded_camera: np.ndarray, plane, noise_m: float, cfg: AnchoringConfig):
    """(poses (C, 4, 4), sources (C,)) of every candidate (module doc, step 1), camera frame; ``noise_m``: the front
    face's depth noise (:func:`~.handles.face_noise`)."""
    groups = {"decoder": np.asarray(decoded_camera, float).reshape(-1, 4, 4)}
    groups["observed"] = observed_field_candidates(view, cfg) if cfg.observed_candidates else np.zeros((0, 4, 4))
    if cfg.square and plane is not None:
        for name in ("decoder", "observed"):
            groups[name] = np.concatenate([groups[name], squared_to_plane(groups[name], plane[0])])
    handles = []
    if cfg.handle_candidates and plane is not None:
        handles = handle_clusters(view.observed, *plane, min_height=handle_min_height(noise_m))
    groups["handle"] = np.array([grasp_across(c, plane[0]) for c in handles]).reshape(-1, 4, 4)
    poses = np.concatenate([groups[s] for s in SOURCES])
    sources = np.array([s for s in SOURCES for _ in range(len(groups[s]))], dtype=object)
    return poses, sources


def anchor_grasps(
    view: ObjectView, decoded_camera: np.ndarray, scene_tree: cKDTree, critics, cfg: AnchoringConfig, top_k: int
) -> AnchoredGrasps:
    """The object's grasps made on, snapped to, checked against and ranked on its observed points (module doc).
    ``decoded_camera``: the decoder's grasps (K, 4, 4, camera frame); ``scene_tree``: every observed point of the
    image (camera frame); ``critics``: (grasp critic, anchored-grasp ranker), either None."""
    observed = np.asarray(view.observed, float).reshape(-1, 3)
    view.observed = observed
    plane = front_plane(observed, cfg.seed)
    noise = face_noise(observed, *plane) if plane is not None else DEFAULT_NOISE_M
    empty = (np.zeros((0, 4, 4)), [])
    poses, sources = candidate_set(view, decoded_camera, plane, noise, cfg) if len(observed) else empty
    counts = {f"candidates_{s}": int(np.sum(np.asarray(sources) == s)) for s in SOURCES}
    if len(poses) == 0:
        return _result(poses, np.zeros(0), sources, np.zeros(0, int), [], counts, top_k)
    object_tree = cKDTree(observed)
    reasons = np.full(len(poses), "", dtype=object)
    shift = np.zeros(len(poses))
    if cfg.snap:
        snapped = [snap_to_material(p, object_tree, cfg.checks, noise) for p in poses]
        reasons[[s is None for s in snapped]] = "far_from_material"
        moved = np.array([p if s is None else s for p, s in zip(poses, snapped, strict=True)])
        shift = np.linalg.norm(moved[:, :3, 3] - poses[:, :3, 3], axis=1)
        poses = moved
    ok = reasons == ""
    counts["snapped"] = int(ok.sum())
    between = np.zeros(len(poses), int)
    between[ok] = closing_points(poses[ok], object_tree, cfg.checks.grasp_depth_m)
    reasons[ok & (between < cfg.checks.min_closing_points)] = "no_material_between_pads"
    ok = reasons == ""
    counts["material_between_pads"] = int(ok.sum())
    hits = np.zeros(len(poses), int)
    hits[ok] = collision_points(poses[ok], scene_tree, cfg.checks)
    reasons[ok & (hits > cfg.checks.max_collision_points)] = "collides_with_observed"
    ok = reasons == ""
    counts["clear"] = int(ok.sum())
    scores, features = np.zeros(len(poses)), np.zeros((len(poses), len(ANCHOR_FEATURES)))
    if ok.any():
        extra = {"closing": between[ok], "shift": shift[ok], "sources": np.asarray(sources)[ok],
                 "grasp_depth": cfg.checks.grasp_depth_m, "handle_floor": handle_min_height(noise)}  # fmt: skip
        features[ok] = anchor_features(view, poses[ok], plane, object_tree, extra)
        scores[ok] = rank_scores(features[ok], critics, cfg)
    return _result(poses, scores, sources, between, list(reasons), counts, top_k, features)


def _result(poses, scores, sources, between, reasons, counts, top_k: int = 0, features=None) -> AnchoredGrasps:
    """Kept grasps (reason "") best first, deduplicated by the decoder extraction's NMS to ``top_k``; the rejected
    ones aside with their reasons."""
    reasons = np.asarray(reasons, dtype=object).reshape(-1)
    kept = np.flatnonzero(reasons == "")
    kept = kept[np.argsort(-scores[kept], kind="stable")]
    if len(kept):
        kept = kept[nms_grasps(poses[kept, :3, 3], poses[kept, :3, :3], scores[kept], GraspExtractionConfig(), top_k)]
    rejected = np.flatnonzero(reasons != "")
    counts["kept"] = len(kept)
    poses = np.asarray(poses, float).reshape(-1, 4, 4)
    return AnchoredGrasps(
        poses=poses[kept],
        scores=np.asarray(scores, float)[kept],
        sources=[str(sources[i]) for i in kept],
        closing_points=np.asarray(between)[kept],
        features=np.zeros((0, len(ANCHOR_FEATURES))) if features is None else features[kept],
        rejected_poses=poses[rejected],
        rejected_reasons=[str(reasons[i]) for i in rejected],
        counts=counts,
    )


def anchor_features(view: ObjectView, poses: np.ndarray, plane, object_tree: cKDTree, extra: dict) -> np.ndarray:
    """(K, len(ANCHOR_FEATURES)) of checked camera-frame grasps: the critic's features read from the decoder at
    their object-frame poses, then the observation's cues (``grasp_critic.ANCHOR_FEATURES``). ``extra``: the
    grasps' ``closing`` point counts, ``shift`` by the snap (m), ``sources``, the ``grasp_depth`` (m) and the face's
    ``handle_floor`` (m, :func:`~.handles.handle_min_height`)."""
    rays = poses[:, :3, 3] / np.maximum(np.linalg.norm(poses[:, :3, 3], axis=1, keepdims=True), 1e-9)
    columns = [
        decoder_features(view, poses),
        handle_cue(poses, plane, object_tree, extra["handle_floor"], extra["grasp_depth"])[:, None],
        leverage_cue(view, poses)[:, None],
        np.clip(np.einsum("ki,ki->k", poses[:, :3, 2], rays), 0.0, 1.0)[:, None],
        np.log1p(np.asarray(extra["closing"], float))[:, None],
        np.asarray(extra["shift"], float)[:, None],
        np.stack([np.asarray(extra["sources"]) == s for s in SOURCES], 1).astype(float),
    ]
    return np.concatenate(columns, 1)


def rank_scores(features: np.ndarray, critics, cfg: AnchoringConfig) -> np.ndarray:
    """(K,) ranking scores from :func:`anchor_features`: the anchored-grasp ranker's success probability where the
    checkpoint has one (fitted to physics outcomes of anchored grasps, ``benchmarks/anchor_critic.py``); else the
    grasp critic's probability (0.5 without one) times the cues' factors documented on :class:`AnchoringConfig`."""
    critic, ranker = critics if critics is not None else (None, None)
    if ranker is not None and cfg.use_ranker:
        return ranker.probability(features)
    col = {name: features[:, i] for i, name in enumerate(ANCHOR_FEATURES)}
    p = critic.probability(features[:, : len(GRASP_FEATURES)]) if critic is not None else np.full(len(features), 0.5)
    return (
        p
        * (1.0 + cfg.handle_weight * col["handle_cue"])
        * (cfg.leverage_floor + (1 - cfg.leverage_floor) * col["leverage"])
        * (cfg.facing_floor + (1 - cfg.facing_floor) * col["facing"])
    )


def decoder_features(view: ObjectView, poses_camera: np.ndarray) -> np.ndarray:
    """(K, len(GRASP_FEATURES)) the grasp critic's features of camera-frame grasps, read from the decoder at their
    object-frame poses (|predicted offset| at the TCP: small where the field agrees a grasp is here); zeros
    without a decoder (``view.decoder`` None: the observation's cues alone)."""
    if view.decoder is None:
        return np.zeros((len(poses_camera), len(GRASP_FEATURES)))
    poses = np.linalg.inv(view.camera_T_object) @ poses_camera
    pos = poses[:, :3, 3].astype(np.float32)
    _, raw = decoder_field(view.decoder, view.code, view.joint, device=view.device)(pos)
    offset = np.linalg.norm(decode_outputs(raw).offset.numpy(), axis=1)
    ext = GraspExtractionConfig()
    tcp_sdf, change = joint_sdf_change(view.decoder, view.code, view.joint, pos, ext.moving_delta, view.device)
    return grasp_features(view.decoder, view.code, view.joint, poses, offset, tcp_sdf, change, view.device)


def handle_cue(poses: np.ndarray, plane, object_tree: cKDTree, floor: float, grasp_depth: float = 0.02) -> np.ndarray:
    """(K,) in [0, 1]: how far the material between each grasp's pads (:func:`~.observed_checks.points_between_pads`)
    stands proud of the object's front plane, above the depth noise (0 at ``floor``, the face's
    :func:`~.handles.handle_min_height`, or less; 1 from 1.5 cm above it up to the handle band's top; 0 without a
    plane)."""
    if plane is None:
        return np.zeros(len(poses))
    normal, offset = plane
    out = np.zeros(len(poses))
    for k, pose in enumerate(poses):
        between = points_between_pads(pose, object_tree, grasp_depth)
        if len(between):
            h = float(np.median(between @ normal + offset))
            out[k] = np.clip((h - floor) / 0.015, 0.0, 1.0) if h <= HANDLE_MAX_HEIGHT_M else 0.0
    return out


def leverage_cue(view: ObjectView, poses: np.ndarray) -> np.ndarray:
    """(K,) in [0, 1]: distance of each grasp from the predicted hinge line over the largest distance of the
    object's observed points from it (revolute); 1 for prismatic joints (any point of a drawer pulls alike)."""
    if view.joint_type != "revolute":
        return np.ones(len(poses))
    d = np.asarray(view.axis_direction, float) / max(np.linalg.norm(view.axis_direction), 1e-9)

    def distance(points):
        rel = np.asarray(points, float) - view.axis_point
        return np.linalg.norm(rel - np.outer(rel @ d, d), axis=1)

    reach = float(distance(view.observed).max()) if len(view.observed) else 1.0
    return np.clip(distance(poses[:, :3, 3]) / max(reach, 1e-6), 0.0, 1.0)


#: Named anchoring settings, cumulative (each adds one lever to the one before): the ladder of the evaluation
#: (``centerart eval scenes --grasps``) and of ``benchmarks/results/``. The predictor's default is ``full``, and
#: ``pose`` where a gravity direction is known (``PredictorConfig.pose_from_depth`` auto).
LADDER = ("proposal", "checks", "snap", "square", "observed", "handle", "full", "pose")


def anchoring_setting(name: str) -> AnchoringConfig:
    """The anchoring of one ladder step (see :data:`LADDER`): ``proposal`` is off (the decoder's grasps through
    the proposal's collision filter); ``checks`` verifies the decoder's grasps where they are; ``snap`` moves them
    onto the material first; ``square`` adds their front-plane-squared twins; ``observed`` adds the SGDF's grasps
    at the observed points; ``handle`` adds grasps across handles; ``full`` ranks with the cues, or the
    anchored-grasp ranker where the checkpoint has one (before it, by the critic alone); ``pose`` is ``full`` with
    the pose corrected from the depth first (a predictor setting: :func:`ladder_predictor_settings`)."""
    if name not in LADDER:
        raise ValueError(f"grasp setting {name!r}: expected one of {', '.join(LADDER)}")
    step = min(LADDER.index(name), LADDER.index("full"))
    return AnchoringConfig(
        enabled=step >= 1,
        snap=step >= 2,
        square=step >= 3,
        observed_candidates=step >= 4,
        handle_candidates=step >= 5,
        handle_weight=1.0 if step >= 6 else 0.0,
        leverage_floor=0.3 if step >= 6 else 1.0,
        facing_floor=0.2 if step >= 6 else 1.0,
        use_ranker=step >= 6,
    )


def ladder_predictor_settings(name: str) -> dict:
    """``PredictorConfig`` fields of one ladder step: its anchoring, and the pose correction from ``pose`` on."""
    return {"anchoring": anchoring_setting(name), "pose_from_depth": "on" if name == "pose" else "off"}
