"""Shape and grasp metrics on cases with known answers."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from centerart.evaluation import metrics as m
from centerart.geometry.transforms import make_pose, rotation_about_axis
from centerart.grasps.gripper import FLIP_Z


def test_identical_meshes_give_zero_and_full_fscore():
    box = trimesh.creation.box(extents=[0.4, 0.3, 0.2])
    res = m.shape_metrics(box, box, samples=5000)
    assert res.chamfer_l1_mm == pytest.approx(0.0, abs=1e-3)
    assert res.fscore == 1.0 and res.precision == 1.0 and res.recall == 1.0
    pts = m.surface_samples(box, 2000, seed=0)
    exact = m.shape_metrics_points(pts, pts)
    assert exact.chamfer_l1_mm == 0.0 and exact.fscore == 1.0


def test_spheres_5mm_apart():
    small = trimesh.creation.icosphere(subdivisions=5, radius=0.2)
    large = trimesh.creation.icosphere(subdivisions=5, radius=0.205)
    res = m.shape_metrics(small, large, samples=30_000)
    assert res.chamfer_l1_mm == pytest.approx(5.0, abs=0.1)
    assert res.fscore == 1.0  # 5 mm < 1 cm
    far = trimesh.creation.icosphere(subdivisions=5, radius=0.22)  # 2 cm apart: nothing within 1 cm
    assert m.shape_metrics(small, far, samples=5000).fscore == 0.0


def test_fscore_partial_shape():
    """Half the true surface predicted: precision 1, recall about 0.5."""
    truth = trimesh.creation.box(extents=[0.4, 0.4, 0.4])
    pts_truth = m.surface_samples(truth, 20_000, 0)
    pred = pts_truth[pts_truth[:, 0] > 0.05]
    res = m.shape_metrics_points(pred, pts_truth)
    assert res.precision == 1.0
    assert 0.3 < res.recall < 0.6
    assert res.fscore == pytest.approx(2 * res.recall / (1 + res.recall))


def test_shape_metrics_are_seeded():
    a = trimesh.creation.box(extents=[0.4, 0.3, 0.2])
    b = trimesh.creation.icosphere(radius=0.2)
    assert m.chamfer_l1_mm(a, b, seed=3) == m.chamfer_l1_mm(a, b, seed=3)


def test_grasp_distance_finger_symmetry():
    g = make_pose(rotation_about_axis([1, 1, 0], 0.7), [0.1, 0.2, 0.3])
    assert m.grasp_distance(g, g @ FLIP_Z) == pytest.approx((0.0, 0.0), abs=1e-5)
    turned = g @ make_pose(rotation_about_axis([0, 0, 1], np.radians(100)))
    assert m.grasp_distance(g, turned)[1] == pytest.approx(80.0, abs=1e-4)  # 100 deg = 80 deg from the flip
    tilted = g @ make_pose(rotation_about_axis([1, 0, 0], np.radians(20)), [0.03, 0.0, 0.04])
    pos, ang = m.grasp_distance(g, tilted)
    assert pos == pytest.approx(0.05) and ang == pytest.approx(20.0, abs=1e-4)


def test_precision_coverage_known_counts():
    labels = np.stack([make_pose(translation=[x, 0.0, 0.0]) for x in (0.0, 0.5, 1.0, 1.5)])
    preds = np.stack(
        [
            make_pose(translation=[0.01, 0.0, 0.0]) @ FLIP_Z,  # matches label 0 (flipped fingers)
            make_pose(rotation_about_axis([1, 0, 0], np.radians(40)), [0.5, 0.0, 0.0]),  # 40 deg: no
            make_pose(translation=[1.0, 0.015, 0.0]),  # matches label 2
            make_pose(translation=[3.0, 0.0, 0.0]),  # far
        ]
    )
    res = m.grasp_precision_coverage(preds, labels)
    assert res.precision == 0.5 and res.coverage == 0.5
    top1 = m.grasp_precision_coverage(preds, labels, k=1)
    assert top1.precision == 1.0 and top1.coverage == 0.25
    assert np.isnan(m.grasp_precision_coverage(np.zeros((0, 4, 4)), labels).precision)
    # Relaxed success takes 45 deg and 3 cm: the 40-degree grasp is relaxed-successful.
    assert m.relaxed_success(preds[1], labels)
    assert not m.relaxed_success(preds[3], labels)
    assert not m.relaxed_success(None, labels)
    assert not m.relaxed_success(preds[0], np.zeros((0, 4, 4)))


def test_nearest_label_distribution():
    labels = np.stack([make_pose(translation=[x, 0.0, 0.0]) for x in (0.0, 1.0)])
    grasps = np.stack([make_pose(translation=[x, 0.0, 0.0]) for x in (0.01, 0.025, 0.9, 0.5)])
    d = m.nearest_label_position_m(grasps, labels)
    np.testing.assert_allclose(d, [0.01, 0.025, 0.1, 0.5])
    dist = m.distance_distribution(d)
    assert dist["within_match_m"]["share"] == 0.25 and dist["within_relaxed_m"]["share"] == 0.5
    assert np.isinf(m.nearest_label_position_m(grasps, np.zeros((0, 4, 4)))).all()
    assert m.thresholds()["relaxed_angle_deg"] == 45.0


def test_score_calibration_on_known_cases():
    scores = np.array([0.1, 0.15, 0.9, 0.95])
    ranked = m.score_calibration(scores, np.array([False, False, True, True]))
    assert ranked["auroc"] == 1.0 and ranked["success_rate"] == 0.5
    # bins [0, 0.2): mean 0.125, none succeed; [0.8, 1]: mean 0.925, all succeed -> ECE = 0.5*0.125 + 0.5*0.075
    assert ranked["ece"] == pytest.approx(0.1)
    assert ranked["brier"] == pytest.approx(np.mean([0.01, 0.0225, 0.01, 0.0025]))
    assert [b["count"] for b in ranked["bins"]] == [2, 0, 0, 0, 2]
    reversed_ = m.score_calibration(scores, np.array([True, True, False, False]))
    assert reversed_["auroc"] == 0.0 and reversed_["ece"] == pytest.approx(0.9)
    ties = m.score_calibration(np.full(4, 0.5), np.array([True, False, True, False]))
    assert ties["auroc"] == 0.5 and ties["bins"][2]["success_rate"] == 0.5
    assert m.score_calibration(scores, np.ones(4, bool))["auroc"] is None  # one class: no ranking to judge
    assert m.score_calibration(np.zeros(0), np.zeros(0, bool))["ece"] is None
    with pytest.raises(ValueError, match="outcomes"):
        m.score_calibration(scores, np.ones(3, bool))
