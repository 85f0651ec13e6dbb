"""Encoder targets from a hand-made two-object label."""

import numpy as np

from centerart.models.encoder.inputs import Letterbox
from centerart.training.encoder_targets import MIN_CELL_WEIGHT, build_targets


def _object(object_id, mean_uv, t, bbox, joint_type="revolute"):
    pose = np.eye(4)
    pose[:3, 3] = t
    return {
        "object_id": object_id,
        "category": "oven",
        "camera_T_object": pose.tolist(),
        "visible_fraction": 1.0,
        "bbox_xyxy": bbox,
        "heatmap_gaussian": {"mean_uv": list(mean_uv), "cov_uv": [[100.0, 0.0], [0.0, 64.0]]},
        "joint": {
            "type": joint_type,
            "axis_origin_camera": [t[0] + 0.2, t[1] - 1.0, t[2] - 0.3],
            "axis_direction_camera": [0.0, 2.0, 0.0],
            "state": 0.4,
            "state_normalized": 0.25,
        },
    }


LABELS = {
    "width": 160,
    "height": 120,
    "K": [[150.0, 0.0, 79.5], [0.0, 150.0, 59.5], [0.0, 0.0, 1.0]],
    # a: origin projects to (49.5, 59.5), inside its box -> the peak goes there; b: origin projects to (109.5, 41.5),
    # outside its box (hidden or truncated centre) -> the peak stays at the mask centroid (120, 30).
    "objects": [
        _object("a", (40, 60), [-0.4, 0.0, 2.0], [20, 40, 70, 80]),
        _object("b", (120, 30), [0.5, -0.3, 2.5], [115, 20, 159, 40], "prismatic"),
    ],
}


def test_two_object_targets():
    box = Letterbox.fit(160, 120, 80, 60)  # half resolution
    t = build_targets(LABELS, box, {"a": np.full(4, 0.5, np.float32)}, code_dim=4, stride=8, max_objects=3)
    heat = t["heatmap"]
    assert heat.shape == (60, 80)
    # Peaks move with the letterbox: (u + 0.5) * 0.5 - 0.5: a at (24.5, 29.5), b at (59.75, 14.75).
    assert heat[29:31, 24:26].max() > 0.95 and heat[round(14.75), round(59.75)] > 0.95
    assert heat[0, 40] < 0.05
    obj = t["cell_object"]
    assert obj.shape == (8, 10)
    assert obj[29 // 8, 24 // 8] == 0 and obj[14 // 8, 59 // 8] == 1
    assert (t["cell_weight"][obj >= 0] > MIN_CELL_WEIGHT).all() and (
        obj[t["cell_weight"] <= MIN_CELL_WEIGHT] == -1
    ).all()
    assert t["present"].tolist() == [True, True, False]
    assert t["shape_code_valid"].tolist() == [True, False, False] and np.allclose(t["shape_code"][0], 0.5)
    assert t["joint_type"][:2].tolist() == [0, 1]
    assert np.allclose(t["axis_direction"][0], [0, 1, 0])
    # Nearest axis point to the origin: the axis runs along y through (t.x + 0.2, *, t.z - 0.3).
    assert np.allclose(t["axis_point_offset"][0], [0.2, 0.0, -0.3])
    assert np.allclose(t["K"], [[75.0, 0, 39.5], [0, 75.0, 29.5], [0, 0, 1]])


def test_objects_whose_centre_leaves_the_input_are_dropped():
    box = Letterbox(1.0, 100.0, 0.0, 60, 120)  # keeps columns 100..159 only
    t = build_targets(LABELS, box, {}, code_dim=4, stride=8, max_objects=3)
    assert t["present"].tolist() == [True, False, False]
    assert np.allclose(t["translation"][0], [0.5, -0.3, 2.5])


def test_view_metrics_on_a_known_case():
    from centerart.models.encoder.readout import Detection
    from centerart.training.encoder_metrics import summarize, view_metrics

    labels = {"objects": [dict(o, visible_fraction=v) for o, v in zip(LABELS["objects"], (1.0, 0.2), strict=True)]}

    def det(t, uv):
        pose = np.eye(4)
        pose[:3, 3] = t
        return Detection(0.9, np.asarray(uv, float), pose, np.zeros(4), 0.25, "revolute", 0.9,
                         np.array([0.0, 1.0, 0.0]), np.zeros(3), 0.4)  # fmt: skip

    # One detection 5 cm from object a (peak on its box), one far from everything (peak off every box).
    result = summarize([view_metrics([det([-0.35, 0.0, 2.0], (45, 60)), det([2.0, 2.0, 5.0], (5, 5))], labels)])
    assert result["recall"] == 1.0 and result["precision"] == 0.5  # b is under 30% visible: not counted
    assert result["image_recall"] == 1.0 and result["image_precision"] == 0.5
    assert abs(result["translation_cm_median"] - 5.0) < 1e-6 and result["joint_type_accuracy"] == 1.0
