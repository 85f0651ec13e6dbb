"""Gravity from a camera pose and from the floor seen in the depth (rendered kitchens, random clouds)."""

from __future__ import annotations

import numpy as np
import pytest

from centerart.geometry.camera import backproject_depth
from centerart.geometry.gravity import estimate_gravity, gravity_from_world_T_camera, support_planes
from centerart.scenes.cameras import look_at_opencv


def _angle_deg(a, b) -> float:
    return float(np.degrees(np.arccos(np.clip(np.dot(a, b), -1.0, 1.0))))


def test_gravity_from_pose_points_down_the_image_for_a_pitched_camera():
    """A camera 30 degrees pitched down without roll sees gravity as (0, cos 30, sin 30) (image-down, forward)."""
    eye = np.array([2.0, 0.0, 1.0 + 2.0 * np.tan(np.radians(30))])
    g = gravity_from_world_T_camera(look_at_opencv(eye, [0.0, 0.0, 1.0]))
    assert np.allclose(g, [0.0, np.cos(np.radians(30)), np.sin(np.radians(30))], atol=1e-9)


def test_floor_and_wall_give_the_floor(tmp_path):
    """A synthetic floor and a back wall with the wall the larger plane: the floor's normal is chosen."""
    rng = np.random.default_rng(0)
    floor = np.c_[rng.uniform(0, 3, 4000), rng.uniform(-2, 2, 4000), np.zeros(4000)]
    wall = np.c_[np.zeros(9000), rng.uniform(-2, 2, 9000), rng.uniform(0, 3, 9000)]
    world_T_camera = look_at_opencv([2.5, 0.3, 1.6], [0.0, 0.0, 0.9])
    R, t = world_T_camera[:3, :3], world_T_camera[:3, 3]
    pts = (np.concatenate([floor, wall]) - t) @ R  # camera frame
    pts = pts[pts[:, 2] > 0.1]
    g = estimate_gravity(pts)
    assert g is not None and _angle_deg(g, gravity_from_world_T_camera(world_T_camera)) < 1.0


def test_random_points_have_no_floor():
    rng = np.random.default_rng(1)
    pts = rng.uniform([-1.0, -1.0, 1.0], [1.0, 1.0, 3.0], (20_000, 3))
    assert estimate_gravity(pts) is None
    assert estimate_gravity(np.zeros((10, 3))) is None


@pytest.mark.slow
def test_estimated_gravity_matches_the_camera_pose_in_rendered_kitchens(kitchen_dataset):
    """Kitchen views (tiny images, true depth): the estimate is within 5 degrees of world -z.

    Stereo depth is only printed: its far floor is a band several cm thick, and on 16 more kitchen views (seed 11)
    the estimate was within 5 degrees on 6 only (3 None, 7 off by 13-38 degrees); true depth: 15 of 16 within
    1 degree, one view without floor 22 degrees off."""
    from centerart.scenes.dataset import list_views, load_view

    errors, stereo = [], []
    for view_dir in list_views(kitchen_dataset):
        view = load_view(view_dir)
        truth = gravity_from_world_T_camera(np.asarray(view.labels["world_T_camera"]))
        K = np.asarray(view.labels["K"])
        pts = backproject_depth(view.depth_true, K)
        g = estimate_gravity(pts)
        assert g is not None, (view_dir, support_planes(pts))
        errors.append(_angle_deg(g, truth))
        g = estimate_gravity(backproject_depth(view.depth_realistic, K))
        stereo.append(None if g is None else round(_angle_deg(g, truth), 2))
    print("gravity errors (deg), true depth:", np.round(errors, 2), "stereo:", stereo)
    assert max(errors) < 5.0, errors
