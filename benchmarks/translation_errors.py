"""Where an encoder's translation error lies: along the camera ray (the centre's depth) or across it. Prints JSON.

For every visible object (``encoder_metrics.MIN_VISIBLE_FRACTION``) whose box holds a heatmap peak above
``readout.PEAK_THRESHOLD`` ("found in the image"), the detection nearest in 3-D among those peaks is taken and its
origin error e = predicted - true (camera frame, m) is split into the part along the ray to the true origin
(signed: > 0 predicted too far) and the part across it. Objects whose 3-D error exceeds
``encoder_metrics.MATCH_DISTANCE_M`` are found in the image but missed by the recall; the report says how many
of them are missed mostly along the ray. Per category, since the centre's depth behind the seen front differs by
category (a fridge is deep, a microwave shallow).

    PYTHONPATH=src:benchmarks python benchmarks/translation_errors.py --checkpoint ENC.pt --scenes DEV/d_single \
        [--depth realistic] [--threads 2] [--out errors.json]
"""

from __future__ import annotations

import argparse
from collections import defaultdict
from pathlib import Path

import numpy as np
import torch

from bench_report import emit, run_main
from centerart.models.encoder import readout
from centerart.models.encoder.checkpoint import load_encoder
from centerart.models.encoder.detect import detect_objects
from centerart.training import encoder_metrics as em
from centerart.training.encoder_data import collect_views, load_view_for_encoder


def split_error(pred_t: np.ndarray, true_t: np.ndarray) -> tuple[float, float]:
    """(along, across) in m: the signed error along the camera ray through ``true_t`` and the rest's length."""
    ray = true_t / np.linalg.norm(true_t)
    e = pred_t - true_t
    along = float(e @ ray)
    return along, float(np.linalg.norm(e - along * ray))


def view_rows(detections, labels: dict) -> list[dict]:
    """One row per visible object found in the image: category, 3-D error, along / across the ray (m)."""
    rows = []
    for obj in labels["objects"]:
        if obj["visible_fraction"] < em.MIN_VISIBLE_FRACTION:
            continue
        inside = [d for d in detections if em.peak_in_box(d.peak_uv, obj["bbox_xyxy"])]
        true_t = np.asarray(obj["camera_T_object"], float)[:3, 3]
        if not inside:
            rows.append({"category": obj["category"], "found_in_image": False})
            continue
        pred_t = min((d.camera_T_object[:3, 3] for d in inside), key=lambda t: np.linalg.norm(t - true_t))
        along, across = split_error(pred_t, true_t)
        rows.append({"category": obj["category"], "found_in_image": True, "error_m": float(np.hypot(along, across)),
                     "along_m": along, "across_m": across, "range_m": float(np.linalg.norm(true_t))})  # fmt: skip
    return rows


def summarize(rows: list[dict]) -> dict:
    """Counts and medians (cm) of a list of :func:`view_rows` rows."""
    found = [r for r in rows if r["found_in_image"]]
    out = {"visible_objects": len(rows), "found_in_image": len(found)}
    if not found:
        return out
    err, along, across = (np.array([r[k] for r in found]) for k in ("error_m", "along_m", "across_m"))
    far = err > em.MATCH_DISTANCE_M
    out.update({
        "within_match_distance": int((~far).sum()),
        "error_cm_median": round(100 * float(np.median(err)), 2),
        "along_ray_cm_median_abs": round(100 * float(np.median(np.abs(along))), 2),
        "along_ray_cm_median_signed": round(100 * float(np.median(along)), 2),
        "across_ray_cm_median": round(100 * float(np.median(across)), 2),
        "beyond_match_distance": int(far.sum()),
        "beyond_mostly_along_ray": int((far & (np.abs(along) > across)).sum()),
        "beyond_within_if_along_ray_were_exact": int((far & (across <= em.MATCH_DISTANCE_M)).sum()),
    })  # fmt: skip
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkpoint", type=Path, required=True)
    ap.add_argument("--scenes", type=Path, nargs="+", required=True)
    ap.add_argument("--depth", choices=["realistic", "true"], default="realistic")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    encoder = load_encoder(args.checkpoint).encoder
    rows = []
    for view_dir in collect_views(args.scenes):
        v = load_view_for_encoder(view_dir)  # no masks needed: training and validation views have none
        depth, camera = v.depth(args.depth)[0], v.camera
        rows += view_rows(detect_objects(encoder, v.rgb, depth, camera, readout.PEAK_THRESHOLD).detections, v.labels)
    by_category = defaultdict(list)
    for r in rows:
        by_category[r["category"]].append(r)
    emit({
        "checkpoint": str(args.checkpoint), "scenes": [str(s) for s in args.scenes], "depth": args.depth,
        "thresholds": {"match_distance_m": em.MATCH_DISTANCE_M, "min_visible_fraction": em.MIN_VISIBLE_FRACTION,
                       "peak_threshold": readout.PEAK_THRESHOLD},
        "overall": summarize(rows),
        "per_category": {c: summarize(r) for c, r in sorted(by_category.items())},
    }, args.out)  # fmt: skip


if __name__ == "__main__":
    run_main(main)
