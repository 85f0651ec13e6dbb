"""``predictions.json`` with grasp anchoring's fields: written, read back and rebuilt as ObjectPrediction (round
trip); an older file without them still reads; the predict summary line of the anchoring counts.

Hand-made predictions, OpenCV camera frame, metres: one object 1.5 m ahead with two kept grasps (sources and
closing points) and three rejected candidates, one of each reason.
"""

from __future__ import annotations

import json

import numpy as np

from centerart.geometry.camera import Intrinsics
from centerart.geometry.transforms import make_pose
from centerart.inference.prediction_io import (
    REJECTION_REASONS,
    object_predictions,
    predictions_record,
    read_predictions,
)
from centerart.inference.predictor import ObjectPrediction
from centerart.predict import anchoring_summary

K = np.array([[500.0, 0.0, 319.5], [0.0, 500.0, 239.5], [0.0, 0.0, 1.0]])
COUNTS = {"candidates_decoder": 30, "candidates_observed": 80, "candidates_handle": 2, "snapped": 90,
          "material_between_pads": 40, "clear": 12, "kept": 2}  # fmt: skip


def hand_made_prediction(anchored: bool = True) -> ObjectPrediction:
    centre = np.array([0.1, 0.0, 1.5])
    kept = np.stack([make_pose(translation=centre + np.array([dx, 0.0, -0.1])) for dx in (0.0, 0.05)])
    rejected = np.stack([make_pose(translation=centre + np.array([dx, 0.02, -0.1])) for dx in (-0.1, 0.1, 0.2)])
    rejected[:, :3, 3] += 1.23456789e-4  # not on the 10-micrometre grid: the file rounds it
    return ObjectPrediction(
        score=0.9, camera_T_object=make_pose(translation=centre), joint_type="revolute", joint_type_probability=0.97,
        axis_direction=np.array([0.0, 1.0, 0.0]), axis_point=centre + np.array([0.2, 0.0, 0.0]), joint_state=0.5,
        joint_state_normalized=0.3, shape_code=np.arange(4, dtype=np.float32), grasp_poses=kept,
        grasp_scores=np.array([0.8, 0.6]), grasp_opening_directions=np.tile([1.0, 0.0, 0.0], (2, 1)),
        peak_uv=np.array([352.8, 239.5]), refinement={"anchoring": dict(COUNTS)} if anchored else {},
        grasp_sources=["observed", "handle"] if anchored else [],
        grasp_closing_points=np.array([23, 9]) if anchored else None,
        rejected_grasps=rejected if anchored else None,
        rejected_reasons=list(REJECTION_REASONS) if anchored else [],
    )  # fmt: skip


def write(tmp_path, preds) -> dict:
    record = predictions_record(preds, Intrinsics.from_matrix(K, 640, 480), {}, {}, {}, {})
    (tmp_path / "predictions.json").write_text(json.dumps(record))
    return read_predictions(tmp_path)


def test_anchoring_fields_round_trip(tmp_path):
    pred = hand_made_prediction()
    data = write(tmp_path, [pred])
    obj = data["objects"][0]
    assert [g["source"] for g in obj["grasps"]] == ["observed", "handle"]
    assert [g["closing_points"] for g in obj["grasps"]] == [23, 9]
    assert [r["reason"] for r in obj["rejected_grasps"]] == list(REJECTION_REASONS)
    assert obj["refinement"]["anchoring"] == COUNTS
    (back,) = object_predictions(data)
    assert back.grasp_sources == pred.grasp_sources
    assert np.array_equal(back.grasp_closing_points, pred.grasp_closing_points)
    assert back.rejected_reasons == pred.rejected_reasons
    assert np.allclose(back.rejected_grasps, pred.rejected_grasps, atol=1e-5)
    assert not np.array_equal(back.rejected_grasps, pred.rejected_grasps)  # rounded to 10 micrometres
    assert np.allclose(back.grasp_poses, pred.grasp_poses) and np.allclose(back.grasp_scores, pred.grasp_scores)
    assert np.allclose(back.camera_T_object, pred.camera_T_object) and back.joint_type == "revolute"
    assert back.refinement["anchoring"] == COUNTS and back.mask is None


def test_anchoring_off_writes_no_anchoring_keys(tmp_path):
    data = write(tmp_path, [hand_made_prediction(anchored=False)])
    obj = data["objects"][0]
    assert "rejected_grasps" not in obj and not any({"source", "closing_points"} & set(g) for g in obj["grasps"])
    (back,) = object_predictions(data)
    assert back.grasp_sources == [] and back.grasp_closing_points is None and back.rejected_grasps is None
    assert anchoring_summary(obj) is None


def test_old_file_without_anchoring_reads(tmp_path):
    """A file as written before anchoring existed (same version: the new keys are optional)."""
    data = write(tmp_path, [hand_made_prediction()])
    old = json.loads(json.dumps(data))
    for obj in old["objects"]:
        del obj["rejected_grasps"]
        obj["refinement"] = {}
        for g in obj["grasps"]:
            del g["source"], g["closing_points"]
    (tmp_path / "predictions.json").write_text(json.dumps(old))
    (back,) = object_predictions(read_predictions(tmp_path))
    assert back.grasp_sources == [] and back.grasp_closing_points is None and back.rejected_grasps is None
    assert len(back.grasp_poses) == 2 and back.rejected_reasons == []


def test_anchoring_summary_line(tmp_path):
    obj = write(tmp_path, [hand_made_prediction()])["objects"][0]
    line = anchoring_summary(obj)
    assert line.startswith("anchoring: 2 kept of 112 candidates (decoder 30, observed 80, handle 2;")
    assert "material between pads 40" in line and "top grasp from observed, 23 points between pads" in line
