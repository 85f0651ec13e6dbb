"""Scene rendering throughput at 640x480: images per second per core for RGB + true depth + realistic depth +
segmentation + labels (PNG writing included), with the rasteriser and with SAPIEN's ray tracer (RGB only is
path-traced; depth, masks and the IR pair stay rasterised).

Per core = per CPU-second of this process (``time.process_time``, all threads: Mesa lavapipe and OpenCV use
several), so the figure does not depend on how many cores the machine lends it. Shader compilation (first picture
of a process) is measured separately and excluded from the throughput.

Usage::

    PYTHONPATH=src python benchmarks/scenes_bench.py --objects /tmp/objects --scenes 4 --views 2
    PYTHONPATH=src python benchmarks/scenes_bench.py --objects /tmp/objects --shader rt --scenes 1 --views 1

Without ``--shader`` both variants run (the ray-tracing one in a child process, because SAPIEN's shader choice is
process-wide). Prints one JSON document.

``--whole-step`` measures what a scenes-step worker does per scene instead (``scenes.dataset._generate_one``: layout
and collision check, textures, build, render, PNGs, labels, atomic write), stereo depth without IR PNGs (the
recipe's setting), kitchens (2 views) and single-object scenes (1 view), with Mesa's threads off as in parallel
workers::

    PYTHONPATH=src python benchmarks/scenes_bench.py --objects /tmp/objects --whole-step --scenes 8

``--render-only`` measures the render definition above (build + render + PNGs + labels, layouts and textures
excluded) with the recipe's settings and a worker's thread settings (stereo, fast IR shading, no IR PNGs, Mesa and
OpenCV single-threaded), the definition the issue's goal of 2 images per CPU-second was set in::

    PYTHONPATH=src python benchmarks/scenes_bench.py --objects /tmp/objects --render-only --scenes 6
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench_report import run_main


def measure(
    objects: Path,
    shader: str,
    depth: str,
    scenes: int,
    views: int,
    spp: int,
    seed: int,
    ir_shading: str = "fast",
    save_ir: bool = True,
) -> dict:
    from centerart.scenes.dataset import (
        GenerateScenesConfig,
        asset_index,
        render_scene_views,
        sample_checked_scene,
        write_textures,
    )
    from centerart.scenes.renderer import SceneRenderer

    entries = asset_index(objects)
    cfg = GenerateScenesConfig(
        objects=objects,
        out=Path("."),
        layout="kitchen",
        views_per_scene=views,
        seed=seed,
        depth=depth,
        intrinsics="d415",
        shader=shader,
        rt_samples_per_pixel=spp,
        ir_shading=ir_shading,
    )
    renderer = SceneRenderer(shader, spp, ir_shading)
    t_layout, cpu_build, cpu_render, wall_build, wall_render, n_images = 0.0, 0.0, 0.0, 0.0, 0.0, 0
    compile_s = None
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(scenes + 1):  # scene 0 warms up (shader compilation)
            t0 = time.perf_counter()
            scene, objs, _ = sample_checked_scene(cfg, i, entries)
            t_layout += time.perf_counter() - t0 if i > 0 else 0.0
            scene_dir = Path(tmp) / f"s{i}"
            scene_dir.mkdir()
            write_textures(scene, scene_dir)
            c0, w0 = time.process_time(), time.perf_counter()
            renderer.build(scene, scene_dir)
            c1, w1 = time.process_time(), time.perf_counter()
            render_scene_views(renderer, scene, objs, scene_dir, depth, seed, i, save_ir=save_ir)
            c2, w2 = time.process_time(), time.perf_counter()
            if i == 0:
                compile_s = w2 - w0
                continue
            cpu_build += c1 - c0
            wall_build += w1 - w0
            cpu_render += c2 - c1
            wall_render += w2 - w1
            n_images += views
    return {
        "shader": shader,
        "rt_samples_per_pixel": spp if shader == "rt" else None,
        "depth": depth,
        "ir_shading": ir_shading if depth == "stereo" else None,
        "ir_pngs_written": save_ir and depth == "stereo",
        "resolution": "640x480",
        "scenes": scenes,
        "views_per_scene": views,
        "images": n_images,
        # Throughput of a dataset run: the scene build (SAPIEN scene, textures, first update) amortised over its views.
        "images_per_cpu_second": round(n_images / (cpu_render + cpu_build), 3),
        "images_per_wall_second": round(n_images / (wall_render + wall_build), 3),
        "cpu_seconds_per_image_render_only": round(cpu_render / n_images, 3),
        "wall_seconds_per_image_render_only": round(wall_render / n_images, 3),
        "cpu_seconds_per_scene_build": round(cpu_build / scenes, 3),
        "wall_seconds_per_scene_build": round(wall_build / scenes, 3),
        "layout_and_collision_check_s_per_scene": round(t_layout / scenes, 3),
        "first_scene_with_shader_compile_s": round(compile_s, 2),
    }


def measure_whole_step(objects: Path, layout: str, scenes: int, seed: int) -> dict:
    """Images per CPU-second of ``_generate_one`` over scenes 1..N; scene 0 first compiles the shaders."""
    from dataclasses import asdict

    from centerart.scenes.dataset import GenerateScenesConfig, _generate_one, asset_index

    os.environ["LP_NUM_THREADS"] = "0"  # as parallel workers set it (scenes.dataset._generate_one)
    entries = asset_index(objects)
    views = 2 if layout == "kitchen" else 1
    with tempfile.TemporaryDirectory() as tmp:
        cfg = GenerateScenesConfig(
            objects=objects, out=Path(tmp), layout=layout, views_per_scene=views, seed=seed, depth="stereo",
            intrinsics="d415", workers=2, save_ir=False,
        )  # fmt: skip
        job = asdict(cfg)
        _generate_one((job, 0, entries))
        c0 = time.process_time()
        for i in range(1, scenes + 1):
            _generate_one((job, i, entries))
        cpu = time.process_time() - c0
    return {"layout": layout, "views_per_scene": views, "images": scenes * views,
            "images_per_cpu_second": round(scenes * views / cpu, 3)}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--objects", type=Path, required=True)
    parser.add_argument("--scenes", type=int, default=4)
    parser.add_argument("--views", type=int, default=2)
    parser.add_argument("--shader", choices=["default", "rt"], default=None)
    parser.add_argument("--rt-spp", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--whole-step", action="store_true", help="time the scenes step's per-scene work instead")
    parser.add_argument("--render-only", action="store_true", help="the render definition, recipe and worker settings")
    args = parser.parse_args()
    if args.render_only:
        from centerart.scenes.dataset import single_threaded_worker

        os.environ["LP_NUM_THREADS"] = "0"  # forced, as for --whole-step, whatever the shell set
        single_threaded_worker()  # the rest of a parallel worker's settings (scenes.dataset._generate_one)
        print(
            json.dumps(measure(args.objects, "default", "stereo", args.scenes, args.views, 1, args.seed, "fast", False))
        )
        return
    if args.whole_step:
        print(
            json.dumps([measure_whole_step(args.objects, lay, args.scenes, args.seed) for lay in ("kitchen", "single")])
        )
        return
    if args.shader is not None:
        variants = [("stereo", "fast")]
        if args.shader == "default":
            variants += [("stereo", "full"), ("analytic", "fast"), ("true", "fast")]
        results = [
            measure(args.objects, args.shader, d, args.scenes, args.views, args.rt_spp, args.seed, ir)
            for d, ir in variants
        ]
        print(json.dumps(results))
        return
    out = {
        "machine": {"cpus_visible": len(os.sched_getaffinity(0)), "python": sys.version.split()[0]},
        "command": " ".join(sys.argv),
        "results": [],
    }
    for shader, scenes, views in (("default", args.scenes, args.views), ("rt", 1, 2)):
        cmd = [
            sys.executable,
            __file__,
            "--objects",
            str(args.objects),
            "--shader",
            shader,
            "--scenes",
            str(scenes),
            "--views",
            str(views),
            "--rt-spp",
            str(args.rt_spp),
            "--seed",
            str(args.seed),
        ]
        res = subprocess.run(cmd, capture_output=True, text=True, check=True)
        out["results"].extend(json.loads(res.stdout.strip().splitlines()[-1]))
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    run_main(main)
