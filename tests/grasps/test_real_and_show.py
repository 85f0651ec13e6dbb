"""Real PartNet-Mobility objects (no handle annotation) and the label picture."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from PIL import Image

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


@pytest.mark.slow
def test_show_draws_markers(objects_dir, known_ids, tmp_path):
    from centerart.grasps.show import ShowGraspsConfig, show_grasps

    objects = tmp_path / "objects"
    oid = known_ids["door_u"]
    shutil.copytree(objects_dir / oid, objects / oid)
    labels = tmp_path / "labels"
    generate_grasps(GenerateGraspsConfig(objects=objects, out=labels, states=2, per_state=5, workers=1))
    png = show_grasps(
        ShowGraspsConfig(
            labels=labels, objects=objects, object=oid, out=tmp_path / "g.png", image_width=160, image_height=120
        )
    )
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    green = (img[..., 1] > 150) & (img[..., 0] < 100) & (img[..., 2] < 100)
    assert green.sum() > 20  # the markers are visible
