"""Augmentation keeps depth and K consistent: back-projected points do not move under scale and crop."""

import numpy as np

from centerart.geometry.camera import Intrinsics, backproject_depth
from centerart.models.encoder.inputs import Letterbox
from centerart.training.encoder_augment import AugmentConfig, choose_depth, jitter_colour, random_letterbox


def _plane_depth(w=160, h=120):
    v, u = np.mgrid[0:h, 0:w]
    return (1.5 + 0.004 * u + 0.002 * v).astype(np.float32)


def test_scale_and_crop_keep_back_projected_points():
    cam = Intrinsics(160, 120, 150.0, 150.0, 79.5, 59.5)
    depth = _plane_depth()
    rng = np.random.default_rng(0)
    for _ in range(5):
        box = random_letterbox(160, 120, 96, 72, AugmentConfig(), rng)
        _, depth_in = box.warp(np.zeros((120, 160, 3), np.uint8), depth)
        pts_in, uv_in = backproject_depth(depth_in, box.intrinsics(cam).K, return_pixels=True)
        # Each input pixel took the depth of its nearest camera pixel: the same 3-D point.
        uv_cam = np.round(box.to_camera_pixels(uv_in)).astype(int)
        full = backproject_depth(depth, cam.K)
        ref = full[uv_cam[:, 1] * 160 + uv_cam[:, 0]]
        lateral = np.abs(pts_in - ref)[:, :2].max()
        assert len(pts_in) > 100 and np.allclose(pts_in[:, 2], ref[:, 2])
        assert lateral < 0.6 * 2.5 / 150.0 / min(box.scale, 1.0) + 1e-6  # within the resampling of one pixel


def test_letterbox_round_trip_of_pixels():
    box = Letterbox(0.37, 12.0, -5.0, 100, 80)
    uv = np.array([[0.0, 0.0], [159.0, 119.0], [33.3, 71.2]])
    assert np.allclose(box.to_camera_pixels(box.to_input_pixels(uv)), uv)


def test_colour_jitter_and_depth_choice_are_seeded():
    rgb = (np.random.default_rng(1).random((40, 50, 3)) * 255).astype(np.uint8)
    a = jitter_colour(rgb, AugmentConfig(), np.random.default_rng(3))
    b = jitter_colour(rgb, AugmentConfig(), np.random.default_rng(3))
    assert np.array_equal(a, b) and not np.array_equal(a, rgb)
    depth = _plane_depth(50, 40)
    K = np.array([[600.0, 0, 24.5], [0, 600.0, 19.5], [0, 0, 1]])
    kinds = {choose_depth(depth, None, K, AugmentConfig(), np.random.default_rng(s))[1] for s in range(20)}
    assert kinds <= {"analytic", "true"} and "analytic" in kinds
    noisy, kind = choose_depth(
        depth, None, K, AugmentConfig(p_realistic_depth=0, p_analytic_depth=1), np.random.default_rng(0)
    )
    valid = noisy > 0
    assert (
        kind == "analytic"
        and 0.5 < valid.mean()
        and not np.array_equal(noisy, depth)
        and np.median(np.abs(noisy - depth)[valid]) < 0.02
    )
