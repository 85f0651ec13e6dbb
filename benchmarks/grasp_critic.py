"""Grasp critic (``models/grasp_critic.py``): collect physics outcomes of a decoder's grasps, fit the critic on
one object set, measure its ranking and calibration on another. Prints JSON.

    # 1. outcomes: codes fitted to each object's SDF samples (decoder frozen, 200 steps), the default extraction's
    #    top 10 at each state executed with the grasp-label executor; one file per object (resumable)
    python benchmarks/grasp_critic.py collect --objects calib_objects --sdf calib_sdf --states 0,0.5,1 --out calib
    python benchmarks/grasp_critic.py collect --objects test_objects --sdf test_sdf --states 0,1 --out test
    # 2. the penalty by cross-validation over objects, then the critic on all of them, beside the checkpoint
    python benchmarks/grasp_critic.py fit --rows calib --save
    # 3. on other objects: top-1 of the decoder's ranking against the critic's (within the executed 10) and the
    #    calibration of both scores
    python benchmarks/grasp_critic.py evaluate --rows test
    # the predictor's 48-cell lattice (its grasps come from a coarser reconstruction)
    python benchmarks/grasp_critic.py collect --objects test_objects --sdf test_sdf --states 0,1 --resolution 48 \
        --out test48
    # a decoder trained under dropout (a run's): fit its codes under it too (--fit-dropout, recorded per file)

A state's top-1 is the first grasp of a ranking, a failure when the state has no grasp (missing counts).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch

from bench_report import emit, run_main
from centerart.evaluation.metrics import score_calibration
from centerart.models.grasp_critic import GRASP_FEATURES, GraspCritic, fit_critic, load_critic, save_critic

L2_GRID = (0.1, 1.0, 10.0, 100.0)
FOLDS = 5


def collect(args) -> dict:
    """One JSON per object in ``--out``: per state, the chamfer / F-score and each executed grasp's features,
    decoder score and outcome; objects already there are skipped."""
    from centerart.assets.articulated_object import ArticulatedObject
    from centerart.evaluation.decoder_eval import chamfer_fscore, execute_grasps, fitted_code
    from centerart.inference.decoder_grasps import extract_grasps, extraction_setting
    from centerart.inference.reconstruction import MeshConfig, reconstruct_object
    from centerart.models.checkpoint import load_decoder
    from centerart.sdf.samples import load_states
    from centerart.utils.atomic import atomic_write_json

    loaded = load_decoder(args.checkpoint)
    cfg = extraction_setting("default", top_k=args.top_k)
    states = [float(u) for u in args.states.split(",")]
    by_object: dict[str, list] = {}
    for s in load_states(args.sdf, 30000, args.seed, progress=False):
        by_object.setdefault(s.object_id, []).append(s)
    args.out.mkdir(parents=True, exist_ok=True)
    shard, shards = (int(v) for v in args.shard.split("/"))
    for oid in sorted(by_object)[shard::shards]:
        path = args.out / f"{oid}.json"
        if path.is_file():
            continue
        obj = ArticulatedObject.load(args.objects / oid)
        code = fitted_code(loaded, by_object[oid], args.fit_steps, args.seed, dropout=args.fit_dropout)
        rows = []
        for u in states:
            q = obj.denormalize(u)
            recon = reconstruct_object(loaded.decoder, code, u, loaded.bounds, MeshConfig(resolution=args.resolution))
            chamfer, fscore = chamfer_fscore(recon.mesh, obj.watertight_mesh(q))
            g = extract_grasps(loaded.decoder, code, u, recon, cfg)
            ok = execute_grasps(obj, q, g.poses, args.top_k)
            rows.append({"u": u, "chamfer_mm": chamfer, "fscore": fscore, "scores": g.scores.tolist(),
                         "features": g.features.tolist(), "ok": ok})  # fmt: skip
        atomic_write_json(path, {"object_id": oid, "checkpoint": str(loaded.path), "fit_dropout": args.fit_dropout,
                                 "feature_names": GRASP_FEATURES, "states": rows})  # fmt: skip
        print(f"{oid}: top-1 {[r['ok'][:1] for r in rows]}", flush=True)
    return {"objects": len(by_object), "out": str(args.out)}


def load_rows(folder: Path) -> list[dict]:
    """Per (object, state): object_id, u, features (K, F) in ``GRASP_FEATURES`` order (picked by the names the
    file was collected with), scores (K,), ok (K,) bool."""
    rows = []
    for path in sorted(Path(folder).glob("*.json")):
        d = json.loads(path.read_text())
        columns = [d["feature_names"].index(name) for name in GRASP_FEATURES]
        for r in d["states"]:
            f = np.asarray(r["features"], float).reshape(-1, len(d["feature_names"]))[:, columns]
            rows.append({"object_id": d["object_id"], "u": r["u"], "features": f,
                         "scores": np.asarray(r["scores"], float), "ok": np.asarray(r["ok"], bool)})  # fmt: skip
    return rows


def stacked(rows: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    return np.concatenate([r["features"] for r in rows]), np.concatenate([r["ok"] for r in rows])


def first_succeeds(row: dict, rank) -> bool:
    """Whether a state's first grasp under ``rank(row) -> order`` succeeded (no grasp: a failure)."""
    return bool(len(row["ok"])) and bool(row["ok"][rank(row)[0]])


def top1(rows: list[dict], rank) -> dict:
    """Success of each state's first grasp under ``rank`` (:func:`first_succeeds`), overall and by state (u)."""
    hits = [first_succeeds(r, rank) for r in rows]
    by_u = {}
    for u in sorted({r["u"] for r in rows}):
        by_u[str(u)] = float(np.mean([h for h, r in zip(hits, rows, strict=True) if r["u"] == u]))
    return {"all": float(np.mean(hits)), "by_state": by_u}


def by_decoder(r: dict) -> np.ndarray:
    return np.arange(len(r["ok"]))


def by_critic(critic: GraspCritic):
    return lambda r: np.argsort(-critic.probability(r["features"]), kind="stable") if len(r["ok"]) else []


def summarize(rows: list[dict], critic: GraspCritic | None) -> dict:
    """Top-1 and any-of-K per ranking, and the calibration of the decoder's scores and the critic's probabilities
    over every executed grasp."""
    x, y = stacked(rows)
    out = {
        "states": len(rows),
        "objects": len({r["object_id"] for r in rows}),
        "grasps_executed": len(y),
        "success_rate": float(y.mean()),
        "any_executed": float(np.mean([r["ok"].any() for r in rows])),
        "no_grasp": sum(not len(r["ok"]) for r in rows),
        "top1_decoder": top1(rows, by_decoder),
        "calibration_decoder": score_calibration(np.concatenate([r["scores"] for r in rows]), y),
    }
    if critic is not None:
        out["top1_critic"] = top1(rows, by_critic(critic))
        out["calibration_critic"] = score_calibration(critic.probability(x), y)
    return out


def cross_validate(rows: list[dict], l2: float) -> dict:
    """Out-of-fold (objects split into ``FOLDS`` groups) top-1 and calibration of the critic at penalty ``l2``."""
    objects = sorted({r["object_id"] for r in rows})
    fold = {oid: i % FOLDS for i, oid in enumerate(np.random.default_rng(0).permutation(objects))}
    probs, ys, hits = [], [], []
    for k in range(FOLDS):
        train = [r for r in rows if fold[r["object_id"]] != k]
        held = [r for r in rows if fold[r["object_id"]] == k]
        critic = fit_critic(*stacked(train), l2=l2)
        x, y = stacked(held)
        probs.append(critic.probability(x))
        ys.append(y)
        hits += [first_succeeds(r, by_critic(critic)) for r in held]
    cal = score_calibration(np.concatenate(probs), np.concatenate(ys))
    return {"l2": l2, "top1_critic": float(np.mean(hits)), "ece": cal["ece"], "brier": cal["brier"],
            "auroc": cal["auroc"]}  # fmt: skip


def fit(args) -> dict:
    """Cross-validate the penalty, fit on all rows with the best (lowest out-of-fold Brier score: a proper score,
    rewarding ranking and calibration alike; top-1 over a few dozen states moves by single states), and with
    --save write it beside the checkpoint."""
    from centerart.models.checkpoint import default_checkpoint

    rows = load_rows(args.rows)
    cv = [cross_validate(rows, l2) for l2 in L2_GRID]
    best = min(cv, key=lambda c: c["brier"])
    checkpoint = Path(args.checkpoint) if args.checkpoint else default_checkpoint()
    info = {"rows": str(args.rows), "objects": len({r["object_id"] for r in rows}), "states": len(rows),
            "grasps": int(sum(len(r["ok"]) for r in rows)), "l2": best["l2"], "cross_validation": cv}  # fmt: skip
    critic = fit_critic(*stacked(rows), l2=best["l2"], info=info)
    saved = str(save_critic(critic, checkpoint)) if args.save else None
    weights = dict(zip(GRASP_FEATURES, critic.weights.tolist(), strict=True))
    return {"cross_validation": cv, "chosen_l2": best["l2"], "weights": weights, "bias": critic.bias, "saved": saved,
            "in_sample": summarize(rows, critic)}  # fmt: skip


def evaluate(args) -> dict:
    from centerart.models.checkpoint import default_checkpoint

    checkpoint = Path(args.checkpoint) if args.checkpoint else default_checkpoint()
    critic = load_critic(checkpoint)
    return {"checkpoint": str(checkpoint), "rows": str(args.rows), "summary": summarize(load_rows(args.rows), critic)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("command", choices=("collect", "fit", "evaluate"))
    ap.add_argument("--objects", type=Path, help="object folders (collect)")
    ap.add_argument("--sdf", type=Path, help="their SDF samples, to fit the codes (collect)")
    ap.add_argument("--out", type=Path, help="collect: folder of per-object outcome files; else the report JSON")
    ap.add_argument("--rows", type=Path, help="a collect folder (fit, evaluate)")
    ap.add_argument("--checkpoint", type=Path, default=None, help="decoder (default: the shipped one)")
    ap.add_argument("--states", default="0,0.5,1", help="normalized joint codes (collect)")
    ap.add_argument("--top-k", type=int, default=10)
    ap.add_argument("--fit-steps", type=int, default=200)
    ap.add_argument(
        "--fit-dropout", action="store_true", help="collect: fit the codes under the decoder's dropout (CodeFitConfig)"
    )
    ap.add_argument("--resolution", type=int, default=128, help="lattice cells of the reconstruction (predictor: 48)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--save", action="store_true", help="fit: write the critic beside the checkpoint")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument(
        "--shard", default="0/1", help="collect: K/N takes every N-th object from the K-th (one process per core)"
    )
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    if args.command == "collect":
        print(json.dumps(collect(args)))
    else:
        emit((fit if args.command == "fit" else evaluate)(args), args.out)


if __name__ == "__main__":
    run_main(main)
