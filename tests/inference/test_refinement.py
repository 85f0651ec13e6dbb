"""Refinement against observed points pulls a perturbed pose back (ICP and SDF fitting, shipped decoder)."""

import numpy as np
import pytest

from centerart.geometry.rotations import axis_angle_matrix
from centerart.geometry.transforms import apply_transform, make_pose
from centerart.inference.reconstruction import MeshConfig, reconstruct_object
from centerart.inference.refinement import (
    RefineConfig,
    SdfRefineConfig,
    refine_pose_icp,
    refine_sdf,
    visible_surface_points,
)
from centerart.models.checkpoint import load_decoder

# The object's front (+x) faces the camera, its top (+z) is image-up, 2 m away.
TRUE_POSE = make_pose(np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]]), [0.1, 0.05, 2.0])


@pytest.fixture(scope="module")
def scene():
    dec = load_decoder()
    oid = sorted(dec.codes)[0]
    code, joint = dec.codes[oid], 0.4
    mesh = reconstruct_object(dec.decoder, code, joint, dec.bounds, MeshConfig(resolution=64)).mesh
    observed = apply_transform(TRUE_POSE, visible_surface_points(mesh, TRUE_POSE, 3000))
    perturbed = make_pose(axis_angle_matrix(np.array([0.0, 1.0, 0.0]), np.radians(4)) @ TRUE_POSE[:3, :3],
                          TRUE_POSE[:3, 3] + [0.03, -0.02, 0.03])  # fmt: skip
    return dec, code, joint, mesh, observed, perturbed


def _t_err(pose):
    return float(np.linalg.norm(pose[:3, 3] - TRUE_POSE[:3, 3]))


def test_icp_pulls_the_pose_back(scene):
    _, _, _, mesh, observed, perturbed = scene
    pose, info = refine_pose_icp(mesh, perturbed, observed, RefineConfig(icp=True))
    assert info["accepted"] and _t_err(pose) < 0.3 * _t_err(perturbed)


def test_sdf_fit_pulls_the_pose_back_and_keeps_the_code(scene):
    dec, code, joint, _, observed, perturbed = scene
    pose, new_code, new_joint, info = refine_sdf(
        dec.decoder, code, joint, perturbed, observed, SdfRefineConfig(enabled=True)
    )
    assert info["accepted"] and _t_err(pose) < 0.5 * _t_err(perturbed)
    assert np.abs(new_code - code).mean() < 0.05 and abs(new_joint - joint) < 0.15


def test_refusals_keep_the_prediction(scene):
    dec, code, joint, mesh, _, perturbed = scene
    few = np.zeros((10, 3))
    assert refine_pose_icp(mesh, perturbed, few, RefineConfig(icp=True))[0] is perturbed
    assert refine_sdf(dec.decoder, code, joint, perturbed, few, SdfRefineConfig(enabled=True))[0] is perturbed
