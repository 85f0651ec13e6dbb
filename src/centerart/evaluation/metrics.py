"""Shape and grasp metrics of EVALUATION.md, with every threshold a named constant printed in reports.

Frames and units: both arguments of a metric are in the same frame (canonical object frame or camera frame);
distances in metres in and out unless a name says ``_mm``; angles in degrees where a name says ``_deg``.
Grasps are TCP poses (4x4, :mod:`centerart.grasps.gripper` convention). A parallel-jaw grasp and the same grasp
turned 180 degrees about its approach axis (``gripper.FLIP_Z``) are one physical grasp, so every rotation
distance takes the smaller of the two.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d
import trimesh
from scipy.spatial import cKDTree

from centerart.grasps.gripper import FLIP_Z

#: Surface samples per mesh for Chamfer distance and F-score.
CHAMFER_SAMPLES = 30_000
#: Distance (m) under which a surface sample counts as matched for the F-score.
FSCORE_THRESHOLD_M = 0.01
#: A predicted grasp matches a label within this TCP distance (m) and rotation (deg): grasp precision/coverage.
GRASP_MATCH_POSITION_M = 0.02
GRASP_MATCH_ANGLE_DEG = 30.0
#: Relaxed success (RSR): the top grasp lies within this distance (m) and rotation (deg) of some label.
RELAXED_POSITION_M = 0.03
RELAXED_ANGLE_DEG = 45.0
#: Equal-width confidence bins on [0, 1] of the grasp-score calibration table.
CALIBRATION_BINS = 5


@dataclass
class ShapeMetrics:
    chamfer_l1_mm: float
    """Mean of the two directed mean nearest-neighbour distances, in mm."""
    fscore: float
    """Harmonic mean of precision and recall at ``threshold_m``."""
    precision: float
    recall: float
    threshold_m: float = FSCORE_THRESHOLD_M
    samples: int = CHAMFER_SAMPLES


def surface_samples(mesh: trimesh.Trimesh, count: int, seed: int) -> np.ndarray:
    """``count`` area-weighted surface points of ``mesh`` (count, 3), deterministic given ``seed``."""
    if len(mesh.faces) == 0:
        raise ValueError("mesh has no triangles")
    points, _ = trimesh.sample.sample_surface(mesh, count, seed=seed)
    return np.asarray(points, float)


def shape_metrics(
    predicted: trimesh.Trimesh,
    truth: trimesh.Trimesh,
    samples: int = CHAMFER_SAMPLES,
    threshold_m: float = FSCORE_THRESHOLD_M,
    seed: int = 0,
) -> ShapeMetrics:
    """Chamfer-L1 (mm) and F-score of ``predicted`` against ``truth``: ``samples`` surface points of each mesh,
    each measured to the other *surface* (exact point-to-triangle distance, open3d), so that the number is the
    shapes' difference and not the gap between two point samplings (about 2 mm for 30k points on 0.5 m^2)."""
    p = surface_samples(predicted, samples, seed)
    t = surface_samples(truth, samples, seed)
    d_pt = _distance_to_surface(truth, p)  # accuracy: predicted points to the true surface
    d_tp = _distance_to_surface(predicted, t)  # completeness: true points to the predicted surface
    return _from_distances(d_pt, d_tp, threshold_m)


def _distance_to_surface(mesh: trimesh.Trimesh, points: np.ndarray) -> np.ndarray:
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(np.asarray(mesh.vertices, np.float32)), o3d.core.Tensor(np.asarray(mesh.faces, np.uint32))
    )
    return scene.compute_distance(o3d.core.Tensor(np.asarray(points, np.float32))).numpy().astype(float)


def _from_distances(d_pt: np.ndarray, d_tp: np.ndarray, threshold_m: float) -> ShapeMetrics:
    chamfer = 0.5 * (d_pt.mean() + d_tp.mean())
    precision = float(np.mean(d_pt < threshold_m))
    recall = float(np.mean(d_tp < threshold_m))
    fscore = 0.0 if precision + recall == 0 else 2 * precision * recall / (precision + recall)
    return ShapeMetrics(1000.0 * float(chamfer), fscore, precision, recall, threshold_m, len(d_pt))


def shape_metrics_points(
    predicted: np.ndarray, truth: np.ndarray, threshold_m: float = FSCORE_THRESHOLD_M
) -> ShapeMetrics:
    """As :func:`shape_metrics` on point sets (N, 3) and (M, 3), point to nearest point (for clouds without a
    mesh, e.g. a partial depth scan); includes the sampling gap."""
    d_pt, _ = cKDTree(truth).query(predicted, k=1)
    d_tp, _ = cKDTree(predicted).query(truth, k=1)
    return _from_distances(np.asarray(d_pt), np.asarray(d_tp), threshold_m)


def chamfer_l1_mm(predicted: trimesh.Trimesh, truth: trimesh.Trimesh, samples: int = CHAMFER_SAMPLES, seed: int = 0):
    return shape_metrics(predicted, truth, samples, seed=seed).chamfer_l1_mm


def fscore(predicted: trimesh.Trimesh, truth: trimesh.Trimesh, threshold_m: float = FSCORE_THRESHOLD_M, seed: int = 0):
    return shape_metrics(predicted, truth, threshold_m=threshold_m, seed=seed).fscore


# ---------------------------------------------------------------------- grasps
def grasp_distances(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairwise ``(position_m (A, B), angle_deg (A, B))`` between TCP poses ``a`` (A, 4, 4) and ``b`` (B, 4, 4):
    TCP position distance, and the rotation angle between them minimised over ``b`` and ``b @ FLIP_Z``."""
    a = np.asarray(a, float).reshape(-1, 4, 4)
    b = np.asarray(b, float).reshape(-1, 4, 4)
    pos = np.linalg.norm(a[:, None, :3, 3] - b[None, :, :3, 3], axis=-1)
    ra, rb = a[:, :3, :3], b[:, :3, :3]
    # trace(Ra^T Rb) = 1 + 2 cos(theta); the flipped Rb' = Rb diag(-1,-1,1) negates Rb's first two columns.
    prod = np.einsum("aij,bij->abj", ra, rb)  # column-wise dot products: (A, B, 3)
    trace = prod.sum(-1)
    trace_flip = -prod[..., 0] - prod[..., 1] + prod[..., 2]
    best = np.maximum(trace, trace_flip)
    angle = np.degrees(np.arccos(np.clip((best - 1.0) / 2.0, -1.0, 1.0)))
    return pos, angle


def grasp_distance(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """``(position_m, angle_deg)`` between two TCP poses (4, 4), finger-swap symmetric."""
    pos, ang = grasp_distances(a[None], b[None])
    return float(pos[0, 0]), float(ang[0, 0])


def grasp_matches(
    predictions: np.ndarray,
    labels: np.ndarray,
    position_m: float = GRASP_MATCH_POSITION_M,
    angle_deg: float = GRASP_MATCH_ANGLE_DEG,
) -> np.ndarray:
    """(P, L) bool: prediction p lies within the thresholds of label l (finger-swap symmetric)."""
    if len(predictions) == 0 or len(labels) == 0:
        return np.zeros((len(predictions), len(labels)), bool)
    pos, ang = grasp_distances(predictions, labels)
    return (pos <= position_m) & (ang <= angle_deg)


@dataclass
class GraspMetrics:
    precision: float
    """Share of the top-k predictions within the thresholds of some label (nan with no predictions)."""
    coverage: float
    """Share of labels within the thresholds of some top-k prediction (nan with no labels)."""
    k: int
    predictions: int
    labels: int
    position_m: float = GRASP_MATCH_POSITION_M
    angle_deg: float = GRASP_MATCH_ANGLE_DEG


def grasp_precision_coverage(
    predictions: np.ndarray,
    labels: np.ndarray,
    k: int | None = None,
    position_m: float = GRASP_MATCH_POSITION_M,
    angle_deg: float = GRASP_MATCH_ANGLE_DEG,
) -> GraspMetrics:
    """Precision and coverage of ranked ``predictions`` (P, 4, 4), best first, against ``labels`` (L, 4, 4);
    only the first ``k`` predictions count (all when None)."""
    predictions = np.asarray(predictions, float).reshape(-1, 4, 4)
    labels = np.asarray(labels, float).reshape(-1, 4, 4)
    top = predictions if k is None else predictions[:k]
    m = grasp_matches(top, labels, position_m, angle_deg)
    precision = float(m.any(axis=1).mean()) if len(top) else float("nan")
    coverage = float(m.any(axis=0).mean()) if len(labels) else float("nan")
    return GraspMetrics(precision, coverage, len(top) if k is None else k, len(top), len(labels), position_m, angle_deg)


def relaxed_success(
    top_grasp: np.ndarray | None,
    labels: np.ndarray,
    position_m: float = RELAXED_POSITION_M,
    angle_deg: float = RELAXED_ANGLE_DEG,
) -> bool:
    """RSR of one object: its top-ranked grasp (4, 4) lies within the thresholds of some label. A missing
    prediction (None) or an object without labels is a failure, never left out."""
    if top_grasp is None:
        return False
    return bool(grasp_matches(np.asarray(top_grasp, float)[None], labels, position_m, angle_deg).any())


def nearest_label_position_m(grasps: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """TCP distance (m) from each grasp (G, 4, 4) to the nearest label's TCP (inf without labels); the
    distribution EVALUATION.md asks for beside RSR."""
    grasps = np.asarray(grasps, float).reshape(-1, 4, 4)
    labels = np.asarray(labels, float).reshape(-1, 4, 4)
    if len(labels) == 0:
        return np.full(len(grasps), np.inf)
    d, _ = cKDTree(labels[:, :3, 3]).query(grasps[:, :3, 3], k=1)
    return np.asarray(d, float)


def distance_distribution(distances_m: np.ndarray, quantiles=(0.1, 0.25, 0.5, 0.75, 0.9)) -> dict:
    """Summary of nearest-label distances (m) for reports: count, finite count, quantiles and the share under
    each RSR/precision position threshold."""
    d = np.asarray(distances_m, float)
    finite = d[np.isfinite(d)]
    out = {"count": len(d), "finite": len(finite)}
    out["quantiles_m"] = {str(q): (float(np.quantile(finite, q)) if len(finite) else None) for q in quantiles}
    for name, thr in (("within_match_m", GRASP_MATCH_POSITION_M), ("within_relaxed_m", RELAXED_POSITION_M)):
        out[name] = {"threshold": thr, "share": float(np.mean(d <= thr)) if len(d) else None}
    return out


def score_calibration(scores: np.ndarray, outcomes: np.ndarray, bins: int = CALIBRATION_BINS) -> dict:
    """How well grasp confidences in [0, 1] predict physics success (True/False per executed grasp).

    Returns the count, the success rate, a reliability table (equal-width bins: count, mean score, success
    rate), the expected calibration error (count-weighted mean |success rate - mean score| over bins), the Brier
    score and the ROC AUC (probability that a random success outranks a random failure, ties counted half;
    ``None`` when only one outcome occurs). A useful ranking has AUC > 0.5 whatever its calibration."""
    s = np.clip(np.asarray(scores, float), 0.0, 1.0)
    y = np.asarray(outcomes, bool)
    if s.shape != y.shape:
        raise ValueError(f"score_calibration: {s.shape} scores but {y.shape} outcomes")
    out: dict = {"count": len(s), "success_rate": float(y.mean()) if len(y) else None, "bins": []}
    if not len(s):
        return out | {"ece": None, "brier": None, "auroc": None}
    which = np.minimum((s * bins).astype(int), bins - 1)
    ece = 0.0
    for b in range(bins):
        m = which == b
        row = {"range": [b / bins, (b + 1) / bins], "count": int(m.sum()), "mean_score": None, "success_rate": None}
        if m.any():
            row["mean_score"], row["success_rate"] = float(s[m].mean()), float(y[m].mean())
            ece += m.sum() / len(s) * abs(row["success_rate"] - row["mean_score"])
        out["bins"].append(row)
    out["ece"], out["brier"] = float(ece), float(np.mean((s - y) ** 2))
    out["auroc"] = _auroc(s, y)
    return out


def _auroc(scores: np.ndarray, positives: np.ndarray) -> float | None:
    """ROC AUC as the Mann-Whitney U of the successes over the failures (ties count half), ``None`` with a single
    class (scipy ranks in O(n log n); a pairwise comparison would hold n_pos x n_neg booleans)."""
    from scipy.stats import mannwhitneyu

    pos, neg = scores[positives], scores[~positives]
    if not len(pos) or not len(neg):
        return None
    return float(mannwhitneyu(pos, neg).statistic / (len(pos) * len(neg)))


def thresholds() -> dict:
    """Every threshold above, for reports."""
    return {
        "chamfer_samples": CHAMFER_SAMPLES,
        "fscore_threshold_m": FSCORE_THRESHOLD_M,
        "grasp_match_position_m": GRASP_MATCH_POSITION_M,
        "grasp_match_angle_deg": GRASP_MATCH_ANGLE_DEG,
        "relaxed_position_m": RELAXED_POSITION_M,
        "relaxed_angle_deg": RELAXED_ANGLE_DEG,
        "calibration_bins": CALIBRATION_BINS,
        "flip": np.asarray(FLIP_Z).tolist(),
    }
