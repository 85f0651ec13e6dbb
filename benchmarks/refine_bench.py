"""Effect of each refinement on held-out scenes: detection recall / precision and pose errors of the predictor's
objects with refinement off, ICP (published option) and SDF fitting (beyond the paper). Prints JSON.

    PYTHONPATH=src python benchmarks/refine_bench.py --scenes data/scenes_val_kitchen data/scenes_val_single \
        --views 30 --out benchmarks/refine_bench_result.json

Matching and thresholds: training.encoder_metrics (3-D centre within MATCH_DISTANCE_M, recall over objects at least
MIN_VISIBLE_FRACTION visible). Realistic (stereo) depth.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch

from bench_report import emit, run_main
from centerart.inference.predictor import Predictor, PredictorConfig
from centerart.inference.refinement import RefineConfig, SdfRefineConfig
from centerart.scenes.dataset import load_view
from centerart.training import encoder_metrics as em
from centerart.training.encoder_data import collect_views

VARIANTS = {
    "none": PredictorConfig(),
    "icp": replace(PredictorConfig(), refine=RefineConfig(icp=True)),
    "sdf": replace(PredictorConfig(), refine_sdf=SdfRefineConfig(enabled=True)),
    "sdf+icp": replace(PredictorConfig(), refine=RefineConfig(icp=True), refine_sdf=SdfRefineConfig(enabled=True)),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=Path, nargs="+", required=True)
    ap.add_argument("--views", type=int, default=30)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS))
    ap.add_argument("--encoder", type=Path, default=None, help="encoder checkpoint (default: the shipped one)")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    views = collect_views(args.scenes)
    views = views[:: max(1, len(views) // args.views)][: args.views]
    predictor = Predictor(args.encoder)
    report = {"views": len(views), "thresholds": {"match_distance_m": em.MATCH_DISTANCE_M,
              "min_visible_fraction": em.MIN_VISIBLE_FRACTION}, "variants": {}}  # fmt: skip
    for name in args.variants:
        predictor.config = replace(VARIANTS[name], collision=PredictorConfig().collision)
        results, seconds = [], []
        for view_dir in views:
            v = load_view(view_dir)
            t0 = time.perf_counter()
            preds = predictor.predict(v.rgb, v.depth_realistic, np.asarray(v.labels["K"]))
            seconds.append(time.perf_counter() - t0)
            results.append(em.view_metrics(preds, v.labels))
        report["variants"][name] = {**em.summarize(results), "seconds_per_image_median": float(np.median(seconds))}
        print(name, json.dumps(report["variants"][name]), flush=True)
    emit(report, args.out)


if __name__ == "__main__":
    run_main(main)
