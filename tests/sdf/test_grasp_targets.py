from __future__ import annotations

import numpy as np

from centerart.geometry.transforms import make_pose, rotation_about_axis
from centerart.grasps.gripper import CONTROL_POINTS_TCP
from centerart.sdf.grasp_targets import nearest_grasp_targets


def test_nearest_grasp_targets_known_case():
    g0 = make_pose(np.eye(3), [0.0, 0.0, 0.0])
    g1 = make_pose(rotation_about_axis([0, 0, 1], np.pi / 2), [1.0, 0.0, 0.0])
    points = np.array([[0.1, 0.0, 0.0], [0.9, 0.2, 0.0], [0.49, 0.0, 0.0], [0.51, 0.0, 0.0]])
    cps, dist = nearest_grasp_targets(points, np.stack([g0, g1]))
    assert cps.shape == (4, 5, 3) and cps.dtype == np.float32
    np.testing.assert_allclose(dist, [0.1, np.hypot(0.1, 0.2), 0.49, 0.49], atol=1e-6)
    np.testing.assert_allclose(cps[0], CONTROL_POINTS_TCP, atol=1e-6)
    np.testing.assert_allclose(cps[2], CONTROL_POINTS_TCP, atol=1e-6)
    # g1: turned 90 degrees about z, so the fingers' +-y becomes -+x, and moved to x = 1.
    expected = CONTROL_POINTS_TCP[:, [1, 0, 2]] * [-1, 1, 1] + [1.0, 0.0, 0.0]
    np.testing.assert_allclose(cps[1], expected, atol=1e-6)
    np.testing.assert_allclose(cps[3], expected, atol=1e-6)


def test_no_grasps_gives_inf_and_zeros():
    cps, dist = nearest_grasp_targets(np.zeros((3, 3)), np.zeros((0, 4, 4)))
    assert np.isinf(dist).all() and not cps.any() and cps.shape == (3, 5, 3)


def test_matches_brute_force():
    rng = np.random.default_rng(0)
    poses = np.tile(np.eye(4), (50, 1, 1))
    poses[:, :3, 3] = rng.uniform(-0.5, 0.5, (50, 3))
    pts = rng.uniform(-0.6, 0.6, (500, 3))
    _, dist = nearest_grasp_targets(pts, poses)
    brute = np.linalg.norm(pts[:, None] - poses[None, :, :3, 3], axis=-1).min(1)
    np.testing.assert_allclose(dist, brute, atol=1e-6)
