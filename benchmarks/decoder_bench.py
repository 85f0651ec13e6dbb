"""Decoder-stage benchmark; prints JSON.

Measures (CPU, ``--threads`` torch threads):

- ``training``: optimisation steps/s and points/s of the auto-decoder loss (forward + backward + Adam) for the
  ``tiny`` and ``small`` presets at 16384 points per step;
- ``meshing``: per training object of the checkpoint at the given joint codes, coarse-to-fine mesh + grasp extraction
  time against one dense 128^3 evaluation of the same network + marching cubes, network evaluations of each,
  Chamfer-L1 (mm) of both meshes against the true mesh (``ArticulatedObject.watertight_mesh``) and between the
  coarse-to-fine and the dense mesh;
- ``evaluation``: the summary of an ``centerart eval decoder`` report, when ``--eval-report`` is given.

Usage::

    centerart objects generate --category all --count 3 --seed 0 --out /tmp/objects   # the checkpoint's objects
    PYTHONPATH=src nice python benchmarks/decoder_bench.py --objects /tmp/objects --n-objects 3 \
        --eval-report /tmp/eval/report.json > decoder_bench.json
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np
import torch

from bench_report import run_main


def bench_training(threads: int, steps: int = 10, points: int = 16384) -> dict:
    from centerart.models.decoder import SGDFDecoder, preset
    from centerart.models.losses import LossConfig, decoder_loss

    out = {}
    for name in ("tiny", "small"):
        torch.manual_seed(0)
        dec = SGDFDecoder(preset(name))
        codes = torch.nn.Parameter(torch.zeros(8, 32))
        opt = torch.optim.Adam([*dec.parameters(), codes], lr=1e-4)
        idx = torch.arange(points) % 8
        x, j = torch.randn(points, 3) * 0.3, torch.rand(points)
        sdf, gp, gd = torch.randn(points) * 0.05, torch.randn(points, 5, 3) * 0.3, torch.rand(points) * 0.1
        for i in range(steps + 2):
            if i == 2:
                t0 = time.perf_counter()
            o = dec(codes[idx], j, x)
            loss = decoder_loss(LossConfig(), o, x, sdf, gp, gd, codes)["loss"]
            opt.zero_grad()
            loss.backward()
            opt.step()
        dt = (time.perf_counter() - t0) / steps
        out[name] = {
            "parameters": dec.num_parameters(),
            "steps_per_s": 1 / dt,
            "points_per_s": points / dt,
            "points_per_step": points,
        }
    return out


def bench_meshing(checkpoint, objects: Path, n_objects: int, joint_codes: list[float]) -> dict:
    from centerart.assets.articulated_object import ArticulatedObject
    from centerart.evaluation.decoder_eval import chamfer_fscore
    from centerart.inference.decoder_grasps import extract_grasps
    from centerart.inference.reconstruction import MeshConfig, decoder_field, reconstruct, reconstruct_dense
    from centerart.models.checkpoint import load_decoder

    loaded = load_decoder(checkpoint)
    rows = []
    ids = [o for o in sorted(loaded.codes) if (objects / o).is_dir()][:n_objects]
    for oid in ids:
        obj = ArticulatedObject.load(objects / oid)
        code = loaded.codes[oid]
        for u in joint_codes:
            field = decoder_field(loaded.decoder, code, u)
            t0 = time.perf_counter()
            rec = reconstruct(field, loaded.bounds, MeshConfig(resolution=128))
            grasps = extract_grasps(loaded.decoder, code, u, rec)
            t_c2f = time.perf_counter() - t0
            t0 = time.perf_counter()
            dense = reconstruct_dense(field, loaded.bounds, 128)
            t_dense = time.perf_counter() - t0
            true = obj.watertight_mesh(obj.denormalize(u))
            cd_c2f, f_c2f = chamfer_fscore(rec.mesh, true)
            cd_dense, f_dense = chamfer_fscore(dense.mesh, true)
            cd_between, _ = chamfer_fscore(rec.mesh, dense.mesh)
            rows.append(
                {
                    "object": oid,
                    "joint_code": u,
                    "c2f_mesh_and_grasps_s": t_c2f,
                    "dense_128_mesh_s": t_dense,
                    "speedup": t_dense / t_c2f,
                    "c2f_network_points": rec.stats["evaluated_points"],
                    "dense_network_points": dense.stats["evaluated_points"],
                    "chamfer_mm_c2f": cd_c2f,
                    "chamfer_mm_dense": cd_dense,
                    "chamfer_mm_c2f_vs_dense": cd_between,
                    "fscore_c2f": f_c2f,
                    "fscore_dense": f_dense,
                    "grasps": len(grasps),
                }
            )
    keys = [k for k in rows[0] if k not in ("object", "joint_code")] if rows else []
    return {"per_item": rows, "mean": {k: float(np.mean([r[k] for r in rows])) for k in keys}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--checkpoint", type=Path, default=None, help="default: the shipped small checkpoint")
    ap.add_argument("--objects", type=Path, required=True, help="object folders of the checkpoint's objects")
    ap.add_argument("--n-objects", type=int, default=3)
    ap.add_argument("--joint-codes", type=float, nargs="+", default=[0.0, 0.5, 1.0])
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--eval-report", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    result = {
        "machine": {"platform": platform.platform(), "processor": platform.processor(), "torch_threads": args.threads},
        "training": bench_training(args.threads),
        "meshing": bench_meshing(args.checkpoint, args.objects, args.n_objects, args.joint_codes),
    }
    if args.eval_report:
        result["evaluation"] = json.loads(args.eval_report.read_text())["summary"]
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    run_main(main)
