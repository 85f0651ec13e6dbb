"""SDF stage benchmark: sampling speed, sign agreement and nearest-grasp target time. Prints JSON.

    PYTHONPATH=$PWD/src nice python benchmarks/sdf_bench.py --objects 4 --points 100000 > sdf_bench.json

Measures, per (object, state) on one process: the whole sample file (surface, points, distances, signs, second
sign method, grasp targets) in points/s, the parts separately, the sign agreement, and the KD-tree target time for
100k points against 1,000 labelled grasps. Generated objects are made in a temporary folder (seed 0); real
PartNet-Mobility objects are read from ``--real`` when it exists.
"""

from __future__ import annotations

import argparse
import json
import platform
import tempfile
import time
from pathlib import Path

import numpy as np
import open3d as o3d

from bench_report import run_main
from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.dataset import GenerateObjectsConfig, generate_objects, list_objects
from centerart.geometry.transforms import make_pose, rotation_about_axis
from centerart.sdf.grasp_targets import nearest_grasp_targets
from centerart.sdf.sampling import SamplingConfig, sample_points, signed_distance
from centerart.sdf.signs import raycasting_scene
from centerart.sdf.surface import object_surface
from centerart.utils.seeding import item_rng


def bench_object(folder: Path, points: int, states: int) -> list[dict]:
    obj = ArticulatedObject.load(folder)
    cfg = SamplingConfig()
    rows = []
    for k, u in enumerate(np.linspace(0.0, 1.0, states)):
        q = obj.denormalize(float(u))
        rng = item_rng(0, obj.object_id, k)
        t0 = time.perf_counter()
        surface = object_surface(obj, q)
        mesh, closed = surface.mesh, surface.closed
        t1 = time.perf_counter()
        pts = sample_points(mesh, points, cfg, rng)
        t2 = time.perf_counter()
        res = signed_distance(surface, pts, cfg, rng)
        t3 = time.perf_counter()
        scene = raycasting_scene(mesh)
        t4 = time.perf_counter()
        scene.compute_distance(o3d.core.Tensor(pts))
        t5 = time.perf_counter()
        rows.append(
            {
                "object": obj.object_id,
                "state": k,
                "closed_mesh": closed,
                "triangles": len(mesh.faces),
                "sign_method": res.sign_method,
                "check_method": res.check_method,
                "sign_agreement": round(res.sign_agreement, 5),
                "seconds_total": round(t3 - t0, 3),
                "points_per_s": round(points / (t3 - t0)),
                "seconds_surface": round(t1 - t0, 3),
                "seconds_sampling": round(t2 - t1, 3),
                "seconds_sdf_and_check": round(t3 - t2, 3),
                "distance_only_points_per_s": round(points / (t5 - t4)),
            }
        )
    return rows


def summarize(rows: list[dict]) -> dict:
    if not rows:
        return {}
    agree = {}
    for r in rows:
        agree.setdefault(r["object"], []).append(r["sign_agreement"])
    return {
        "states": len(rows),
        "points_per_s_median": float(np.median([r["points_per_s"] for r in rows])),
        "seconds_per_state_median": float(np.median([r["seconds_total"] for r in rows])),
        "distance_only_points_per_s_median": float(np.median([r["distance_only_points_per_s"] for r in rows])),
        "sign_agreement_min_per_object": {k: min(v) for k, v in agree.items()},
        "sign_agreement_mean": float(np.mean([r["sign_agreement"] for r in rows])),
        "rows": rows,
    }


def bench_targets(points: int, grasps: int) -> dict:
    rng = np.random.default_rng(0)
    poses = np.stack(
        [
            make_pose(rotation_about_axis(rng.normal(size=3), rng.uniform(0, np.pi)), rng.uniform(-0.4, 0.4, 3))
            for _ in range(grasps)
        ]
    )
    pts = rng.uniform(-0.5, 0.5, (points, 3))
    times = []
    for _ in range(3):
        t = time.perf_counter()
        nearest_grasp_targets(pts, poses)
        times.append(time.perf_counter() - t)
    return {"points": points, "grasps": grasps, "seconds_min": round(min(times), 4)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", type=int, default=1, help="generated objects per category")
    ap.add_argument("--states", type=int, default=2)
    ap.add_argument("--points", type=int, default=100_000)
    ap.add_argument(
        "--real", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "partnet-mobility-samples"
    )
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        generate_objects(GenerateObjectsConfig(out=Path(tmp), count=args.objects, seed=0, workers=1))
        gen_rows = [r for f in list_objects(Path(tmp)) for r in bench_object(f, args.points, args.states)]
    real_rows = []
    if args.real.is_dir():
        real_rows = [r for f in list_objects(args.real) for r in bench_object(f, args.points, args.states)]
    out = {
        "benchmark": "sdf",
        "machine": {"platform": platform.platform(), "processor": platform.processor()},
        "points_per_state": args.points,
        "generated": summarize(gen_rows),
        "real_partnet_mobility": summarize(real_rows) if real_rows else "absent",
        "nearest_grasp_targets": bench_targets(args.points, 1000),
    }
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    run_main(main)
