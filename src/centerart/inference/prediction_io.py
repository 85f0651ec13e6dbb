"""``predictions.json``: the documented, versioned record of one prediction (schema below), and its reader.

Frames and units are stated in the file itself: every pose is a 4x4 ``camera_T_X`` in the OpenCV camera frame of
the input image (x right, y down, z forward), metres and radians.

```
{
  "format": "centerart-predictions", "version": 1,
  "frames": "...", "image": {"width", "height", "K"},
  "inputs": {"rgb": "rgb.png", "depth": "depth.npy", "points": "points.ply"},      (files beside this one)
  "checkpoints": {"encoder": {"path", "sha256"}, "decoder": {"path", "sha256"}},
  "config": {...PredictorConfig...}, "thresholds": {"peak": 0.5, ...}, "timing_s": {...},
  "objects": [{
    "index": 0, "score": 0.93, "peak_uv": [u, v], "mask_pixels": 5123,
    "camera_T_object": 4x4,
    "joint": {"type": "revolute", "type_probability": 0.98, "axis_direction_camera": [3], "axis_point_camera": [3],
              "state": 0.61, "unit": "rad", "state_normalized": 0.4},
    "shape_code": [...], "refinement": {...},
    "grasps": [{"camera_T_tcp": 4x4, "score": 0.8, "opening_direction_camera": [3],   (ranked, best first)
                "source": "observed", "closing_points": 23}],                          (anchoring on)
    "rejected_grasps": [{"camera_T_tcp": 4x4, "reason": "collides_with_observed"}],  (anchoring on)
    "mesh": "object_00.ply" | null
  }]
}
```

Grasp anchoring (:mod:`~centerart.inference.grasp_anchoring`, on by default) adds: per kept grasp its ``source``
(``decoder`` / ``observed`` / ``handle``) and ``closing_points`` (observed points of the object between its pads);
per object the ``rejected_grasps`` (candidate TCP poses, camera frame, rounded to 10 micrometres, each with the
reason it was rejected: one of :data:`REJECTION_REASONS`) and, in ``refinement.anchoring``, the counts of
candidates per source and of survivors of each check. These keys are optional: files written with anchoring off,
or before it existed, lack them and read the same (:func:`object_predictions` gives empty / None fields).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from centerart.errors import CenterArtError
from centerart.inference.predictor import ObjectPrediction
from centerart.utils.json_schema import array, json_problem, optional

FORMAT = "centerart-predictions"
VERSION = 1
FRAMES = (
    "OpenCV camera frame of the input image (x right, y down, z forward); metres, radians; "
    "poses are 4x4 camera_T_X; grasps are TCP poses (z approach, y finger closing, origin between the pads)"
)


#: Why anchoring rejects a candidate (:mod:`~centerart.inference.grasp_anchoring`), in the order of its checks.
REJECTION_REASONS = ("far_from_material", "no_material_between_pads", "collides_with_observed")
POSE_DECIMALS = 5  # rejected poses are only drawn: 10 micrometres and 1e-5 of a rotation entry are plenty

#: What readers of predictions.json (the viewer) rely on; checked by :func:`read_predictions`.
GRASP_SCHEMA = {"camera_T_tcp": array(4, 4), "score": float, "source?": str, "closing_points?": int}
REJECTED_SCHEMA = {"camera_T_tcp": array(4, 4), "reason": str}
JOINT_SCHEMA = {
    "type": str,
    "state_normalized": float,
    "axis_direction_camera": array(3),
    "axis_point_camera": array(3),
}
OBJECT_SCHEMA = {"camera_T_object": array(4, 4), "joint": JOINT_SCHEMA, "shape_code": array(None),
                 "grasps": [GRASP_SCHEMA], "rejected_grasps?": [REJECTED_SCHEMA], "mesh?": optional(str)}  # fmt: skip
PREDICTIONS_SCHEMA = {"image": {"K": array(3, 3), "width": int, "height": int}, "objects": [OBJECT_SCHEMA]}


def object_record(index: int, pred: ObjectPrediction, mesh_file: str | None) -> dict:
    return {
        "index": index,
        "score": float(pred.score),
        "peak_uv": None if pred.peak_uv is None else np.asarray(pred.peak_uv, float).round(2).tolist(),
        "mask_pixels": None if pred.mask is None else int(pred.mask.sum()),
        "camera_T_object": np.asarray(pred.camera_T_object).tolist(),
        "joint": {
            "type": pred.joint_type,
            "type_probability": float(pred.joint_type_probability),
            "axis_direction_camera": np.asarray(pred.axis_direction).tolist(),
            "axis_point_camera": np.asarray(pred.axis_point).tolist(),
            "state": float(pred.joint_state),
            "unit": pred.joint_unit,
            "state_normalized": float(pred.joint_state_normalized),
        },
        "shape_code": np.asarray(pred.shape_code).tolist(),
        "refinement": pred.refinement,
        "grasps": grasp_records(pred),
        **rejected_record(pred),
        "mesh": mesh_file,
    }


def grasp_records(pred: ObjectPrediction) -> list[dict]:
    """The ranked grasps (camera-frame TCP poses), with source and closing points where anchoring gave them."""
    rows = [
        {"camera_T_tcp": g.tolist(), "score": float(s), "opening_direction_camera": d.tolist()}
        for g, s, d in zip(pred.grasp_poses, pred.grasp_scores, pred.grasp_opening_directions, strict=True)
    ]
    if len(pred.grasp_sources) == len(rows):
        for row, source in zip(rows, pred.grasp_sources, strict=True):
            row["source"] = str(source)
    if pred.grasp_closing_points is not None and len(pred.grasp_closing_points) == len(rows):
        for row, n in zip(rows, pred.grasp_closing_points, strict=True):
            row["closing_points"] = int(n)
    return rows


def rejected_record(pred: ObjectPrediction) -> dict:
    """``{"rejected_grasps": [...]}`` (camera-frame TCP poses and reasons) when anchoring ran, else nothing."""
    if pred.rejected_grasps is None:
        return {}
    poses = np.asarray(pred.rejected_grasps, float).reshape(-1, 4, 4).round(POSE_DECIMALS)
    return {
        "rejected_grasps": [
            {"camera_T_tcp": pose.tolist(), "reason": str(reason)}
            for pose, reason in zip(poses, pred.rejected_reasons, strict=True)
        ]
    }


def predictions_record(preds, camera, checkpoints: dict, config: dict, timing: dict, files: dict) -> dict:
    return {
        "format": FORMAT,
        "version": VERSION,
        "frames": FRAMES,
        "image": camera.to_dict(),
        "inputs": files.get("inputs", {}),
        "checkpoints": checkpoints,
        "config": config,
        "timing_s": {k: round(float(v), 4) for k, v in timing.items()},
        "objects": [object_record(i, p, files.get("meshes", {}).get(i)) for i, p in enumerate(preds)],
    }


def read_predictions(path: Path) -> dict:
    """A ``predictions.json`` (or the folder holding one), checked for its format and version."""
    path = Path(path)
    if path.is_dir():
        path = path / "predictions.json"
    if not path.is_file():
        raise CenterArtError(f"{path}: no predictions.json")
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as err:
        raise CenterArtError(f"{path}: not readable JSON ({err})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT or data.get("version") != VERSION:
        raise CenterArtError(f"{path}: not a centerart predictions file (format {FORMAT!r}, version {VERSION})")
    problem = json_problem(data, PREDICTIONS_SCHEMA)
    if problem:
        raise CenterArtError(f"{path}: not a valid predictions file ({problem})")
    return data


def object_predictions(data: dict) -> list[ObjectPrediction]:
    """The objects of a read ``predictions.json`` as :class:`ObjectPrediction` (camera frame, metres, radians), for
    pictures of a saved folder. Not saved, so absent: masks (None) and the mesher (``mesh()`` does not work).
    Files without the anchoring keys give empty ``grasp_sources``, and None closing points and rejected grasps."""
    return [_object_prediction(rec) for rec in data.get("objects", [])]


def _object_prediction(rec: dict) -> ObjectPrediction:
    joint, grasps = rec["joint"], rec.get("grasps") or []
    rejected = rec.get("rejected_grasps")
    sources = [g["source"] for g in grasps if "source" in g]
    closing = [g["closing_points"] for g in grasps if "closing_points" in g]
    anchored = rejected is not None or bool(closing)  # anchoring ran (it always writes rejected_grasps)
    return ObjectPrediction(
        score=float(rec.get("score", 0.0)),
        camera_T_object=np.asarray(rec["camera_T_object"], float),
        joint_type=joint["type"],
        joint_type_probability=float(joint.get("type_probability", float("nan"))),
        axis_direction=np.asarray(joint["axis_direction_camera"], float),
        axis_point=np.asarray(joint["axis_point_camera"], float),
        joint_state=float(joint.get("state", float("nan"))),
        joint_state_normalized=float(joint["state_normalized"]),
        shape_code=np.asarray(rec["shape_code"], np.float32),
        grasp_poses=np.asarray([g["camera_T_tcp"] for g in grasps], float).reshape(-1, 4, 4),
        grasp_scores=np.asarray([g["score"] for g in grasps], float),
        grasp_opening_directions=np.asarray(
            [g.get("opening_direction_camera", [np.nan] * 3) for g in grasps], float
        ).reshape(-1, 3),
        peak_uv=None if rec.get("peak_uv") is None else np.asarray(rec["peak_uv"], float),
        refinement=rec.get("refinement") or {},
        grasp_sources=sources if len(sources) == len(grasps) else [],
        grasp_closing_points=np.asarray(closing, int) if anchored and len(closing) == len(grasps) else None,
        rejected_grasps=None
        if rejected is None
        else np.asarray([r["camera_T_tcp"] for r in rejected], float).reshape(-1, 4, 4),
        rejected_reasons=[] if rejected is None else [r["reason"] for r in rejected],
    )
