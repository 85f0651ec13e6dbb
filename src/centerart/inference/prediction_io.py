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
    "grasps": [{"camera_T_tcp": 4x4, "score": 0.8, "opening_direction_camera": [3]}],   (ranked, best first)
    "mesh": "object_00.ply" | null
  }]
}
```
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


#: What readers of predictions.json (the viewer) rely on; checked by :func:`read_predictions`.
GRASP_SCHEMA = {"camera_T_tcp": array(4, 4), "score": float}
JOINT_SCHEMA = {
    "type": str,
    "state_normalized": float,
    "axis_direction_camera": array(3),
    "axis_point_camera": array(3),
}
OBJECT_SCHEMA = {"camera_T_object": array(4, 4), "joint": JOINT_SCHEMA, "shape_code": array(None),
                 "grasps": [GRASP_SCHEMA], "mesh?": optional(str)}  # fmt: skip
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
        "grasps": [
            {"camera_T_tcp": g.tolist(), "score": float(s), "opening_direction_camera": d.tolist()}
            for g, s, d in zip(pred.grasp_poses, pred.grasp_scores, pred.grasp_opening_directions, strict=True)
        ],
        "mesh": mesh_file,
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
