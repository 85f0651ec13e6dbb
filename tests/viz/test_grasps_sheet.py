"""The grasp label sheet: stored labels drawn as gripper markers on the object."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
from centerart.grasps.generate import GenerateGraspsConfig, generate_grasps
from centerart.viz.grasps_sheet import ShowGraspsConfig, show_grasps

DOOR_U = "microwave_0001"  # with seed 0: a U handle on a side-hinged door (as in tests/grasps/conftest.py)


@pytest.fixture(scope="module")
def objects_dir(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("sheet_objects")
    generate_objects(GenerateObjectsConfig(out=out, category="microwave", count=2, seed=0, workers=1))
    return out


@pytest.mark.slow
def test_show_draws_markers(objects_dir, tmp_path):
    objects = tmp_path / "objects"
    oid = DOOR_U
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
