"""Grasp collision filter and opening directions (camera frame)."""

import numpy as np

from centerart.geometry.transforms import make_pose
from centerart.inference.grasp_filter import CollisionFilterConfig, collision_free
from centerart.inference.predictor import opening_directions


def _slab(x0, x1, y0, y1, z, n=40):
    xs, ys = np.meshgrid(np.linspace(x0, x1, n), np.linspace(y0, y1, n))
    return np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, z)])


def test_grasp_into_a_wall_is_dropped_and_a_free_one_kept():
    # A wall at z = 0.5 (camera frame); grasps approach along +z.
    wall = _slab(-0.1, 0.1, -0.15, 0.15, 0.5, n=150)  # 1-2 mm spacing, as at 1-2 m from a D415
    free = make_pose(translation=[0.0, 0.0, 0.3])  # fingers end about 0.3 + 0.005 m: clear of the wall
    hits = make_pose(translation=[0.0, 0.0, 0.53])  # TCP 3 cm behind the wall: the fingers cut through it
    keep = collision_free(np.stack([free, hits]), wall, CollisionFilterConfig())
    assert keep.tolist() == [True, False]


def test_points_between_the_fingers_do_not_count():
    handle = _slab(-0.01, 0.01, -0.015, 0.015, 0.0, n=20)  # a bar between the open fingers at the TCP
    assert collision_free(make_pose()[None], handle, CollisionFilterConfig()).tolist() == [True]


def test_opening_directions():
    grasps = np.stack([make_pose(translation=[1.0, 0.0, 2.0]), make_pose(translation=[0.0, 0.0, 3.0])])
    rev = opening_directions(grasps, "revolute", np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 2.0]))
    # Right-hand rule about -y at the hinge (0, 0, 2): the point at +x moves towards +z.
    assert np.allclose(rev[0], [0, 0, 1])
    pri = opening_directions(grasps, "prismatic", np.array([0.0, 0.0, -1.0]), np.zeros(3))
    assert np.allclose(pri, [[0, 0, -1], [0, 0, -1]])
