"""Encoder metrics on one labelled view: detection precision / recall and per-object pose and joint errors.

Thresholds (constants, printed in every report that uses them): a prediction matches a labelled object when their
3-D centres (object origins, camera frame) are closer than ``MATCH_DISTANCE_M`` (Hungarian assignment); recall
counts labelled objects at least ``MIN_VISIBLE_FRACTION`` visible; a prediction matched to a less visible object
is neither a true nor a false positive. ``image_recall`` / ``image_precision`` are a looser image-space check
(a peak inside a labelled object's bounding box), which tells "found in the image" apart from "3-D centre right".
"""

from __future__ import annotations

import numpy as np

from centerart.geometry.matching import match_points
from centerart.geometry.transforms import rotation_angle_between
from centerart.models.encoder.readout import Detection

MATCH_DISTANCE_M = 0.10
MIN_VISIBLE_FRACTION = 0.3


def batch_detections(out, batch: dict, config) -> list[list[Detection]]:
    """The read-out objects of every view of an un-augmented batch (its letterbox is the plain fit), their peaks
    mapped back to the labelled camera's pixels. ``config``: the encoder's config (input size, read-out radius)."""
    from centerart.models.encoder.inputs import Letterbox
    from centerart.models.encoder.readout import read_objects

    views = []
    for b, meta in enumerate(batch["meta"]):
        detections = read_objects(out, batch["K"][b].cpu().numpy(), index=b, radius_cells=config.read_radius_cells)
        labels = meta["labels"]
        box = Letterbox.fit(labels["width"], labels["height"], config.input_width, config.input_height)
        for d in detections:
            d.peak_uv = box.to_camera_pixels(d.peak_uv)
        views.append(detections)
    return views


def batch_view_metrics(out, batch: dict, config, codes: dict | None = None, shape_error=None) -> list[dict]:
    """:func:`view_metrics` of every view of an un-augmented batch (:func:`batch_detections`)."""
    detections = batch_detections(out, batch, config)
    return [view_metrics(d, meta["labels"], codes, shape_error)
            for d, meta in zip(detections, batch["meta"], strict=True)]  # fmt: skip


def view_metrics(detections: list[Detection], labels: dict, codes: dict | None = None, shape_error=None) -> dict:
    """Counts and a list of per-object error rows (matched labelled objects) for one view. ``shape_error``: an
    optional judge of the regressed code (``training.shape_validation.HeldOutShapeError``), which adds
    ``shape_sdf_mm`` to the rows it can judge."""
    objects = labels["objects"]
    true_t = np.array([np.asarray(o["camera_T_object"])[:3, 3] for o in objects]).reshape(-1, 3)
    pred_t = np.array([d.camera_T_object[:3, 3] for d in detections]).reshape(-1, 3)
    pairs = match_points(pred_t, true_t, MATCH_DISTANCE_M)
    visible = [o["visible_fraction"] >= MIN_VISIBLE_FRACTION for o in objects]
    matched_true = {j for _, j in pairs}
    counts = {
        "true_objects": int(sum(visible)),
        "found": int(sum(1 for j in matched_true if visible[j])),
        "predictions": len(detections) - sum(1 for _, j in pairs if not visible[j]),
        "true_positives": int(sum(1 for _, j in pairs if visible[j])),
        "all_predictions": len(detections),
    }
    rows = [object_errors(detections[i], objects[j], codes, shape_error) for i, j in pairs]
    for (i, j), row in zip(pairs, rows, strict=True):
        row["prediction"], row["label"] = i, j
    recall_rows = [{"category": o["category"], "found": j in matched_true} for j, o in enumerate(objects) if visible[j]]
    counts.update(image_counts(detections, objects, visible))
    return {"counts": counts, "rows": rows, "recall_rows": recall_rows}


def peak_in_box(uv, box) -> bool:
    """Whether a heatmap peak (u, v camera pixels, or None) lies in a labelled box (x0, y0, x1, y1, pixels)."""
    return uv is not None and box[0] <= uv[0] <= box[2] and box[1] <= uv[1] <= box[3]


def image_counts(detections, objects: list[dict], visible: list[bool]) -> dict:
    """A looser, image-space check: is a visible object's box hit by some peak, and does each peak lie in some
    object's box? Separates "found in the image" from "3-D centre within the match distance"."""
    peaks = [getattr(d, "peak_uv", None) for d in detections]
    boxes = [o["bbox_xyxy"] for o in objects]
    return {
        "found_in_image": sum(1 for j, b in enumerate(boxes) if visible[j] and any(peak_in_box(p, b) for p in peaks)),
        "peaks_on_objects": sum(1 for p in peaks if any(peak_in_box(p, b) for b in boxes)),
    }


def object_errors(det: Detection, obj: dict, codes: dict | None = None, shape_error=None) -> dict:
    pose = np.asarray(obj["camera_T_object"], float)
    joint = obj["joint"]
    axis = np.asarray(joint["axis_direction_camera"], float)
    axis /= np.linalg.norm(axis)
    scale = 180.0 / np.pi if joint["type"] == "revolute" else 100.0  # deg or cm
    row = {
        "object_id": obj["object_id"],
        "category": obj["category"],
        "visible_fraction": obj["visible_fraction"],
        "joint_type": joint["type"],
        "translation_cm": 100.0 * float(np.linalg.norm(det.camera_T_object[:3, 3] - pose[:3, 3])),
        "rotation_deg": float(np.degrees(rotation_angle_between(det.camera_T_object[:3, :3], pose[:3, :3]))),
        "joint_type_correct": det.joint_type == joint["type"],
        "axis_deg": float(np.degrees(np.arccos(np.clip(np.dot(det.axis_direction, axis), -1.0, 1.0)))),
        "joint_state_error": abs(det.joint_state - joint["state"]) * scale,
        "joint_code_error": abs(det.joint_code - joint["state_normalized"]),
    }
    if codes is not None and obj["object_id"] in codes:
        row["shape_code_l1"] = float(np.abs(det.shape_code - codes[obj["object_id"]]).mean())
    if shape_error is not None and (mm := shape_error(det.shape_code, obj)) is not None:
        row["shape_sdf_mm"] = mm
    return row


def summarize_by_category(results: list[dict]) -> dict[str, dict]:
    """Recall and median errors per object category."""
    cats = sorted({r["category"] for res in results for r in res["recall_rows"]})
    out = {}
    for cat in cats:
        found = [r["found"] for res in results for r in res["recall_rows"] if r["category"] == cat]
        rows = [row for res in results for row in res["rows"] if row["category"] == cat]
        out[cat] = {"true_objects": len(found), "recall": float(np.mean(found)), "matched": len(rows)}
        if rows:
            out[cat].update(summarize_rows(rows))
    return out


def summarize(results: list[dict]) -> dict:
    """Precision, recall and median errors over many views' :func:`view_metrics` results."""
    tp = sum(r["counts"]["true_positives"] for r in results)
    preds = sum(r["counts"]["predictions"] for r in results)
    true = sum(r["counts"]["true_objects"] for r in results)
    found = sum(r["counts"]["found"] for r in results)
    rows = [row for r in results for row in r["rows"]]
    in_image = sum(r["counts"].get("found_in_image", 0) for r in results)
    on_objects = sum(r["counts"].get("peaks_on_objects", 0) for r in results)
    all_preds = sum(r["counts"].get("all_predictions", 0) for r in results)
    out = {
        "views": len(results),
        "true_objects": true,
        "precision": tp / preds if preds else 0.0,
        "recall": found / true if true else 0.0,
        "matched": len(rows),
        "image_recall": in_image / true if true else 0.0,
        "image_precision": on_objects / all_preds if all_preds else 0.0,
    }
    if rows:
        out.update(summarize_rows(rows))
    return out


def summarize_rows(rows: list[dict]) -> dict:
    med = lambda key, sel=rows: float(np.median([r[key] for r in sel])) if sel else float("nan")  # noqa: E731
    rev = [r for r in rows if r["joint_type"] == "revolute"]
    pri = [r for r in rows if r["joint_type"] == "prismatic"]
    out = {
        "translation_cm_median": med("translation_cm"),
        "rotation_deg_median": med("rotation_deg"),
        "joint_type_accuracy": float(np.mean([r["joint_type_correct"] for r in rows])),
        "axis_deg_median": med("axis_deg"),
        "joint_state_deg_median": med("joint_state_error", rev),
        "joint_state_cm_median": med("joint_state_error", pri),
    }
    if any("shape_code_l1" in r for r in rows):
        out["shape_code_l1_mean"] = float(np.mean([r["shape_code_l1"] for r in rows if "shape_code_l1" in r]))
    if judged := [r["shape_sdf_mm"] for r in rows if "shape_sdf_mm" in r]:
        out["shape_sdf_mm_median"], out["shape_sdf_mm_mean"] = float(np.median(judged)), float(np.mean(judged))
    return out
