import numpy as np
import pytest

from centerart.geometry.camera import (
    OPENCV_T_OPENGL,
    OPENCV_T_SAPIEN,
    Intrinsics,
    backproject_depth,
    depth_to_point_map,
    pixel_rays,
    project,
)

K = np.array([[600.0, 0.0, 319.5], [0.0, 610.0, 239.5], [0.0, 0.0, 1.0]])


def test_hand_computed_pixel():
    # (0.1, -0.05, 2.0): u = 600 * 0.05 + 319.5 = 349.5, v = 610 * -0.025 + 239.5 = 224.25
    uv, z = project(np.array([[0.1, -0.05, 2.0]]), K)
    assert np.allclose(uv, [[349.5, 224.25]]) and np.allclose(z, [2.0])


def test_project_backproject_round_trip():
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-1, 1, 50), rng.uniform(-1, 1, 50), rng.uniform(0.5, 4, 50)])
    uv, z = project(pts, K)
    assert np.allclose(pixel_rays(uv, K) * z[:, None], pts)


def test_points_behind_camera_have_no_pixel():
    uv, _ = project(np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]), K)
    assert not np.isfinite(uv[0]).any() and np.isfinite(uv[1]).all()


def test_backproject_depth_with_mask_and_holes():
    depth = np.full((4, 5), 2.0)
    depth[0, 0] = 0.0
    depth[1, 1] = np.nan
    mask = np.ones((4, 5), bool)
    mask[3, 4] = False
    pts, uv = backproject_depth(depth, K, mask=mask, return_pixels=True)
    assert len(pts) == 20 - 3
    back, _ = project(pts, K)
    assert np.allclose(back, uv)
    pmap = depth_to_point_map(depth, K)
    assert np.isnan(pmap[0, 0]).all() and np.allclose(pmap[2, 3], pts[(uv[:, 0] == 3) & (uv[:, 1] == 2)][0])


def test_scaling_keeps_points_on_their_pixels():
    intr = Intrinsics.from_matrix(K, 640, 480)
    half = intr.scaled(320, 240)
    assert half.fx == 300.0 and half.cx == 159.5 and half.cy == 119.5
    pts = np.array([[0.3, 0.2, 1.5], [-0.4, 0.1, 3.0]])
    uv, _ = project(pts, intr.K)
    uv_half, _ = project(pts, half.K)
    assert np.allclose((uv + 0.5) * 0.5 - 0.5, uv_half)


def test_crop_shifts_principal_point():
    intr = Intrinsics.from_matrix(K, 640, 480)
    crop = intr.cropped(100, 50, 200, 100)
    pts = np.array([[0.1, 0.05, 1.0]])
    assert np.allclose(project(pts, crop.K)[0], project(pts, intr.K)[0] - [100, 50])
    assert Intrinsics.from_dict(crop.to_dict()) == crop


def test_problems_name_bad_intrinsics():
    assert Intrinsics.from_matrix(K, 640, 480).problems() == []
    assert any("principal point" in p for p in Intrinsics.from_matrix(K, 200, 150).problems())
    with pytest.raises(ValueError):
        Intrinsics.from_matrix(np.eye(2), 10, 10)


def test_renderer_frames_are_rotations_between_documented_axes():
    for pose in (OPENCV_T_SAPIEN, OPENCV_T_OPENGL):
        assert np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3)) and np.isclose(np.linalg.det(pose[:3, :3]), 1)
    # SAPIEN forward (+x) is OpenCV +z; OpenGL's forward (-z) is OpenCV +z.
    assert np.allclose(OPENCV_T_SAPIEN[:3, 0], [0, 0, 1]) and np.allclose(-OPENCV_T_OPENGL[:3, 2], [0, 0, 1])
