"""Cheap encoder data (issue 29, item 2): scenes at the encoder's 320x240 with the stereo sensor's error model,
against full-size (640x480) stereo depth shrunk the way the encoder's loader shrinks it.

Two parts, one JSON document on stdout:

* ``bands``: on the same kitchen views (same seed, same layouts and camera poses; only the image size differs),
  depth error bands (:func:`centerart.scenes.stereo_model.error_bands`: per true-depth band the median and 90th
  percentile absolute error and the hole share; hole share on and off depth edges and in the left blind band) of
  (i) ``reference``: 640x480 stereo (IR pair + SGBM) letterboxed to 320x240 with ``Letterbox.fit`` + ``warp`` as
  ``EncoderViewDataset`` does (nearest for depth), compared with the 640x480 true depth warped the same way;
  (ii) ``stereo-model`` at 320x240 (the cheap path); (iii) ``stereo`` matched at 320x240 directly and (iv)
  ``analytic`` at 320x240 with its defaults, for the record. The model was fitted on seed 0; the default seed
  here is 1.
* ``throughput``: ``centerart scenes generate`` (kitchens, 2 views) with the cheap settings at ``--workers 1`` and
  ``2``, and the full-size stereo settings at ``--workers 1``: wall time of the whole run (worker start-up and
  SAPIEN's shader compilation included), steady images per second (the scenes' own seconds, each worker's first
  scene, which compiles the shaders, left out), and CPU seconds per image (this process and its workers).

Usage::

    PYTHONPATH=src python benchmarks/cheap_scenes.py --objects /work/data/dev/objects > cheap_scenes.json
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

from bench_report import run_main

CHEAP = {"intrinsics": "d415-half", "depth": "stereo-model", "save_ir": False, "save_masks": False,
         "save_textures": False}  # fmt: skip
FULL = {"intrinsics": "d415", "depth": "stereo", "save_ir": False}
BLIND_PX = 42  # the reference's blind band at 320 px (40 columns, registration moves it 1-2 more)


def render_pair(renderer, scene, view: int, seed: int, index: int, depth: str) -> tuple:
    """(true depth, realistic depth, {rgb, instances}) of one view, rendered and sensed as ``scenes generate`` does."""
    from centerart.scenes.depth_noise import analytic_depth, stereo_depth, stereo_occlusion, to_ir_uint8
    from centerart.scenes.stereo_model import modelled_stereo_depth
    from centerart.utils.seeding import item_rng

    im = renderer.render(view, ir=depth == "stereo")
    rng, st, K = item_rng(seed, "scene", index, "view", view, "sensor"), scene.stereo, renderer.K
    if depth == "stereo":
        left, right = to_ir_uint8(im.ir_left, rng), to_ir_uint8(im.ir_right, rng)
        occluded = stereo_occlusion(im.ir_left_depth, im.ir_right_depth, K, st.baseline_m)
        real = stereo_depth(left, right, K, st.baseline_m, st.left_offset_m, occluded=occluded)
    elif depth == "stereo-model":
        real = modelled_stereo_depth(im.depth, K, rng, st.left_offset_m, st.baseline_m, st.projector_offset_m)
    else:
        real = analytic_depth(im.depth, K, rng, baseline=st.baseline_m)
    return im.depth, real, {"rgb": im.rgb, "instances": im.instances}


def compare_bands(objects: Path, scenes: int, seed: int) -> dict:
    from centerart.models.encoder.inputs import Letterbox
    from centerart.scenes.dataset import GenerateScenesConfig, asset_index, sample_checked_scene
    from centerart.scenes.renderer import SceneRenderer
    from centerart.scenes.stereo_model import error_bands

    entries = asset_index(objects)
    renderer = SceneRenderer()
    box = Letterbox.fit(640, 480, 320, 240)
    views: dict[str, list] = {"reference": [], "stereo-model": [], "stereo": [], "analytic": []}
    for i in range(scenes):
        for intrinsics in ("d415", "d415-half"):
            cfg = GenerateScenesConfig(objects, Path("."), layout="kitchen", seed=seed, intrinsics=intrinsics)
            scene, _, _ = sample_checked_scene(cfg, i, entries)
            renderer.build(scene, None)
            for v in range(len(scene.cameras)):
                if intrinsics == "d415":
                    true, real, im = render_pair(renderer, scene, v, seed, i, "stereo")
                    views["reference"].append((box.warp(im["rgb"], true)[1], box.warp(im["rgb"], real)[1]))
                    continue
                for kind in ("stereo-model", "stereo", "analytic"):
                    true, real, _ = render_pair(renderer, scene, v, seed, i, kind)
                    views[kind].append((true, real))
    out = {kind: error_bands(pairs, BLIND_PX) for kind, pairs in views.items()}
    out["views"] = len(views["reference"])
    return out


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def throughput(objects: Path, count: int, workers: int, settings: dict, seed: int) -> dict:
    """One ``generate_scenes`` run into a fresh folder; see the module docstring for the figures."""
    from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes

    with tempfile.TemporaryDirectory() as tmp:
        if workers == 1:  # in this process: compile the shaders first, as a long-lived worker has
            generate_scenes(GenerateScenesConfig(objects, Path(tmp) / "warm", count=1, seed=seed + 99, workers=1,
                                                 **settings))  # fmt: skip
        cfg = GenerateScenesConfig(objects, Path(tmp) / "run", count=count, seed=seed, workers=workers, **settings)
        c0, k0, w0 = time.process_time(), _children_cpu(), time.perf_counter()
        manifest = generate_scenes(cfg)
        cpu = time.process_time() - c0 + _children_cpu() - k0
        wall = time.perf_counter() - w0
    rows = sorted(manifest["scenes"], key=lambda r: r["seconds"])
    images = sum(len(r["views"]) for r in rows)
    steady = rows[: len(rows) - (workers if workers > 1 else 0)]  # each spawned worker's first scene compiles
    steady_images = sum(len(r["views"]) for r in steady)
    return {
        "workers": workers, "scenes": count, "images": images, "wall_s": round(wall, 1),
        "images_per_s_whole_run": round(images / wall, 2),
        "images_per_s_steady": round(workers * steady_images / sum(r["seconds"] for r in steady), 2),
        "cpu_s_per_image": round(cpu / images, 3), "images_per_cpu_s": round(images / cpu, 2),
        "load_average_1min_after": round(os.getloadavg()[0], 2),
    }  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--objects", type=Path, required=True)
    parser.add_argument("--scenes", type=int, default=6, help="kitchens (2 views) for the error bands")
    parser.add_argument("--throughput-scenes", type=int, default=16)
    parser.add_argument("--full-scenes", type=int, default=6, help="kitchens for the full-size throughput row")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--skip-bands", action="store_true")
    args = parser.parse_args()
    os.environ.setdefault("LP_NUM_THREADS", "0")  # as in scene workers (scenes.dataset.single_threaded_worker)
    import cv2

    cv2.setNumThreads(1)
    result: dict = {"command": " ".join(["python", *sys.argv]), "objects": str(args.objects), "cores": os.cpu_count()}
    result["throughput"] = {
        "cheap_workers_1": throughput(args.objects, args.throughput_scenes, 1, CHEAP, args.seed),
        "cheap_workers_2": throughput(args.objects, args.throughput_scenes, 2, CHEAP, args.seed),
        "full_size_stereo_workers_1": throughput(args.objects, args.full_scenes, 1, FULL, args.seed),
    }
    if not args.skip_bands:
        result["bands"] = compare_bands(args.objects, args.scenes, args.seed)
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    run_main(main)
