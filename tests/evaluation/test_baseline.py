"""The geometric baseline on point clouds with a known handle."""

from __future__ import annotations

import numpy as np

from centerart.evaluation.baseline import GRASP_DEPTH_M, baseline_grasps


def _front_with_bar(proud: float = 0.04, bar_axis=(1.0, 0.0, 0.0)) -> np.ndarray:
    """A 0.6 m x 0.6 m front face 1.5 m in front of the camera (OpenCV frame, z forward) and a 0.2 m bar
    ``proud`` metres in front of it (toward the camera), centred at (0.1, -0.1)."""
    rng = np.random.default_rng(0)
    face = np.c_[rng.uniform(-0.3, 0.3, (6000, 2)), np.full(6000, 1.5)]
    t = rng.uniform(-0.1, 0.1, 400)
    axis = np.asarray(bar_axis, float)
    bar = np.array([0.1, -0.1, 1.5 - proud]) + t[:, None] * axis + rng.normal(0, 0.003, (400, 3)) * [1, 1, 0]
    return np.vstack([face, bar])


def test_grasp_closes_across_the_bar_from_the_front():
    for bar_axis in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)):
        grasps = baseline_grasps(_front_with_bar(bar_axis=bar_axis))
        assert len(grasps) >= 1
        g = grasps[0]
        np.testing.assert_allclose(g[:3, 2], [0, 0, 1], atol=0.05)  # approach into the face, away from the camera
        assert abs(g[:3, 0] @ np.asarray(bar_axis)) > 0.95  # finger width along the bar: fingers close across it
        np.testing.assert_allclose(g[:2, 3], [0.1, -0.1], atol=0.02)
        assert abs(g[2, 3] - (1.5 - 0.04 + GRASP_DEPTH_M)) < 0.01
        np.testing.assert_allclose(g[:3, :3] @ g[:3, :3].T, np.eye(3), atol=1e-9)


def test_a_flat_front_has_no_handle():
    assert len(baseline_grasps(_front_with_bar(proud=0.0))) == 0
    assert len(baseline_grasps(np.zeros((0, 3)))) == 0
