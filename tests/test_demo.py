"""The README's main job, end to end at its smallest scale: every stage runs and writes its picture."""

import json

import numpy as np
import pytest
from PIL import Image

from centerart.cli import main


@pytest.mark.slow
def test_demo_writes_every_picture(tmp_path):
    assert main(["demo", "--out", str(tmp_path), "--count", "1", "--workers", "1"]) == 0
    for name in ("objects", "grasps", "reconstruction", "kitchen", "predict/overlay"):
        img = np.asarray(Image.open(tmp_path / f"{name}.png"))
        assert img.ndim == 3 and img.shape[0] > 100 and img[..., :3].std() > 10, name
    comparison = json.loads((tmp_path / "predict" / "comparison.json").read_text())
    assert comparison["objects"] and all("found" in row for row in comparison["objects"])
    assert (tmp_path / "predict" / "scene.glb").is_file() and (tmp_path / "predict" / "predictions.json").is_file()
