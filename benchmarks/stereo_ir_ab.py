"""Stereo depth quality with the IR pair lit by SAPIEN (``--ir-shading full``) against shaded from geometry
(``fast``): the same kitchen views rendered both ways, matched by the same SGBM; valid share per image and absolute
error by true depth (pixels right of the matcher's 80-px blind band), and CPU seconds per view (render, IR, match).

Usage::

    PYTHONPATH=src python benchmarks/stereo_ir_ab.py --objects data/objects --scenes 4 > ir_ab.json

Prints one JSON document.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench_report import run_main

BANDS_M = ((0.5, 1.5), (1.5, 2.5), (2.5, 3.5), (3.5, 5.0))
BLIND_BAND_PX = 80


def stereo_view(renderer, scene, view: int, seed_key: tuple) -> tuple[np.ndarray, np.ndarray]:
    """(true depth, stereo depth) of one view, the sensor noise seeded by ``seed_key``."""
    from centerart.scenes.depth_noise import stereo_depth, stereo_occlusion, to_ir_uint8
    from centerart.utils.seeding import item_rng

    im = renderer.render(view, ir=True)
    rng, st = item_rng(*seed_key), scene.stereo
    left, right = to_ir_uint8(im.ir_left, rng), to_ir_uint8(im.ir_right, rng)
    occluded = stereo_occlusion(im.ir_left_depth, im.ir_right_depth, renderer.K, st.baseline_m)
    return im.depth, stereo_depth(left, right, renderer.K, st.baseline_m, st.left_offset_m, occluded=occluded)


def summarize(valid: list, errors: dict, cpu_s: float, views: int) -> dict:
    out = {"views": views, "cpu_s_per_view": round(cpu_s / views, 3)}
    out["valid_median"] = round(float(np.median(valid)), 4)
    out["valid_p10"] = round(float(np.percentile(valid, 10)), 4)
    for (lo, hi), errs in errors.items():
        e = np.concatenate(errs) if errs else np.zeros(0)
        if len(e):
            out[f"abs_error_mm_{lo}-{hi}m"] = {
                "median": round(1000 * float(np.median(e)), 1),
                "p90": round(1000 * float(np.percentile(e, 90)), 1),
                "pixels": len(e),
            }
    return out


def main() -> None:
    from centerart.scenes.dataset import GenerateScenesConfig, asset_index, sample_checked_scene, write_textures
    from centerart.scenes.renderer import SceneRenderer

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--objects", type=Path, required=True)
    parser.add_argument("--scenes", type=int, default=4)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    entries = asset_index(args.objects)
    cfg = GenerateScenesConfig(objects=args.objects, out=Path("."), layout="kitchen", views_per_scene=2, seed=args.seed)
    renderers = {mode: SceneRenderer(ir_shading=mode) for mode in ("full", "fast")}
    acc = {m: {"valid": [], "errors": {b: [] for b in BANDS_M}, "cpu": 0.0, "views": 0} for m in renderers}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.scenes + 1):  # scene 0 warms up (shader compilation)
            scene, _, _ = sample_checked_scene(cfg, i, entries)
            folder = Path(tmp) / f"s{i}"
            folder.mkdir()
            write_textures(scene, folder)
            for mode, renderer in renderers.items():
                renderer.build(scene, folder)
                for v in range(len(scene.cameras)):
                    c0 = time.process_time()
                    true, real = stereo_view(renderer, scene, v, (args.seed, "scene", i, "view", v, "sensor"))
                    if i == 0:
                        continue
                    a = acc[mode]
                    a["cpu"] += time.process_time() - c0
                    a["views"] += 1
                    t, r = true[:, BLIND_BAND_PX:], real[:, BLIND_BAND_PX:]
                    ok = r > 0
                    a["valid"].append(float(ok[t > 0].mean()))
                    for lo, hi in BANDS_M:
                        sel = ok & (t >= lo) & (t < hi)
                        a["errors"][(lo, hi)].append(np.abs(r[sel] - t[sel]))
    result = {"command": " ".join(["python", *sys.argv]), "objects": str(args.objects)}
    result |= {mode: summarize(a["valid"], a["errors"], a["cpu"], a["views"]) for mode, a in acc.items()}
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    run_main(main)
