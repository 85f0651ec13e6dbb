"""Make the bundled example RGB-D image (src/centerart/examples/kitchen/) that `centerart predict` runs on by default.

Objects are generated with seed 1000 (the shipped models were trained on seed-0 objects only, so none of these was
seen in training); one kitchen is rendered with realistic (stereo) depth at the D415 resolution.

    .venv/bin/python scripts/make_example.py
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes, list_views, load_view

OBJECT_SEED = 1000
SCENE_SEED = 11
DEST = Path(__file__).resolve().parents[1] / "src" / "centerart" / "examples" / "kitchen"


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        generate_objects(
            GenerateObjectsConfig(out=tmp / "objects", category="all", count=1, seed=OBJECT_SEED, workers=1)
        )
        generate_scenes(
            GenerateScenesConfig(
                objects=tmp / "objects", out=tmp / "scenes", layout="kitchen", count=1, views_per_scene=1,
                seed=SCENE_SEED, depth="stereo", workers=1, save_ir=False,
            )
        )  # fmt: skip
        view_dir = list_views(tmp / "scenes")[0]
        view = load_view(view_dir)
        if DEST.exists():
            shutil.rmtree(DEST)
        DEST.mkdir(parents=True)
        shutil.copy(view_dir / "rgb.png", DEST / "rgb.png")
        shutil.copy(view_dir / "depth_realistic.png", DEST / "depth.png")
        labels = view.labels
        intr = {"width": labels["width"], "height": labels["height"], "K": labels["K"], "depth_unit": "millimetre"}
        (DEST / "intrinsics.json").write_text(json.dumps(intr, indent=1))
        truth = {
            "note": f"ground truth of the example (objects seed {OBJECT_SEED}, scene seed {SCENE_SEED}); "
            "OpenCV camera frame, metres, radians",
            "objects": [
                {k: o[k] for k in ("object_id", "category", "camera_T_object", "joint", "visible_fraction")}
                for o in labels["objects"]
            ],
        }
        (DEST / "ground_truth.json").write_text(json.dumps(truth, indent=1))
        assert np.asarray(Image.open(DEST / "depth.png")).dtype == np.uint16
        print(f"wrote {DEST} ({len(truth['objects'])} objects)")


if __name__ == "__main__":
    main()
