"""Predictor latency per image, stage by stage, grouped by the number of objects found; prints JSON.

    PYTHONPATH=src python benchmarks/predict_bench.py --scenes data/scenes_val_kitchen data/scenes_val_single \
        --views 20 --threads 2 --out benchmarks/predict_bench_result.json

Stages: ``encoder_s`` (letterbox, network, peaks, read-out, masks), ``grasps_s`` (decoder: surface shell at
``grasp_resolution`` + grasp extraction, all objects), ``refine_s`` (ICP, only with --icp), ``filter_s`` (grasp
anchoring in the observed depth, or with --no-anchoring the proposal's collision check), ``total_s`` (all of
these), and ``meshes_s`` (every object's mesh at ``mesh_resolution``, decoded on demand after the prediction).
The first image (warm-up) is excluded.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch

from bench_report import emit, run_main
from centerart.inference.grasp_anchoring import AnchoringConfig
from centerart.inference.predictor import Predictor, PredictorConfig
from centerart.inference.refinement import RefineConfig
from centerart.scenes.dataset import load_view
from centerart.training.encoder_data import collect_views


def group_of(n: int) -> str:
    return {0: "0", 1: "1", 2: "2-3", 3: "2-3"}.get(n, "4+")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=Path, nargs="+", required=True)
    ap.add_argument("--views", type=int, default=20)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--icp", action="store_true")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--runtime", choices=["auto", "torch", "onnxruntime"], default="auto")
    ap.add_argument("--no-batch", action="store_true", help="decode objects one after the other")
    ap.add_argument("--no-anchoring", action="store_true", help="the decoder's grasps alone (collision filter)")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    cfg = replace(
        PredictorConfig(), refine=RefineConfig(icp=args.icp), runtime=args.runtime, batch_objects=not args.no_batch,
        anchoring=AnchoringConfig(enabled=not args.no_anchoring),
    )  # fmt: skip
    predictor = Predictor(device=args.device, config=cfg)
    views = collect_views(args.scenes)
    step = max(1, len(views) // (args.views + 1))
    rows = []
    for k, view_dir in enumerate(views[::step][: args.views + 1]):
        v = load_view(view_dir)
        preds = predictor.predict(v.rgb, v.depth_realistic, np.asarray(v.labels["K"]))
        timing = dict(predictor.timing)
        t0 = time.perf_counter()
        predictor.meshes(preds)
        timing["meshes_s"] = time.perf_counter() - t0
        if k > 0:
            rows.append({"objects": len(preds), **timing})
    groups = {}
    for name in ("1", "2-3", "4+"):
        sel = [r for r in rows if group_of(r["objects"]) == name]
        if sel:
            keys = [k for k in sel[0] if k.endswith("_s")]
            groups[name] = {"images": len(sel), **{k: float(np.median([r[k] for r in sel])) for k in keys}}
    report = {
        "threads": args.threads,
        "device": args.device,
        "image": f"{v.labels['width']}x{v.labels['height']}",
        "config": {
            "grasp_resolution": cfg.grasp_resolution,
            "mesh_resolution": cfg.mesh_resolution,
            "icp": args.icp,
            "decoder_runtime": type(predictor.fast_decoder).__name__,
            "batch_objects": cfg.batch_objects,
            "anchoring": cfg.anchoring.enabled,
        },
        "median_seconds_by_objects_found": groups,
        "per_image": rows,
    }
    emit(report, args.out)


if __name__ == "__main__":
    run_main(main)
