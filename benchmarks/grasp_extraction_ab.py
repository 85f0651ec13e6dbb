"""A/B of the decoder's grasp extraction: physics top-1 / any-of-5 at the closed and the fully open state, for
three extraction settings on the same reconstruction, and that reconstruction's Chamfer-L1 / F-score@1cm against
the true mesh. Prints JSON.

    python benchmarks/grasp_extraction_ab.py --data runs/small --objects-per-category 0:8 \
        --out benchmarks/results/grasp_extraction/ab_shipped.json

Settings (``inference.decoder_grasps.extraction_setting``): ``before`` (the reconstruction's own points within 2
cm of the surface, no clearance check: the extraction before the shell points), ``shell`` (plus 20k points up to 4
cm either side of the surface), ``default`` (plus the open-gripper clearance check), ``critic`` (the default
extraction ranked by the checkpoint's grasp critic, ``models/grasp_critic.py``). ``--data`` is the folder that
holds the checkpoint's training ``objects/`` (a recipe's output folder); the objects are the checkpoint's trained
codes, ``--objects-per-category A:B`` of each category in id order. With ``--fit-codes-from SDF``, the objects are
instead those of ``--objects`` (held-out objects no checkpoint trained on), their codes fitted to their SDF samples
with the decoder frozen, as ``centerart eval decoder`` does for held-out objects:

    python benchmarks/grasp_extraction_ab.py --objects data/test_objects --fit-codes-from data/test_sdf \
        --out benchmarks/results/grasp_extraction/ab_shipped_test_objects.json

Every top-5 grasp is executed with the grasp-label
executor (``grasps/executor.py``); a missing grasp is a failure.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from bench_report import emit, run_main
from centerart.assets.articulated_object import ArticulatedObject
from centerart.evaluation.decoder_eval import chamfer_fscore, execute_grasps, fitted_code
from centerart.inference.decoder_grasps import extract_grasps, extraction_setting
from centerart.inference.reconstruction import MeshConfig, reconstruct_object
from centerart.models.checkpoint import load_decoder

SETTINGS = {name: extraction_setting(name) for name in ("before", "shell", "default")}
SETTINGS["critic"] = SETTINGS["default"]  # ranked by the checkpoint's grasp critic (models/grasp_critic.py)
STATES = {"closed": 0.0, "open": 1.0}


def pick_objects(codes: dict, span: str) -> list[str]:
    a, b = (int(x) for x in span.split(":"))
    per_category: dict[str, list[str]] = {}
    for oid in sorted(codes):
        per_category.setdefault(oid.rsplit("_", 1)[0], []).append(oid)
    return [oid for ids in per_category.values() for oid in ids[a:b]]


def fitted_codes(loaded, sdf: Path, steps: int = 200, seed: int = 0) -> dict[str, np.ndarray]:
    """Object id -> code fitted to all its SDF samples (decoder frozen; ``centerart eval decoder``'s settings)."""
    from centerart.sdf.samples import load_states

    by_object: dict[str, list] = {}
    for s in load_states(sdf, 30000, seed, progress=False):
        by_object.setdefault(s.object_id, []).append(s)
    return {oid: fitted_code(loaded, states, steps, seed) for oid, states in sorted(by_object.items())}


def summarize(rows: list[dict], settings=tuple(SETTINGS)) -> dict:
    """Per setting and state kind: top-1, any of 5, states without a grasp; and the shape (Chamfer-L1 mm mean and
    median over finite values, F-score@1cm) per state kind."""
    out = {"shape": {}}
    for kind in STATES:
        cd = [r["chamfer_mm"] for r in rows if r["state"] == kind and np.isfinite(r["chamfer_mm"])]
        fs = [r["fscore"] for r in rows if r["state"] == kind]
        out["shape"][kind] = {
            "chamfer_mm": float(np.mean(cd)) if cd else None,
            "chamfer_mm_median": float(np.median(cd)) if cd else None,
            "fscore": float(np.mean(fs)) if fs else None,
            "empty_meshes": len(fs) - len(cd),
        }
    for name in settings:
        out[name] = {}
        for kind in STATES:
            rs = [r[name] for r in rows if r["state"] == kind]
            out[name][kind] = {
                "states": len(rs),
                "top1": float(np.mean([bool(r["ok"]) and r["ok"][0] for r in rs])),
                "any5": float(np.mean([any(r["ok"]) for r in rs])),
                "no_grasp": sum(r["count"] == 0 for r in rs),
                "seconds_extraction": float(np.mean([r["seconds"] for r in rs])),
            }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=None, help="folder with the training objects/ (a recipe's --out)")
    ap.add_argument("--objects", type=Path, default=None, help="held-out object folders (with --fit-codes-from)")
    ap.add_argument("--fit-codes-from", type=Path, default=None, help="SDF samples of --objects: fit their codes")
    ap.add_argument("--checkpoint", type=Path, default=None, help="decoder (default: the shipped one)")
    ap.add_argument("--objects-per-category", default="0:8")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--settings", default="before,shell,default", help="comma-separated extraction settings")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    settings = {name: SETTINGS[name] for name in args.settings.split(",")}
    torch.set_num_threads(args.threads)
    loaded = load_decoder(args.checkpoint)
    if "critic" in settings and loaded.critic is None:
        ap.error(f"--settings critic: {loaded.path} has no grasp critic beside it (benchmarks/grasp_critic.py fit)")
    if args.fit_codes_from is not None:
        codes, objects = fitted_codes(loaded, args.fit_codes_from), args.objects
    else:
        codes = {oid: loaded.code(oid) for oid in pick_objects(loaded.codes, args.objects_per_category)}
        objects = args.data / "objects"
    rows = []
    for oid, code in codes.items():
        obj = ArticulatedObject.load(objects / oid)
        for kind, u in STATES.items():
            q = obj.denormalize(u)
            recon = reconstruct_object(loaded.decoder, code, u, loaded.bounds, MeshConfig(resolution=128))
            chamfer, fscore = chamfer_fscore(recon.mesh, obj.watertight_mesh(q))
            row = {"object_id": oid, "state": kind, "chamfer_mm": chamfer, "fscore": fscore}
            for name, cfg in settings.items():
                t0 = time.perf_counter()
                g = extract_grasps(
                    loaded.decoder, code, u, recon, cfg, critic=loaded.critic if name == "critic" else None
                )
                seconds = time.perf_counter() - t0
                row[name] = {"count": len(g), "ok": execute_grasps(obj, q, g.poses, 5), "seconds": seconds}
            rows.append(row)
    report = {"checkpoint": str(loaded.path), "objects": str(objects), "fitted_codes": args.fit_codes_from is not None,
              "summary": summarize(rows, tuple(settings)), "states": rows}  # fmt: skip
    emit(report, args.out)


if __name__ == "__main__":
    run_main(main)
