"""Test-time code fitting for objects the decoder never saw: where the fit starts and how long it runs, measured by
the decoded shape (Chamfer-L1 / F-score@1cm of the 128-cell mesh against the true mesh at the closed and the fully
open state). Prints JSON.

    PYTHONPATH=src python benchmarks/code_fit_ab.py --objects data/test_objects --sdf data/test_sdf \\
        --out benchmarks/results/code_fit/test.json

Variants (decoder frozen, all of an object's SDF samples as observations, ``centerart eval decoder``'s 30k points
per state and 4096 points per step):

- ``zero_200``: from the zero code, 200 steps (``centerart eval decoder``'s fit);
- ``zero_800``: from the zero code, 800 steps;
- ``best_200``: from the training code that best explains the observations (``start_codes_by_fit``), 200 steps;
- ``best3_200``: from each of the 3 best training codes, 200 steps each, the lowest final data loss kept;
- ``best_0``: the best training code itself, not optimised (a retrieval baseline).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from bench_report import emit, run_main
from centerart.assets.articulated_object import ArticulatedObject
from centerart.evaluation.decoder_eval import chamfer_fscore
from centerart.inference.reconstruction import MeshConfig, reconstruct_object
from centerart.models.checkpoint import load_decoder
from centerart.models.code_fitting import CodeFitConfig, Observations, fit_code, interval_loss
from centerart.sdf.samples import load_states

VARIANTS = ("zero_200", "zero_800", "best_200", "best3_200", "best_0")
STATES = {"closed": 0.0, "open": 1.0}


def start_codes_by_fit(decoder, obs: Observations, codes: np.ndarray, points: int = 4096, seed: int = 0) -> np.ndarray:
    """Indices of the training ``codes`` (K, code_dim), best first, by their data loss on a seeded subset of the
    observations (decoder frozen, observations with known joint codes): starts for ``fit_code`` on the decoder's
    learned shapes instead of the prior's mean (measured: no better on average, see the module doc)."""
    device = next(decoder.parameters()).device
    idx = np.random.default_rng(seed).choice(len(obs.points), min(points, len(obs.points)), replace=False)
    pts = torch.as_tensor(obs.points[idx], device=device)
    lo, hi = (torch.as_tensor(a[idx], device=device) for a in (obs.lower, obs.upper))
    joint = torch.as_tensor(obs.joint[idx], device=device)
    losses = []
    with torch.no_grad():
        for code in np.asarray(codes, np.float32):
            z = torch.as_tensor(code, device=device).expand(len(idx), -1)
            losses.append(float(interval_loss(decoder.sdf_only(z, joint, pts), lo, hi, CodeFitConfig.clamp)))
    return np.argsort(losses, kind="stable")


def fit_variant(
    decoder, obs: Observations, ranked: np.ndarray | None, name: str, seed: int, code_weight: float
) -> tuple[np.ndarray, float]:
    """(code, final data loss) of one variant (see the module doc); ``ranked``: the training codes best first
    (``start_codes_by_fit``), needed by the ``best`` variants; ``code_weight``: the decoder's trained code prior."""
    start, steps = name.split("_")
    cfg = CodeFitConfig(steps=int(steps), points_per_step=4096, code_weight=code_weight, seed=seed)
    if start == "zero":
        code, _, loss = fit_code(decoder, obs, cfg)
        return code, loss
    if cfg.steps == 0:
        return ranked[0], float("nan")
    fits = [fit_code(decoder, obs, cfg, start=code) for code in ranked[: 3 if start == "best3" else 1]]
    code, _, loss = min(fits, key=lambda f: f[2])
    return code, loss


def object_rows(loaded, folder: Path, states: list, variants: list[str], train_codes: np.ndarray, seed: int) -> list:
    obj = ArticulatedObject.load(folder)
    obs = Observations.from_states(states)
    # Ranked once per object, shared by every variant that starts from a training code; its time counts in each.
    ranked, rank_seconds = None, 0.0
    if any(not name.startswith("zero") for name in variants):
        t0 = time.perf_counter()
        ranked = train_codes[start_codes_by_fit(loaded.decoder, obs, train_codes, seed=seed)]
        rank_seconds = time.perf_counter() - t0
    rows = []
    for name in variants:
        t0 = time.perf_counter()
        code, loss = fit_variant(loaded.decoder, obs, ranked, name, seed, loaded.code_weight)
        seconds = time.perf_counter() - t0 + (0.0 if name.startswith("zero") else rank_seconds)
        for kind, u in STATES.items():
            recon = reconstruct_object(loaded.decoder, code, u, loaded.bounds, MeshConfig(resolution=128))
            chamfer, fscore = chamfer_fscore(recon.mesh, obj.watertight_mesh(obj.denormalize(u)))
            rows.append({"object_id": obj.object_id, "variant": name, "state": kind, "chamfer_mm": chamfer,
                         "fscore": fscore, "final_data_loss": loss, "fit_seconds": seconds})  # fmt: skip
    return rows


def summarize(rows: list[dict], variants: list[str]) -> dict:
    out = {}
    for name in variants:
        out[name] = {}
        for kind in STATES:
            rs = [r for r in rows if r["variant"] == name and r["state"] == kind]
            cd = [r["chamfer_mm"] for r in rs if np.isfinite(r["chamfer_mm"])]
            out[name][kind] = {
                "chamfer_mm_mean": float(np.mean(cd)) if cd else None,
                "chamfer_mm_median": float(np.median(cd)) if cd else None,
                "fscore": float(np.mean([r["fscore"] for r in rs])),
                "empty_meshes": len(rs) - len(cd),
            }
        out[name]["fit_seconds_mean"] = float(np.mean([r["fit_seconds"] for r in rows if r["variant"] == name]))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", type=Path, required=True, help="held-out object folders")
    ap.add_argument("--sdf", type=Path, required=True, help="their SDF samples (`centerart sdf generate`)")
    ap.add_argument("--checkpoint", type=Path, default=None, help="decoder (default: the shipped one)")
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    variants = args.variants.split(",")
    loaded = load_decoder(args.checkpoint)
    by_object: dict[str, list] = {}
    for s in load_states(args.sdf, 30000, args.seed, progress=False):
        by_object.setdefault(s.object_id, []).append(s)
    train_codes = np.stack([loaded.codes[k] for k in sorted(loaded.codes)])
    rows = [
        r
        for oid, st in sorted(by_object.items())
        for r in object_rows(loaded, args.objects / oid, st, variants, train_codes, args.seed)
    ]
    emit({"checkpoint": str(loaded.path), "objects": str(args.objects), "sdf": str(args.sdf), "variants": variants,
          "summary": summarize(rows, variants), "rows": rows}, args.out)  # fmt: skip


if __name__ == "__main__":
    run_main(main)
