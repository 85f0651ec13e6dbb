import numpy as np
from scipy.spatial.transform import Rotation

from centerart.geometry.transforms import (
    apply_transform,
    invert_pose,
    make_pose,
    rotation_angle_between,
    transform_about_line,
)


def test_invert_pose_round_trip():
    rng = np.random.default_rng(0)
    poses = np.stack([make_pose(Rotation.random(random_state=i).as_matrix(), rng.normal(size=3)) for i in range(5)])
    np.testing.assert_allclose(invert_pose(poses) @ poses, np.broadcast_to(np.eye(4), poses.shape), atol=1e-12)


def test_composition_convention():
    a_T_b = make_pose(Rotation.from_euler("z", 90, degrees=True).as_matrix(), [1.0, 0, 0])
    p_b = np.array([1.0, 0.0, 0.0])
    # B's x axis is A's y axis, and B's origin is at x=1 in A.
    np.testing.assert_allclose(apply_transform(a_T_b, p_b), [1.0, 1.0, 0.0], atol=1e-12)


def test_transform_about_line_rotates_about_the_line_not_the_origin():
    motion = transform_about_line(origin=[1.0, 0.0, 0.0], direction=[0.0, 0.0, 1.0], angle=np.pi / 2)
    np.testing.assert_allclose(apply_transform(motion, [1.0, 0.0, 5.0]), [1.0, 0.0, 5.0], atol=1e-12)
    np.testing.assert_allclose(apply_transform(motion, [2.0, 0.0, 0.0]), [1.0, 1.0, 0.0], atol=1e-12)
    shift = transform_about_line([0, 0, 0], [0, 2.0, 0], shift=0.3)
    np.testing.assert_allclose(apply_transform(shift, [0, 0, 0]), [0, 0.3, 0], atol=1e-12)


def test_rotation_angle_between():
    r = Rotation.from_euler("x", 0.3).as_matrix()
    assert abs(rotation_angle_between(np.eye(3), r) - 0.3) < 1e-9
