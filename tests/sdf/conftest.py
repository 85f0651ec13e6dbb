"""Shared fixtures: a few generated objects and synthetic grasp labels on their moving parts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
from centerart.geometry.transforms import make_pose
from centerart.grasps.labels import StateLabels


def front_face_grasps(obj: ArticulatedObject, q: float, count: int, rng: np.random.Generator) -> np.ndarray:
    """TCP poses (count, 4, 4) on the moving part's front face at state q (canonical frame): approach along -x
    along -x (into the front), fingers closing along z or y, at the part's front-most x."""
    mesh = obj.moving_mesh(q)
    lo, hi = mesh.bounds
    poses = []
    for _ in range(count):
        y, z = rng.uniform(lo[1:], hi[1:])
        approach = np.array([-1.0, 0.0, 0.0])
        closing = np.array([0.0, 0.0, 1.0]) if rng.random() < 0.5 else np.array([0.0, 1.0, 0.0])
        x_axis = np.cross(closing, approach)
        rot = np.stack([x_axis, closing, approach], axis=1)
        poses.append(make_pose(rot, [hi[0], y, z]))
    return np.array(poses)


def write_labels(obj: ArticulatedObject, folder: Path, qs_normalized, count: int, seed: int = 0) -> list[StateLabels]:
    rng = np.random.default_rng(seed)
    out = []
    for k, u in enumerate(qs_normalized):
        q = obj.denormalize(u)
        poses = front_face_grasps(obj, q, count, rng)
        lab = StateLabels(
            object_id=obj.object_id,
            state_index=k,
            q=q,
            q_normalized=u,
            joint_type=obj.joint_type,
            direction=1,
            poses=poses,
            displacement=np.full(count, 0.2),
            failed_poses=np.zeros((0, 4, 4)),
            failed_displacement=np.zeros(0),
        )
        lab.save(folder)
        out.append(lab)
    return out


@pytest.fixture(scope="session")
def generated_objects(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("objects")
    for category in ("microwave", "storage_furniture"):
        generate_objects(GenerateObjectsConfig(out=out, category=category, count=1, seed=3, workers=1))
    return out


@pytest.fixture(scope="session")
def label_writer():
    """``write_labels(obj, folder, qs_normalized, count, seed=0)``: synthetic label files on the front face."""
    return write_labels
