"""Encoder benchmark on held-out scenes: detection precision / recall, pose and joint errors, shape from the
predicted code (Chamfer-L1 against the true mesh), and inference time per image. Prints JSON.

    PYTHONPATH=src python benchmarks/encoder_bench.py --scenes data/scenes_val_kitchen data/scenes_val_single \
        --objects data/obj_heldout --depth realistic --out benchmarks/encoder_bench_result.json

Thresholds: training.encoder_metrics (MATCH_DISTANCE_M, MIN_VISIBLE_FRACTION) and models.encoder.readout
(PEAK_THRESHOLD); printed in the JSON. Timing: torch with ``--threads`` CPU threads, one image at a time,
letterboxing and peak read-out included, first image (warm-up) excluded.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from bench_report import emit, run_main
from centerart.models.checkpoint import load_decoder
from centerart.models.encoder import readout
from centerart.models.encoder.checkpoint import load_encoder
from centerart.models.encoder.detect import detect_objects
from centerart.scenes.dataset import load_view
from centerart.training import encoder_metrics as em
from centerart.training.encoder_data import collect_views


def shape_errors(views_rows, decoder, objects_root: Path, limit: int) -> dict:
    """Chamfer-L1 / F-score of meshes decoded from predicted codes vs the true meshes (object frame)."""
    from centerart.evaluation.metrics import shape_metrics
    from centerart.inference.reconstruction import MeshConfig, reconstruct_object
    from centerart.scenes.description import SceneDescription, load_scene_object

    chamfer, fscore = [], []
    for view_dir, det, label in views_rows[:limit]:
        desc = SceneDescription.load(view_dir.parent.parent / "scene.json", objects_root=objects_root)
        spec = next(o for o in desc.objects if o.name == label["name"])
        truth = load_scene_object(spec).mesh(spec.joint_state)
        rec = reconstruct_object(decoder.decoder, det.shape_code.astype(np.float32), det.joint_code, decoder.bounds,
                                 MeshConfig(resolution=96))  # fmt: skip
        m = shape_metrics(rec.mesh, truth)
        chamfer.append(m.chamfer_l1_mm)
        fscore.append(m.fscore)
    if not chamfer:
        return {}
    return {"objects": len(chamfer), "chamfer_l1_mm_mean": float(np.mean(chamfer)),
            "chamfer_l1_mm_median": float(np.median(chamfer)), "fscore_1cm_mean": float(np.mean(fscore))}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkpoint", type=Path, default=None)
    ap.add_argument("--scenes", type=Path, nargs="+", required=True)
    ap.add_argument("--objects", type=Path, default=None, help="objects root for the shape metric (skip if absent)")
    ap.add_argument("--depth", choices=["realistic", "true"], default="realistic")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--peak-threshold", type=float, default=readout.PEAK_THRESHOLD)
    ap.add_argument("--sweep", type=float, nargs="*", default=[0.3, 0.4, 0.5, 0.6, 0.7],
                    help="also report precision / recall with these peak thresholds")  # fmt: skip
    ap.add_argument("--shape-limit", type=int, default=30)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    loaded = load_encoder(args.checkpoint)
    decoder = load_decoder(None)
    results, times, matched, sweep = [], [], [], {t: [] for t in args.sweep}
    for k, view_dir in enumerate(collect_views(args.scenes)):
        v = load_view(view_dir)
        depth, camera = v.depth(args.depth)[0], v.camera
        t0 = time.perf_counter()
        enc = detect_objects(loaded.encoder, v.rgb, depth, camera, min([args.peak_threshold, *args.sweep]))
        if k > 0:
            times.append(time.perf_counter() - t0)
        for t in args.sweep:
            sweep[t].append(em.view_metrics([d for d in enc.detections if d.score >= t], v.labels))
        enc.detections = [d for d in enc.detections if d.score >= args.peak_threshold]
        res = em.view_metrics(enc.detections, v.labels, decoder.codes)
        results.append(res)
        matched += [(view_dir, enc.detections[r["prediction"]], v.labels["objects"][r["label"]]) for r in res["rows"]]
    report = {
        "checkpoint": str(loaded.path),
        "scenes": [str(s) for s in args.scenes],
        "depth": args.depth,
        "thresholds": {
            "match_distance_m": em.MATCH_DISTANCE_M,
            "min_visible_fraction": em.MIN_VISIBLE_FRACTION,
            "peak_threshold": args.peak_threshold,
        },
        "overall": em.summarize(results),
        "per_category": em.summarize_by_category(results),
        "peak_threshold_sweep": {
            str(t): {k: em.summarize(r)[k] for k in ("precision", "recall")} for t, r in sweep.items()
        },
        "inference_ms_per_image": {
            "median": 1000 * float(np.median(times)),
            "threads": args.threads,
            "image": f"{v.labels['width']}x{v.labels['height']}",
        }
        if times
        else None,
        "train_metrics": loaded.meta.get("metrics"),
    }
    if args.objects is not None:
        report["shape_from_predicted_code"] = shape_errors(matched, decoder, args.objects, args.shape_limit)
    emit(report, args.out)


if __name__ == "__main__":
    run_main(main)
