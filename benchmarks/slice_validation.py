"""A sliced encoder run's validation figures for any encoder files, with the held-out shape figure.

The ledger's validation measured detection, pose and joint, never the regressed shape code on the held-out objects
the validation views show (they have no training code). This re-validates encoder files (e.g. each slice's
``encoder.pt`` from git history) on a run's fixed validation set with ``shape_sdf_mm_*``
(``centerart.training.shape_validation``), so that the figure's ranking of slices can be held against their closed
loop SR. Prints JSON:

    PYTHONPATH=src:benchmarks python benchmarks/slice_validation.py --run training_runs/encoder-small-102 \
        --work WORK --encoders slice1.pt slice5.pt [--fitted-floor] [--threads 1] [--out X.json]
    # WORK: the run's work folder (its objects and val scenes; made again from the plan's seeds when missing)
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torch

from bench_report import emit, run_main


def judged(results: list[dict]) -> dict[tuple, float]:
    """(view, label) -> shape_sdf_mm of every judged matched object."""
    return {(v, row["label"]): row["shape_sdf_mm"] for v, res in enumerate(results) for row in res["rows"]
            if "shape_sdf_mm" in row}  # fmt: skip


def mean_code_errors(views: list[Path], keys: list[tuple], codes: dict, judge) -> dict[tuple, float]:
    """The reference: the decoder's mean training code judged on the same (view, label) objects."""
    import json

    import numpy as np

    mean = np.mean(np.stack(list(codes.values())), axis=0)
    labels = [json.loads((views[v] / "labels.json").read_text())["objects"] for v in range(len(views))]
    return {(v, j): judge(mean, labels[v][j]) for v, j in keys}


def fitted_code_errors(views: list[Path], keys: list[tuple], loaded, objects: Path, judge) -> dict[tuple, float]:
    """The floor: a code fitted to each object's true surface at the view's state (the stage analysis's code
    oracle, ``evaluation.code_oracle``; about 4 s an object), judged on the same objects."""
    import json

    from centerart.assets.articulated_object import ArticulatedObject
    from centerart.evaluation.code_oracle import oracle_code

    out = {}
    for v, j in keys:
        label = json.loads((views[v] / "labels.json").read_text())["objects"][j]
        obj = ArticulatedObject.load(objects / label["object_id"])
        out[(v, j)] = judge(oracle_code(loaded, obj, float(label["joint"]["state"]), seed=j), label)
    return out


def validate_files(run: Path, work: Path, encoders: list[Path], floor: bool = False) -> dict:
    """Each encoder's figures on ``run``'s validation views (the run's decoder and codes), and the shape figure
    over the objects all of them matched."""
    import numpy as np

    from centerart.models.checkpoint import load_shape_codes
    from centerart.models.encoder.checkpoint import load_encoder
    from centerart.recipe.slices import checked_decoder, load_plan, prepare_objects, shape_judge, validation_views
    from centerart.training.encoder_data import EncoderViewDataset
    from centerart.training.encoder_metrics import summarize
    from centerart.training.slice_training import validation_results

    plan = load_plan(run)
    decoder = checked_decoder(plan)
    codes = load_shape_codes(decoder)
    views = validation_views(plan, prepare_objects(plan, work, decoder, 1), work, 1)
    judge = shape_judge(decoder, work / "objects")
    figures, per_object = {}, {}
    for path in encoders:
        t0 = time.perf_counter()
        encoder = load_encoder(path).encoder
        dataset = EncoderViewDataset(views, encoder.config, codes, None)
        results = validation_results(encoder, dataset, codes, shape_error=judge)
        summary = {k: round(float(v), 5) for k, v in summarize(results).items() if isinstance(v, (int, float))}
        figures[str(path)] = {**summary, "seconds": round(time.perf_counter() - t0, 1)}
        per_object[str(path)] = judged(results)
    common = sorted(set.intersection(*(set(p) for p in per_object.values())))
    per_object["mean training code"] = mean_code_errors(views, common, codes, judge)
    if floor:
        from centerart.models.checkpoint import load_decoder

        loaded = load_decoder(decoder)
        per_object["fitted code"] = fitted_code_errors(views, common, loaded, work / "objects", judge)
    return {"figures": figures, "common": {
        "objects": len(common),
        **{name: {"shape_sdf_mm_median": round(float(np.median([p[k] for k in common])), 3),
                  "shape_sdf_mm_mean": round(float(np.mean([p[k] for k in common])), 3)}
           for name, p in per_object.items()},
    }}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", type=Path, required=True)
    parser.add_argument("--work", type=Path, required=True)
    parser.add_argument("--encoders", type=Path, nargs="+", required=True)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--fitted-floor", action="store_true", help="also judge codes fitted to the true surfaces")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    emit({"run": str(args.run), **validate_files(args.run, args.work, args.encoders, args.fitted_floor)}, args.out)


if __name__ == "__main__":
    run_main(main)
