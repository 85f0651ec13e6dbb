"""Per-object result rows of the scene evaluation, one method at a time, for one view and depth mode.

A row is one ground-truth object (at least ``MIN_VISIBLE_FRACTION`` visible) under one method. Failures are rows
too: a missed detection, an object without a grasp, every abort. Frames: predictions arrive in the OpenCV camera
frame and are mapped to the scene's world frame with the view's ``world_T_camera`` for execution; rows store the
executed top grasp in the camera frame (for pictures) and errors in cm / degrees / mm as their keys say.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from centerart.evaluation.baseline import baseline_grasps
from centerart.evaluation.metrics import nearest_label_position_m, relaxed_success, shape_metrics
from centerart.evaluation.physics_scene import PhysicsScene
from centerart.evaluation.trials import any_of_top, execute_grasp, full_open, oracle_trial
from centerart.geometry.camera import backproject_depth
from centerart.geometry.matching import match_points
from centerart.grasps.executor import commanded_direction
from centerart.models.encoder.readout import Detection
from centerart.training.encoder_metrics import MATCH_DISTANCE_M, MIN_VISIBLE_FRACTION, object_errors, view_metrics


@dataclass
class SceneContext:
    """One scene in physics, with its objects' ground-truth labels at their exact states (world frame)."""

    phys: PhysicsScene
    labels_world: list[np.ndarray]
    oracle: dict[int, dict] = field(default_factory=dict)


@dataclass
class ViewInput:
    """One view under one depth mode: images, intrinsics, labels (``labels.json``) and its camera pose."""

    scene: str
    view: int
    depth_mode: str
    rgb: np.ndarray
    depth: np.ndarray
    instances: np.ndarray
    labels: dict

    @property
    def K(self) -> np.ndarray:
        return np.asarray(self.labels["K"], float)

    @property
    def world_T_camera(self) -> np.ndarray:
        return np.asarray(self.labels["world_T_camera"], float)

    def ground_truth(self) -> list[tuple[int, dict]]:
        """(label index, label) of every object counted in SR (visible enough)."""
        return [(j, o) for j, o in enumerate(self.labels["objects"]) if o["visible_fraction"] >= MIN_VISIBLE_FRACTION]


def base_row(v: ViewInput, obj: dict, method: str) -> dict:
    joint = obj["joint"]
    return {
        "scene": v.scene,
        "view": v.view,
        "depth": v.depth_mode,
        "method": method,
        "instance": obj["instance"] - 1,
        "object_id": obj["object_id"],
        "category": obj["category"],
        "joint_type": joint["type"],
        "state_normalized": joint["state_normalized"],
        "opens": commanded_direction(joint["type"], joint["state"], joint["range"][1]) > 0,
        "visible_fraction": obj["visible_fraction"],
    }


def failed(reason: str) -> dict:
    return {"sr": False, "sr_abort": reason, "sr_axis": False, "top5_any": False, "rsr": False, "nearest_label_m": None}


def grasp_outcomes(ctx: SceneContext, v: ViewInput, k: int, grasps_cam: np.ndarray, axis: dict | None) -> dict:
    """SR, SR-axis (when ``axis``, world frame, is given), full-open, any-of-top-5 and RSR of ranked camera-frame
    grasps of object ``k``."""
    if len(grasps_cam) == 0:
        return failed("no_grasp")
    world = v.world_T_camera @ np.asarray(grasps_cam, float)
    sr = execute_grasp(ctx.phys, k, world[0])
    nearest = float(nearest_label_position_m(world[:1], ctx.labels_world[k])[0])
    out = {
        "sr": sr["success"],
        "sr_abort": sr["abort"] or ("" if sr["success"] else "too_little_motion"),
        "sr_displacement": sr["displacement"],
        "sr_axis": execute_grasp(ctx.phys, k, world[0], axis)["success"] if axis is not None else None,
        "full_open": full_open(ctx.phys, k, world[0], axis) if axis is not None else None,
        "top5_any": any_of_top(ctx.phys, k, world, first=sr),
        "rsr": relaxed_success(world[0], ctx.labels_world[k]),
        "nearest_label_m": nearest if np.isfinite(nearest) else None,
        "grasp_camera": np.asarray(grasps_cam[0], float).round(5).tolist(),
    }
    return out


def predicted_axis_world(v: ViewInput, pred) -> dict:
    T = v.world_T_camera
    return {
        "origin": T[:3, :3] @ pred.axis_point + T[:3, 3],
        "direction": T[:3, :3] @ pred.axis_direction,
        "type": pred.joint_type,
    }


def match_predictions(v: ViewInput, preds) -> dict[int, int]:
    """label index -> prediction index (Hungarian on 3-D centres, camera frame, MATCH_DISTANCE_M)."""
    true_t = np.array([np.asarray(o["camera_T_object"])[:3, 3] for o in v.labels["objects"]]).reshape(-1, 3)
    pred_t = np.array([p.camera_T_object[:3, 3] for p in preds]).reshape(-1, 3)
    return {j: i for i, j in match_points(pred_t, true_t, MATCH_DISTANCE_M)}


def true_mesh_camera(ctx: SceneContext, v: ViewInput, k: int, obj: dict):
    mesh = ctx.phys.objects[k].mesh(ctx.phys.states[k]).copy()
    mesh.apply_transform(np.asarray(obj["camera_T_object"], float))
    return mesh


def shape_row(ctx: SceneContext, v: ViewInput, k: int, obj: dict, pred) -> dict | None:
    try:
        m = shape_metrics(pred.mesh(), true_mesh_camera(ctx, v, k, obj))
    except ValueError:  # an empty predicted surface: no shape to measure
        return None
    return {"chamfer_l1_mm": m.chamfer_l1_mm, "fscore": m.fscore}


def gt_pose_swap(predictor, v: ViewInput, pred, obj: dict) -> np.ndarray:
    """The matched prediction's grasps with the true pose and joint state swapped in (shape code kept)."""
    joint = obj["joint"]
    det = Detection(
        score=pred.score, peak_uv=pred.peak_uv, camera_T_object=np.asarray(obj["camera_T_object"], float),
        shape_code=pred.shape_code, joint_code=float(joint["state_normalized"]), joint_type=pred.joint_type,
        joint_type_probability=pred.joint_type_probability, axis_direction=pred.axis_direction,
        axis_point=pred.axis_point, joint_state=float(joint["state"]), mask=pred.mask,
    )  # fmt: skip
    return predictor.predict_detection(det, v.rgb, v.depth, v.K).grasp_poses


def learned_rows(ctx: SceneContext, v: ViewInput, predictor, method: str, shape: bool, ablation: bool):
    """Rows of the learned method, plus the image's detection counts and latency."""
    preds = predictor.predict(v.rgb, v.depth, v.K)
    image = {"scene": v.scene, "view": v.view, "depth": v.depth_mode, "method": method}
    image.update(counts=view_metrics(preds, v.labels)["counts"], timing_s=dict(predictor.timing))
    match = match_predictions(v, preds)
    rows = []
    for j, obj in v.ground_truth():
        row, k = base_row(v, obj, method), obj["instance"] - 1
        if j not in match:
            rows.append({**row, "matched": False, **failed("missed")})
            continue
        pred = preds[match[j]]
        row.update(matched=True, errors=object_errors(pred, obj))
        row.update(grasp_outcomes(ctx, v, k, pred.grasp_poses, predicted_axis_world(v, pred)))
        if shape:
            row["shape"] = shape_row(ctx, v, k, obj, pred)
        if ablation:
            swapped = gt_pose_swap(predictor, v, pred, obj)
            row["sr_gt_pose"] = grasp_outcomes(ctx, v, k, swapped, None)["sr"]
        rows.append(row)
    return rows, image


def baseline_rows(ctx: SceneContext, v: ViewInput, seed: int) -> list[dict]:
    """The geometric baseline on each object's observed points inside its true mask."""
    rows = []
    for _, obj in v.ground_truth():
        k = obj["instance"] - 1
        points = backproject_depth(v.depth, v.K, mask=v.instances == k + 1)
        grasps = baseline_grasps(points, seed)
        outcome = grasp_outcomes(ctx, v, k, grasps, None)
        if len(grasps) == 0:
            outcome["sr_abort"] = "no_handle_found"
        outcome["sr_axis"] = None  # the baseline predicts no joint
        rows.append({**base_row(v, obj, "baseline"), "matched": True, **outcome})
    return rows


def oracle_rows(ctx: SceneContext, v: ViewInput) -> list[dict]:
    """A ground-truth label of each object executed in the scene (computed once per object, shared by views)."""
    rows = []
    for _, obj in v.ground_truth():
        k = obj["instance"] - 1
        if k not in ctx.oracle:
            ctx.oracle[k] = oracle_trial(ctx.phys, k, ctx.labels_world[k])
        trial = ctx.oracle[k]
        ok = trial["grasp_world"] is not None
        out = {
            "sr": trial["success"],
            "sr_abort": trial["abort"] or ("" if trial["success"] else "too_little_motion"),
            "sr_axis": None,
            "top5_any": None,
            "rsr": ok,
            "nearest_label_m": 0.0 if ok else None,
            "oracle_label_index": trial["label_index"],
        }
        if ok:
            cam = np.linalg.inv(v.world_T_camera) @ np.asarray(trial["grasp_world"], float)
            out["grasp_camera"] = cam.round(5).tolist()
        rows.append({**base_row(v, obj, "oracle"), "matched": True, **out})
    return rows
