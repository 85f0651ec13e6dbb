import numpy as np
from scipy.spatial.transform import Rotation

from centerart.geometry.rotations import (
    axis_angle_matrix,
    matrix_from_quat,
    project_to_so3,
    quat_from_matrix,
    quat_multiply,
)


def test_quaternion_round_trip_matches_scipy():
    for rot in Rotation.random(200, random_state=0):
        m = rot.as_matrix()
        q = np.array(quat_from_matrix(m))
        ref = rot.as_quat()
        assert np.allclose(q, ref) or np.allclose(q, -ref)
        assert np.allclose(matrix_from_quat(q), m)


def test_quat_multiply_composes_rotations():
    a, b = Rotation.random(2, random_state=1)
    prod = quat_multiply(a.as_quat(), b.as_quat())
    assert np.allclose(matrix_from_quat(prod), (a * b).as_matrix())


def test_axis_angle_matches_scipy():
    axis = np.array([1.0, 2.0, -0.5])
    axis /= np.linalg.norm(axis)
    assert np.allclose(axis_angle_matrix(axis, 0.7), Rotation.from_rotvec(axis * 0.7).as_matrix())


def test_project_to_so3_fixes_noise_and_reflection():
    m = Rotation.from_euler("xyz", [0.3, -0.2, 1.0]).as_matrix()
    assert np.allclose(project_to_so3(m + 1e-3 * np.random.default_rng(0).normal(size=(3, 3))), m, atol=3e-3)
    r = project_to_so3(-m)
    assert np.isclose(np.linalg.det(r), 1.0)
