"""Grasp-label benchmark: physics speed, label rate, yield and orientation diversity per category. Prints JSON.

    PYTHONPATH=src python benchmarks/grasps_bench.py --objects-per-category 3 --states 10 --per-state 100 \
        --workers 2 --work /tmp/grasps_bench

1. ``executor``: trials per second on one core, executing a fixed list of pre-filtered candidates (pure physics
   trial cost, one process, no candidate search), per CPU second (``time.process_time``) and per wall second.
2. ``generation``: ``centerart grasps generate`` on ``objects-per-category`` generated objects per category (seed
   0) x ``states`` states, capped at ``per-state`` labels per (object, state); per category: yield (successes /
   executed trials), (object, state) items reaching 100 labels, successful labels per item per CPU minute
   (one core, so the figure does not depend on other load on the machine), trials per second of simulation
   time, and the approach-direction spread (mean angle to the mean
   approach of a state, degrees). Items already in ``--work`` are reused (the run is resumable); their
   timings are those of the run that made them.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from bench_report import run_main
from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
from centerart.grasps import executor as ex
from centerart.grasps.candidates import CandidateSampler
from centerart.grasps.generate import GenerateGraspsConfig, generate_grasps
from centerart.grasps.sim_world import connect, spawn_object_in_pybullet
from centerart.utils.manifest import code_version


def bench_executor(objects: list[Path], trials_per_object: int = 150) -> dict:
    import pybullet as pb

    from centerart.geometry.transforms import make_pose

    back = make_pose(translation=[0.0, 0.0, -ex.APPROACH_DISTANCE])
    done = 0
    seconds = cpu = 0.0
    successes = 0
    for folder in objects:
        obj = ArticulatedObject.load(folder)
        q = obj.denormalize(0.4)
        client = connect()
        target = spawn_object_in_pybullet(client, obj, q)
        executor = ex.GraspExecutor(client)
        sampler = CandidateSampler(obj, q, np.random.default_rng(0))
        poses, _ = sampler.sample(4 * trials_per_object)
        keep = [p for p in poses if not executor.hand_collides(p, tol=0.0005) and not executor.hand_collides(p @ back)]
        keep = keep[:trials_per_object]
        t0, c0 = time.perf_counter(), time.process_time()
        for p in keep:
            successes += executor.execute(p, target).success
        seconds += time.perf_counter() - t0
        cpu += time.process_time() - c0
        done += len(keep)
        pb.disconnect(client)
    return {
        "trials": done,
        "wall_seconds": round(seconds, 3),
        "cpu_seconds": round(cpu, 3),
        "trials_per_second_per_core": round(done / cpu, 1),
        "trials_per_wall_second_one_process": round(done / seconds, 1),
        "cpu_ms_per_trial": round(1000 * cpu / done, 2),
        "success_fraction": round(successes / done, 3),
    }


def bench_generation(objects_dir: Path, out: Path, states: int, per_state: int, workers: int) -> dict:
    t0 = time.perf_counter()
    generate_grasps(
        GenerateGraspsConfig(objects=objects_dir, out=out, states=states, per_state=per_state, workers=workers)
    )
    wall = time.perf_counter() - t0
    rows = json.loads((out / "manifest.json").read_text())["items"]
    per_cat = {}
    for cat in sorted({r["category"] for r in rows}):
        rs = [r for r in rows if r["category"] == cat]
        trials = sum(r["trials"] for r in rs)
        succ = sum(r["successes"] for r in rs)
        rate = [r["successes"] / (r["cpu_seconds"] / 60.0) for r in rs]
        short = [
            f"{r['object_id']}#{r['state_index']} (q={r['q']:.2f}, {r['successes']})"
            for r in rs
            if r["successes"] < 100
        ]
        per_cat[cat] = {
            "objects": len({r["object_id"] for r in rs}),
            "items": len(rs),
            "items_with_100_labels": sum(r["successes"] >= 100 for r in rs),
            "fraction_items_with_100_labels": round(sum(r["successes"] >= 100 for r in rs) / len(rs), 3),
            "items_below_100": short,
            "labels": succ,
            "trials": trials,
            "yield": round(succ / max(trials, 1), 4),
            "prefiltered": sum(r["outcomes"].get("prefiltered", 0) for r in rs),
            "labels_per_item_per_cpu_minute_median": round(float(np.median(rate)), 1),
            "item_cpu_seconds_mean": round(float(np.mean([r["cpu_seconds"] for r in rs])), 2),
            "trials_per_sim_second": round(trials / max(sum(r["sim_seconds"] for r in rs), 1e-9), 1),
            "item_seconds_mean": round(float(np.mean([r["seconds"] for r in rs])), 2),
            "approach_spread_deg_mean": round(float(np.mean([r["approach_spread_deg"] for r in rs])), 1),
            "successes_by_source": {
                k: sum(r["successes_by_source"].get(k, 0) for r in rs)
                for k in sorted({k for r in rs for k in r["successes_by_source"]})
            },
        }
    all_items = len(rows)
    return {
        "wall_seconds": round(wall, 1),
        "workers": workers,
        "items": all_items,
        "fraction_items_with_100_labels": round(sum(r["successes"] >= 100 for r in rows) / max(all_items, 1), 3),
        "item_seconds_total": round(sum(r["seconds"] for r in rows), 1),
        "item_cpu_seconds_total": round(sum(r["cpu_seconds"] for r in rows), 1),
        "per_category": per_cat,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--objects-per-category", type=int, default=3)
    ap.add_argument("--states", type=int, default=10)
    ap.add_argument("--per-state", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--work", type=Path, default=Path("/tmp/centerart_grasps_bench"))
    ap.add_argument("--skip-generation", action="store_true")
    args = ap.parse_args()
    objects = args.work / "objects"
    generate_objects(GenerateObjectsConfig(out=objects, count=args.objects_per_category, seed=0, workers=args.workers))
    folders = sorted(p for p in objects.iterdir() if (p / "mobility.urdf").is_file())
    report = {
        "code_version": code_version(),
        "command": "benchmarks/grasps_bench.py "
        + " ".join(f"--{k.replace('_', '-')} {v}" for k, v in vars(args).items()),
        "protocol": {k: getattr(ex, k) for k in ("SUCCESS_ANGLE", "SUCCESS_DISTANCE", "GRASP_FORCE", "PULL_SPEED")},
        "executor": bench_executor([folders[i] for i in range(0, len(folders), max(1, args.objects_per_category))]),
    }
    if not args.skip_generation:
        report["generation"] = bench_generation(
            objects, args.work / "labels", args.states, args.per_state, args.workers
        )
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    run_main(main)
