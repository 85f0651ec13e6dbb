"""Anchored-grasp ranker (``models/grasp_critic.py`` kind ``anchor_critic``): collect physics outcomes of the
predictor's anchored grasps on scenes of objects that are neither training nor test objects, fit the ranker
(logistic regression over ``ANCHOR_FEATURES``), save it beside the decoder checkpoint. Prints JSON.

    # 1. outcomes: every kept grasp (up to --top-k per object, the cue ranking) of each object that a prediction is
    #    associated with by image, executed in the rebuilt scene (the evaluation's executor); one file per scene
    python benchmarks/anchor_critic.py collect --scenes dev/single dev/kitchen --out anchor_rows --shard 0/2
    # 2. the penalty by cross-validation over objects (top-1 of the ranker against the cue ranking, out of fold),
    #    then the ranker on all rows, beside the checkpoint
    python benchmarks/anchor_critic.py fit --rows anchor_rows --save

The scenes must hold objects no model trained on and no test object: the shipped ranker's come from seeds 7000
and 7500 (training: 0, critic calibration: 8000, test: 9000).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from bench_report import emit, run_main
from centerart.models.grasp_critic import ANCHOR_FEATURES, fit_critic, save_critic

L2_GRID = (0.1, 1.0, 10.0, 100.0)
FOLDS = 5


def collect_scene(scene_dir: Path, predictor, depth_modes) -> list[dict]:
    """One row per (view, depth mode, image-associated object): its kept grasps' features, cue scores, sources
    and physics outcomes."""
    from centerart.evaluation.physics_scene import build_physics_scene
    from centerart.evaluation.scene_eval import view_inputs
    from centerart.evaluation.scene_rows import associate_by_image
    from centerart.evaluation.trials import execute_grasp
    from centerart.scenes.description import SceneDescription, load_scene_object
    from centerart.training.encoder_metrics import MIN_VISIBLE_FRACTION

    scene = SceneDescription.load(scene_dir / "scene.json")
    phys = build_physics_scene(scene, [load_scene_object(s) for s in scene.objects])
    rows = []
    try:
        for v in view_inputs(scene_dir, depth_modes):
            preds = predictor.predict(v.rgb, v.depth, v.K)
            for j, i in associate_by_image(v, preds).items():
                obj, pred = v.labels["objects"][j], preds[i]
                if pred.grasp_features is None or obj["visible_fraction"] < MIN_VISIBLE_FRACTION:
                    continue
                world = v.world_T_camera @ pred.grasp_poses
                ok = [bool(execute_grasp(phys, obj["instance"] - 1, w)["success"]) for w in world]
                rows.append({"scene": scene_dir.name, "view": v.view, "depth": v.depth_mode,
                             "object_id": obj["object_id"], "category": obj["category"], "ok": ok,
                             "scores": pred.grasp_scores.tolist(), "sources": pred.grasp_sources,
                             "features": pred.grasp_features.tolist()})  # fmt: skip
    finally:
        phys.close()
    return rows


def collect(args) -> dict:
    from centerart.inference.grasp_anchoring import AnchoringConfig
    from centerart.inference.predictor import Predictor, PredictorConfig
    from centerart.utils.atomic import atomic_write_json

    cfg = PredictorConfig(top_k_grasps=args.top_k, anchoring=AnchoringConfig(use_ranker=False))
    predictor = Predictor(None, args.checkpoint, config=cfg)
    k, n = (int(x) for x in args.shard.split("/"))
    dirs = sorted(d for folder in args.scenes for d in Path(folder).glob("scene_*") if (d / "scene.json").is_file())
    done = 0
    for d in dirs[k::n]:
        path = args.out / f"{d.parent.parent.name}_{d.parent.name}_{d.name}.json"
        if not path.is_file():
            atomic_write_json(path, collect_scene(d, predictor, tuple(args.depth.split(","))))
            done += 1
    return {"scenes": len(dirs[k::n]), "collected_now": done, "out": str(args.out)}


def load_rows(folder: Path) -> list[dict]:
    rows = [r for p in sorted(Path(folder).glob("*.json")) for r in json.loads(p.read_text())]
    for r in rows:
        r["ok"] = np.asarray(r["ok"], bool)
        r["features"] = np.asarray(r["features"], float).reshape(-1, len(ANCHOR_FEATURES))
        r["scores"] = np.asarray(r["scores"], float)
    return rows


def first_succeeds(row: dict, order) -> bool:
    return bool(len(row["ok"])) and bool(row["ok"][order[0]])


def cross_validate(rows: list[dict], l2: float) -> dict:
    """Out-of-fold (objects in FOLDS groups) top-1 of the ranker, beside the cue ranking's top-1 on the same rows."""
    objects = sorted({r["object_id"] for r in rows})
    fold = {oid: i % FOLDS for i, oid in enumerate(np.random.default_rng(0).permutation(objects))}
    hits, cue_hits, briers = [], [], []
    for f in range(FOLDS):
        train = [r for r in rows if fold[r["object_id"]] != f and len(r["ok"])]
        held = [r for r in rows if fold[r["object_id"]] == f]
        x = np.concatenate([r["features"] for r in train])
        y = np.concatenate([r["ok"] for r in train])
        ranker = fit_critic(x, y, l2=l2, names=ANCHOR_FEATURES)
        for r in held:
            p = ranker.probability(r["features"]) if len(r["ok"]) else np.zeros(0)
            hits.append(first_succeeds(r, np.argsort(-p, kind="stable")))
            cue_hits.append(first_succeeds(r, np.argsort(-r["scores"], kind="stable")))
            briers += ((p - r["ok"]) ** 2).tolist()
    return {"l2": l2, "top1_ranker": float(np.mean(hits)), "top1_cues": float(np.mean(cue_hits)),
            "brier": float(np.mean(briers)), "rows": len(hits)}  # fmt: skip


def fit(args) -> dict:
    """Cross-validate the penalty (lowest out-of-fold Brier score), fit on every row, --save beside the checkpoint."""
    from centerart.models.checkpoint import default_checkpoint

    rows = load_rows(args.rows)
    cv = [cross_validate(rows, l2) for l2 in L2_GRID]
    best = min(cv, key=lambda c: c["brier"])
    executed = [r for r in rows if len(r["ok"])]
    x, y = np.concatenate([r["features"] for r in executed]), np.concatenate([r["ok"] for r in executed])
    info = {"rows": str(args.rows), "objects": len({r["object_id"] for r in rows}), "object_views": len(rows),
            "grasps": len(y), "successes": int(y.sum()), "l2": best["l2"], "cross_validation": cv}  # fmt: skip
    ranker = fit_critic(x, y, l2=best["l2"], info=info, names=ANCHOR_FEATURES)
    checkpoint = Path(args.checkpoint) if args.checkpoint else default_checkpoint()
    saved = str(save_critic(ranker, checkpoint, "anchor_critic")) if args.save else None
    any_ok = float(np.mean([r["ok"].any() for r in rows]))
    return {"cross_validation": cv, "chosen_l2": best["l2"], "any_kept_grasp_succeeds": any_ok,
            "weights": dict(zip(ANCHOR_FEATURES, ranker.weights.round(4).tolist(), strict=True)),
            "bias": ranker.bias, "saved": saved, **{k: info[k] for k in ("objects", "object_views", "grasps",
                                                                            "successes")}}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("command", choices=("collect", "fit"))
    ap.add_argument("--scenes", type=Path, nargs="+", help="scene folders (collect)")
    ap.add_argument("--out", type=Path, help="collect: folder of per-scene outcome files; fit: the report JSON")
    ap.add_argument("--rows", type=Path, help="a collect folder (fit)")
    ap.add_argument("--checkpoint", type=Path, default=None, help="decoder (default: the shipped one)")
    ap.add_argument("--depth", default="realistic,true", help="depth modes (collect)")
    ap.add_argument("--top-k", type=int, default=20, help="kept grasps executed per object (collect)")
    ap.add_argument("--shard", default="0/1", help="collect: K/N takes every N-th scene from the K-th")
    ap.add_argument("--save", action="store_true", help="fit: write the ranker beside the checkpoint")
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    import torch

    torch.set_num_threads(args.threads)
    if args.command == "collect":
        args.out.mkdir(parents=True, exist_ok=True)
        result = collect(args)
    else:
        result = fit(args)
    emit(result, args.out if args.command == "fit" else None)


if __name__ == "__main__":
    run_main(main)
