"""Does the held-out shape figure say something about grasp success? It, per test object, beside the closed loop.

For each encoder and its ``centerart eval scenes`` output on the same test scenes, the validation figure
``shape_sdf_mm`` (``centerart.training.shape_validation``: the regressed code's decoded SDF error at the object's
true surface) of every matched object, split by the object's closed-loop outcome (``sr_image``, and that or the
stage analysis's true-pose swap ``sr_image_gt_pose``), with the medians and a Mann-Whitney U test. Prints JSON:

    PYTHONPATH=src:benchmarks python benchmarks/shape_vs_outcome.py --scenes TEST/single --objects TEST/objects \
        --decoder training_runs/encoder-small-102/decoder.pt --pairs ENCODER_A=EVAL_OUT_A ENCODER_B=EVAL_OUT_B
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import torch
from scipy.stats import mannwhitneyu

from bench_report import emit, run_main


def eval_rows(eval_out: Path) -> dict[tuple[str, str], dict]:
    """(scene, object id) -> the learned method's row of a single-object evaluation's records."""
    from centerart.evaluation.paired import learned_rows

    return {(row["scene"], row["object_id"]): row for _, row in learned_rows(eval_out)}


def split(values: list[tuple[float, bool]]) -> dict:
    """Medians of the figure for successes and failures and the test between them."""
    good, bad = [v for v, ok in values if ok], [v for v, ok in values if not ok]
    out = {"successes": len(good), "failures": len(bad)}
    if good and bad:
        out |= {"median_mm_successes": round(float(np.median(good)), 2),
                "median_mm_failures": round(float(np.median(bad)), 2),
                "mann_whitney_p": round(float(mannwhitneyu(good, bad).pvalue), 4)}  # fmt: skip
    return out


def figures(encoder: Path, eval_out: Path, views: list[Path], judge) -> dict:
    """The figure of each object ``encoder`` matches in ``views``, beside its outcome in ``eval_out``. No training
    codes are given: test objects may share ids with the decoder's training objects (both are named by category
    and index) without being them."""
    from centerart.models.encoder.checkpoint import load_encoder
    from centerart.training.encoder_data import EncoderViewDataset
    from centerart.training.slice_training import validation_results

    net = load_encoder(encoder).encoder
    results = validation_results(net, EncoderViewDataset(views, net.config, {}, None), {}, shape_error=judge)
    records, judged = eval_rows(eval_out), []
    for view, res in zip(views, results, strict=True):
        scene = view.parent.parent.name
        judged += [(row["shape_sdf_mm"], records.get((scene, row["object_id"]))) for row in res["rows"]]
    paired = [(mm, row) for mm, row in judged if row is not None]
    true_pose = [(mm, bool(r.get("sr_image") or r.get("sr_image_gt_pose"))) for mm, r in paired]
    return {
        "judged": len(judged), "median_mm": round(float(np.median([mm for mm, _ in judged])), 2),
        "sr_image": split([(mm, bool(r.get("sr_image"))) for mm, r in paired]),
        "sr_image_or_true_pose": split(true_pose),
    }  # fmt: skip


def main() -> None:
    from centerart.models.checkpoint import load_decoder
    from centerart.training.encoder_data import checked_views
    from centerart.training.shape_validation import HeldOutShapeError

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenes", type=Path, required=True, help="a single-object test set (its scene folders)")
    p.add_argument("--objects", type=Path, required=True, help="the test objects' folders")
    p.add_argument("--decoder", type=Path, required=True)
    p.add_argument("--pairs", nargs="+", required=True, help="ENCODER=EVAL_OUT, the evaluation of that encoder")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--out", type=Path)
    args = p.parse_args()
    torch.set_num_threads(args.threads)
    judge = HeldOutShapeError(load_decoder(args.decoder).decoder, args.objects)
    views = checked_views([args.scenes])
    report = {"scenes": str(args.scenes), "decoder": str(args.decoder), "figures": {}}
    for pair in args.pairs:
        encoder, _, eval_out = pair.partition("=")
        report["figures"][pair] = figures(Path(encoder), Path(eval_out), views, judge)
    emit(report, args.out)


if __name__ == "__main__":
    run_main(main)
