"""Real PartNet-Mobility objects (no handle annotation)."""

from __future__ import annotations

import pytest

from centerart.grasps.generate import GenerateGraspsConfig, generate_grasps
from centerart.grasps.labels import load_object_labels


def test_real_microwave_7119_gets_labels(partnet_dir, tmp_path):
    if not (partnet_dir / "7119" / "mobility.urdf").is_file():
        pytest.skip(f"sample 7119 not found in {partnet_dir}")
    objects = tmp_path / "objects"
    objects.mkdir()
    (objects / "7119").symlink_to(partnet_dir / "7119")
    out = tmp_path / "labels"
    summary = generate_grasps(
        GenerateGraspsConfig(objects=objects, out=out, states=3, per_state=8, max_trials=60, workers=1)
    )
    labels = load_object_labels(out, "7119")
    assert len(labels) == 3
    assert sum(lab.count for lab in labels) >= 8, summary
    assert labels[-1].direction == -1  # fully open: the trial closes the door


def test_a_real_door_without_solid_moving_geometry_gets_no_labels_instead_of_a_crash(partnet_dir, tmp_path):
    """PartNet door 8877's moving link is one flat, zero-thickness surface: no edge to pinch, so its states get no
    labels (the evaluation's labels at a test state stopped the whole run with an IndexError from trimesh)."""
    door = partnet_dir.parent / "partnet-mobility-dev" / "8877"
    if not (door / "mobility.urdf").is_file():
        pytest.skip(f"dev object 8877 not found at {door}")
    objects = tmp_path / "objects"
    objects.mkdir()
    (objects / "8877").symlink_to(door)
    out = tmp_path / "labels"
    generate_grasps(GenerateGraspsConfig(objects=objects, out=out, states=2, per_state=4, max_trials=20, workers=1))
    labels = load_object_labels(out, "8877")
    assert len(labels) == 2 and sum(lab.count for lab in labels) == 0
