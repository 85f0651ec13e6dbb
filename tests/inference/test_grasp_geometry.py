"""The clearance check on an analytic shape: a solid half-space below z = 0 (SDF = z)."""

import numpy as np

from centerart.geometry.transforms import make_pose
from centerart.inference.grasp_geometry import GeometryCheckConfig, clear_grasps, open_gripper_points

DOWN = np.diag([1.0, -1.0, -1.0])  # TCP z (approach) along world -z: a top-down grasp


def _top_down(height: float) -> np.ndarray:
    return make_pose(DOWN, [0.1, 0.2, height])


def half_space(points: np.ndarray) -> np.ndarray:
    return points[:, 2]


def test_gripper_points_fill_palm_and_fingers():
    pts = open_gripper_points()
    assert abs(pts[:, 2].max()) < 1e-9  # the deepest checked points are at the TCP, fingertips 5 mm past it
    assert pts[:, 2].min() < -0.08  # the palm, up to its last row of cells (its back is at -0.1034)
    assert np.abs(pts[:, 1]).max() > 0.04  # both fingers, outside the 8 cm opening


def test_clearance_against_a_half_space():
    heights = [0.03, 0.0, -0.002, -0.004, -0.05]
    ok = clear_grasps(half_space, np.stack([_top_down(h) for h in heights]), GeometryCheckConfig(clearance_m=0.003))
    # 3 cm above: clear; pads at the surface: clear; 2 mm in: within the margin; 4 mm and 5 cm in: blocked
    assert ok.tolist() == [True, True, True, False, False]


def test_disabled_or_empty():
    assert clear_grasps(half_space, np.stack([_top_down(-0.05)]), GeometryCheckConfig(enabled=False)).all()
    assert clear_grasps(half_space, np.zeros((0, 4, 4))).shape == (0,)


def test_grasp_from_the_side_clears_where_a_top_down_one_does_not():
    side = make_pose(np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]]), [0.0, 0.0, 0.06])  # approach along +x
    assert clear_grasps(half_space, np.stack([side, _top_down(-0.02)])).tolist() == [True, False]


def test_material_between_pads_and_clearance_are_the_least_sdf_of_their_regions():
    """Top-down over the half-space: the closing region spans the pads' 2 cm length about the TCP, so its least SDF
    is the TCP height less a third of it; the clearance checks the palm and fingers down to the TCP only."""
    from centerart.inference.grasp_geometry import gripper_clearance, material_between_pads

    poses = np.stack([_top_down(h) for h in (0.05, 0.005, -0.01)])
    between = material_between_pads(half_space, poses)
    assert np.allclose(between, [0.05, 0.005, -0.01] - np.array(0.02 / 3), atol=1e-9)
    assert between[2] < 0 < between[0]  # the pads close on material only when the TCP is at or under the surface
    clearance = gripper_clearance(half_space, poses)
    assert np.allclose(clearance, [0.05, 0.005, -0.01], atol=1e-9)
    assert material_between_pads(half_space, np.zeros((0, 4, 4))).shape == (0,)
