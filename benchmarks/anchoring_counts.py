"""Why a closed-loop evaluation's top grasp is missing: the grasp anchoring's counts on views it lost with no grasp.

``centerart eval scenes`` records an object view whose prediction kept no grasp as ``no_grasp``; it does not record
which of the anchoring's steps (``inference/grasp_anchoring.py``: candidates per source, snapped onto observed
material, material between the pads, clear of the observed points) emptied the pool. This reruns the evaluation's
predictor (its encoder, decoder and grasp setting, from ``OUT/settings.json``; the camera's true gravity, as the
evaluation gives it) on a sample of those views and of the views it opened, and prints per group the median of
each count, how often it is zero, the pose error of the prediction and the pose correction's acceptance. Optionally
only the ``no_grasp`` views that a decoder given the true detection opened (``decoder_closed_loop.py``'s
``rows.jsonl``), i.e. those the encoder's prediction lost. Prints JSON:

    PYTHONPATH=src:benchmarks python benchmarks/anchoring_counts.py --eval OUT --scenes DEV/d_single DEV2/d2_single \
        [--per-group 40] [--against benchmarks/results/decoder_closed_loop/rows.jsonl --against-column shipped]
    # OUT: a `centerart eval scenes` output (records/) of those scene folders, one learned method
"""

from __future__ import annotations

import argparse
import json
import random
from collections import Counter
from pathlib import Path

import numpy as np

from bench_report import emit, run_main

COUNTS = ("candidates_decoder", "candidates_observed", "candidates_handle", "snapped", "material_between_pads",
          "clear", "kept")  # fmt: skip


def view_groups(eval_out: Path, against: Path | None, column: str) -> dict[str, list[tuple]]:
    """Row keys (``decoder_closed_loop.bare_key``: set, scene, view, depth, instance, object id) of the views lost
    with ``no_grasp`` (that ``column`` opened, with ``against``) and of the views opened."""
    from centerart.evaluation.paired import learned_rows
    from decoder_closed_loop import bare_key, column_outcomes, read_jsonl

    opened_there = None
    if against is not None:
        opened_there = {k for k, ok in column_outcomes(read_jsonl(against), column).items() if ok}
    groups: dict[str, list[tuple]] = {"no_grasp": [], "opened": []}
    for set_name, row in learned_rows(eval_out):
        keys = ("scene", "view", "depth", "method", "instance", "object_id")
        k = bare_key((set_name, *(row[c] for c in keys)))
        if row.get("sr_image"):
            groups["opened"].append(k)
        elif row.get("sr_image_abort") == "no_grasp" and (opened_there is None or k in opened_there):
            groups["no_grasp"].append(k)
    return groups


def view_counts(predictor, folder: Path, k: tuple) -> dict | None:
    """The anchoring counts, pose error and pose correction of the prediction associated with object view ``k``
    (a :func:`view_groups` key), in the row's depth mode."""
    from centerart.evaluation.scene_eval import view_inputs
    from centerart.evaluation.scene_rows import associate_by_image
    from centerart.geometry.gravity import gravity_from_world_T_camera
    from centerart.training.encoder_metrics import object_errors

    v = next(x for x in view_inputs(folder / k[1], (k[3],)) if x.view == k[2])  # the row's depth mode
    preds = predictor.predict(v.rgb, v.depth, v.K, gravity=gravity_from_world_T_camera(v.world_T_camera))
    j, obj = next((j, o) for j, o in v.ground_truth() if o["instance"] == k[4] + 1)
    m = associate_by_image(v, preds).get(j)
    if m is None:
        return None
    p, errors = preds[m], object_errors(preds[m], obj)
    correction = p.refinement.get("pose_from_depth", {})
    counts = p.refinement.get("anchoring", {})
    return {"counts": {c: counts.get(c, 0) for c in COUNTS}, "translation_cm": errors["translation_cm"],
            "rotation_deg": errors["rotation_deg"], "pose_correction_accepted": correction.get("accepted"),
            "rejected": Counter(p.rejected_reasons)}  # fmt: skip


def summarise(views: list[dict]) -> dict:
    """Per count its median and zero share; the median pose errors; corrections accepted; rejections by reason."""
    out: dict = {"views": len(views)}
    for c in COUNTS:
        v = np.array([x["counts"][c] for x in views])
        out[c] = {"median": float(np.median(v)), "zero_share": round(float(np.mean(v == 0)), 3)}
    for e in ("translation_cm", "rotation_deg"):
        out[f"{e}_median"] = round(float(np.median([x[e] for x in views])), 2)
    out["pose_correction_accepted"] = dict(Counter(str(x["pose_correction_accepted"]) for x in views))
    out["rejected"] = dict(sum((x["rejected"] for x in views), Counter()))
    return out


def main() -> None:
    from centerart.errors import CenterArtError
    from centerart.evaluation.scene_eval import predictor_for

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--eval", type=Path, required=True, help="a `centerart eval scenes` output")
    p.add_argument("--scenes", type=Path, nargs="+", required=True, help="its scene folders")
    p.add_argument("--per-group", type=int, default=40, help="views sampled per group (seeded)")
    p.add_argument("--against", type=Path, default=None, help="a decoder_closed_loop.py rows.jsonl of those views")
    p.add_argument("--against-column", default="shipped")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path, default=None)
    args = p.parse_args()
    settings_file = args.eval / "settings.json"
    if not settings_file.is_file():
        raise CenterArtError(f"--eval: {args.eval}: no settings.json (expected a `centerart eval scenes` output)")
    settings = json.loads(settings_file.read_text())
    folders = {f.name: f for f in args.scenes}
    cfg = {k: settings[k] for k in ("encoder", "decoder", "shape_prior")}
    predictor = predictor_for(cfg, settings["refine"][0], settings["grasps"][0])
    rng, report = random.Random(args.seed), {"eval": str(args.eval), "settings": cfg, "groups": {}}
    for name, keys in view_groups(args.eval, args.against, args.against_column).items():
        missing = sorted({k[0] for k in keys} - set(folders))
        if missing:
            raise CenterArtError(f"--scenes: no folder named {missing[0]} (the evaluation's set)")
        sample = rng.sample(keys, min(args.per_group, len(keys)))
        views = [c for k in sample if (c := view_counts(predictor, folders[k[0]], k)) is not None]
        report["groups"][name] = {"of": len(keys), **summarise(views)}
    emit(report, args.out)


if __name__ == "__main__":
    run_main(main)
