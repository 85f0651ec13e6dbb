"""Per-object result rows of the scene evaluation, one method at a time, for one view and depth mode.

A row is one ground-truth object (at least ``MIN_VISIBLE_FRACTION`` visible) under one method. Failures are rows
too: a missed detection, an object without a grasp, every abort.

Two associations of the learned method's predictions with objects (EVALUATION.md, "Matching predictions to
objects"), both executed: the 3-D centre match (``matched``, ``sr``, ``rsr``, ...: Hungarian within
``MATCH_DISTANCE_M``; detection precision / recall use it) and the image association (``image_matched``,
``sr_image``, ``rsr_image``, ``sr_image_abort``, ``sr_image_gt_pose``: the prediction whose heatmap peak lies in
the object's visible mask, :data:`IMAGE_ASSOCIATION`). Where both pick the same prediction its outcome is reused
(``image_same_as_3d``), so physics runs only for the objects where they differ.

Frames: predictions arrive in the OpenCV camera frame and are mapped to the scene's world frame with the view's
``world_T_camera`` for execution; rows store the executed top grasp (of the 3-D match) in the camera frame (for
pictures) and errors in cm / degrees / mm as their keys say.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from centerart.evaluation.baseline import baseline_grasps
from centerart.evaluation.metrics import nearest_label_position_m, relaxed_success, shape_metrics
from centerart.evaluation.physics_scene import PhysicsScene
from centerart.evaluation.trials import any_of_top, execute_grasp, full_open, oracle_trial
from centerart.geometry.camera import backproject_depth
from centerart.geometry.gravity import gravity_from_world_T_camera
from centerart.geometry.matching import match_points
from centerart.grasps.executor import commanded_direction
from centerart.models.encoder.readout import Detection
from centerart.training.encoder_metrics import MATCH_DISTANCE_M, MIN_VISIBLE_FRACTION, object_errors, view_metrics

#: The image association's rule (printed in reports): no distance threshold, only the visible mask.
IMAGE_ASSOCIATION = (
    "the prediction whose heatmap peak (rounded to its pixel) lies in the object's visible instance mask; "
    "highest score first, one prediction per object"
)


@dataclass
class SceneContext:
    """One scene in physics, with its objects' ground-truth labels at their exact states (world frame)."""

    phys: PhysicsScene
    labels_world: list[np.ndarray]
    oracle: dict[int, dict] = field(default_factory=dict)
    code_oracle: bool = False
    """Stage analysis: also swap in a shape code fitted to the object's true surface (:mod:`.code_oracle`)."""
    codes: dict[int, np.ndarray] = field(default_factory=dict)
    """Those codes, per scene object (fitted once, shared by the scene's views and settings)."""


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


def _abort_word(trial: dict) -> str:
    """The row's outcome word of an executed trial: the executor's abort, "" for a success, else too little motion."""
    return trial["abort"] or ("" if trial["success"] else "too_little_motion")


def same_as_3d(row: dict) -> dict:
    """Image-association keys of a row whose executed grasp is, by construction, the 3-D match's one (the baseline
    and the oracle use the true mask; an image-associated prediction that is the 3-D matched one)."""
    return {"image_matched": row["matched"], "sr_image": row["sr"], "sr_image_abort": row["sr_abort"],
            "rsr_image": row["rsr"]}  # fmt: skip


def top_grasp_trial(ctx: SceneContext, v: ViewInput, k: int, grasps_cam: np.ndarray) -> dict:
    """SR (the hand follows the true joint), its outcome word and RSR of the top one of ranked camera-frame grasps
    of object ``k``: one physics trial, without the variants of :func:`grasp_outcomes`."""
    if len(grasps_cam) == 0:
        return {"sr": False, "sr_abort": "no_grasp", "rsr": False}
    world = v.world_T_camera @ np.asarray(grasps_cam[0], float)
    trial = execute_grasp(ctx.phys, k, world)
    return {"sr": trial["success"], "sr_abort": _abort_word(trial), "rsr": relaxed_success(world, ctx.labels_world[k])}


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
        "sr_abort": _abort_word(sr),
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


def peak_pixel(peak_uv, shape: tuple[int, int]) -> tuple[int, int] | None:
    """(row, column) of the pixel holding a heatmap peak, or None when it has none or lies outside the image.

    ``peak_uv`` is (u, v) = (column, row) in the input image's pixels with pixel centres at integers
    (``Letterbox.to_camera_pixels``), so rounding gives the pixel; ``shape`` is the image's (H, W)."""
    if peak_uv is None:
        return None
    u, v = np.rint(np.asarray(peak_uv, float)[:2]).astype(int)
    return (int(v), int(u)) if 0 <= v < shape[0] and 0 <= u < shape[1] else None


def associate_by_image(v: ViewInput, preds) -> dict[int, int]:
    """label index -> prediction index by image association (:data:`IMAGE_ASSOCIATION`).

    Object ``j`` owns the pixels where ``v.instances == labels["objects"][j]["instance"]`` (its visible mask). A
    peak lies in at most one mask, so a prediction serves at most one object; of several predictions whose peaks
    lie in one object's mask, the highest ``score`` is taken (what a robot acting on its best detection does).
    No distance threshold: how far the 3-D centre is off matters only through the executed grasp."""
    owner = {int(o["instance"]): j for j, o in enumerate(v.labels["objects"])}
    out: dict[int, int] = {}
    for i in sorted(range(len(preds)), key=lambda i: -float(preds[i].score)):  # stable: ties keep list order
        pixel = peak_pixel(getattr(preds[i], "peak_uv", None), v.instances.shape[:2])
        j = owner.get(int(v.instances[pixel])) if pixel is not None else None
        if j is not None and j not in out:
            out[j] = i
    return out


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


def gt_pose_swap(predictor, v: ViewInput, pred, obj: dict, shape_code: np.ndarray | None = None) -> np.ndarray:
    """The matched prediction's grasps with the true pose and joint state swapped in (shape code kept, or
    ``shape_code`` swapped in too)."""
    joint = obj["joint"]
    code = pred.shape_code if shape_code is None else shape_code
    det = Detection(
        score=pred.score, peak_uv=pred.peak_uv, camera_T_object=np.asarray(obj["camera_T_object"], float),
        shape_code=code, joint_code=float(joint["state_normalized"]), joint_type=pred.joint_type,
        joint_type_probability=pred.joint_type_probability, axis_direction=pred.axis_direction,
        axis_point=pred.axis_point, joint_state=float(joint["state"]), mask=pred.mask,
    )  # fmt: skip
    return predictor.predict_detection(det, v.rgb, v.depth, v.K).grasp_poses


def gt_code_swap_sr(ctx: SceneContext, v: ViewInput, predictor, pred, obj: dict, already: bool) -> bool | None:
    """SR of the top grasp with the true pose, joint state and a shape code fitted to the object's true surface
    swapped in (:mod:`.code_oracle`; callers ask only with ``ctx.code_oracle`` on); None where it is not measured:
    the prediction already succeeds as it is or with the true pose (``already``), so the stage analysis needs no
    code swap."""
    if already:
        return None
    from centerart.evaluation.code_oracle import oracle_code

    k = obj["instance"] - 1
    if k not in ctx.codes:
        ctx.codes[k] = oracle_code(predictor.decoder, ctx.phys.objects[k], ctx.phys.states[k], seed=k)
    return top_grasp_trial(ctx, v, k, gt_pose_swap(predictor, v, pred, obj, ctx.codes[k]))["sr"]


def _image_ablation(ctx: SceneContext, v: ViewInput, predictor, pred, obj: dict, sr_image: bool) -> dict:
    """The stage analysis's swaps for an image-associated prediction that is not the 3-D matched one."""
    k = obj["instance"] - 1
    gt_pose = top_grasp_trial(ctx, v, k, gt_pose_swap(predictor, v, pred, obj))["sr"]
    out = {"sr_image_gt_pose": gt_pose}
    if ctx.code_oracle:
        out["sr_image_gt_pose_code"] = gt_code_swap_sr(ctx, v, predictor, pred, obj, sr_image or gt_pose)
    return out


def image_outcomes(ctx: SceneContext, v: ViewInput, predictor, preds, obj: dict, row: dict, i3d, i_img,
                   ablation: bool) -> dict:  # fmt: skip
    """Image-association keys of one learned row (object ``obj``, its 3-D match ``i3d`` and image association
    ``i_img``, prediction indices or None). Executing grasps is the expensive part: when both associations pick the
    same prediction, the 3-D match's outcome already in ``row`` is reused; only a different prediction runs."""
    k = obj["instance"] - 1
    if i_img is None:  # no peak in the object's mask: a miss, a failure like the 3-D miss
        out = {"image_matched": False, "image_same_as_3d": None, "sr_image": False, "sr_image_abort": "missed",
               "rsr_image": False}  # fmt: skip
        return out | ({f"sr_image_{key[3:]}": None for key in _swap_keys(ctx)} if ablation else {})
    if i_img == i3d:  # the 3-D match's swaps, under the image association's names (sr_gt_pose -> sr_image_gt_pose)
        out = {**same_as_3d(row), "image_same_as_3d": True}
        return out | ({f"sr_image_{key[3:]}": row.get(key) for key in _swap_keys(ctx)} if ablation else {})
    pred = preds[i_img]
    trial = top_grasp_trial(ctx, v, k, pred.grasp_poses)
    out = {"image_matched": True, "image_same_as_3d": False, "sr_image": trial["sr"],
           "sr_image_abort": trial["sr_abort"], "rsr_image": trial["rsr"]}  # fmt: skip
    if ablation:
        out.update(_image_ablation(ctx, v, predictor, pred, obj, trial["sr"]))
    return out


def _swap_keys(ctx: SceneContext) -> tuple[str, ...]:
    """The stage analysis's keys of a row (the 3-D match's names)."""
    return ("sr_gt_pose", "sr_gt_pose_code") if ctx.code_oracle else ("sr_gt_pose",)


def learned_rows(ctx: SceneContext, v: ViewInput, predictor, method: str, shape: bool, ablation: bool, encoded=None):
    """Rows of the learned method (3-D match and image association, see the module docstring), plus the image's
    detection counts (3-D match) and latency. ``encoded``: the image's encoder pass (``Predictor.encode``), shared
    by the grasp settings of one evaluation."""
    # Gravity as a robot knows it (TF / IMU): the camera's true orientation; only the pose correction reads it.
    preds = predictor.predict(
        v.rgb, v.depth, v.K, encoded=encoded, gravity=gravity_from_world_T_camera(v.world_T_camera)
    )
    image = {"scene": v.scene, "view": v.view, "depth": v.depth_mode, "method": method}
    image.update(counts=view_metrics(preds, v.labels)["counts"], timing_s=dict(predictor.timing))
    match, by_image = match_predictions(v, preds), associate_by_image(v, preds)
    rows = []
    for j, obj in v.ground_truth():
        row, k = base_row(v, obj, method), obj["instance"] - 1
        if j not in match:
            row.update(matched=False, **failed("missed"))
        else:
            pred = preds[match[j]]
            row.update(matched=True, errors=object_errors(pred, obj))
            row.update(grasp_outcomes(ctx, v, k, pred.grasp_poses, predicted_axis_world(v, pred)))
            if shape:
                row["shape"] = shape_row(ctx, v, k, obj, pred)
            if ablation:  # only the top grasp's SR is used: one trial, not the variants
                row["sr_gt_pose"] = top_grasp_trial(ctx, v, k, gt_pose_swap(predictor, v, pred, obj))["sr"]
                if ctx.code_oracle:
                    done = row["sr"] or row["sr_gt_pose"]
                    row["sr_gt_pose_code"] = gt_code_swap_sr(ctx, v, predictor, pred, obj, done)
        row.update(image_outcomes(ctx, v, predictor, preds, obj, row, match.get(j), by_image.get(j), ablation))
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
        row = {**base_row(v, obj, "baseline"), "matched": True, **outcome}
        rows.append(row | same_as_3d(row))  # the true mask picks the object: both associations are the same
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
            "sr_abort": _abort_word(trial),
            "sr_axis": None,
            "top5_any": None,
            "rsr": ok,
            "nearest_label_m": 0.0 if ok else None,
            "oracle_label_index": trial["label_index"],
        }
        if ok:
            cam = np.linalg.inv(v.world_T_camera) @ np.asarray(trial["grasp_world"], float)
            out["grasp_camera"] = cam.round(5).tolist()
        row = {**base_row(v, obj, "oracle"), "matched": True, **out}
        rows.append(row | same_as_3d(row))  # a label of the object itself: both associations are the same
    return rows
