"""Benchmark the object generator: objects per second per core, mesh sizes, and how many attempts the checks reject.

    python benchmarks/objects_bench.py --count 10            # prints one JSON object

Runs in one process (one core): generation + writing + all physics checks per object, then statistics from the
manifest. The same code as `centerart objects generate`.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from bench_report import run_main
from centerart.assets.categories import CATEGORIES
from centerart.assets.dataset import GenerateObjectsConfig, generate_objects


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=10, help="objects per category")
    parser.add_argument("--seed", type=int, default=1000)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "objects"
        t0 = time.perf_counter()
        result = generate_objects(
            GenerateObjectsConfig(out=out, category="all", count=args.count, seed=args.seed, workers=1)
        )
        wall = time.perf_counter() - t0
        records = result["objects"]
        tris = np.array([r["triangles"] for r in records])
        per_cat = {}
        for c in CATEGORIES:
            rows = [r for r in records if r["category"] == c]
            t = np.array([r["triangles"] for r in rows])
            per_cat[c] = {
                "objects": len(rows),
                "rejected_attempts": int(sum(len(r["rejected"]) for r in rows)),
                "seconds_per_object_mean": round(float(np.mean([r["seconds"] for r in rows])), 4),
                "triangles_min": int(t.min()),
                "triangles_median": float(np.median(t)),
                "triangles_max": int(t.max()),
            }
        attempts = sum(1 + len(r["rejected"]) for r in records)
        print(
            json.dumps(
                {
                    "benchmark": "objects",
                    "objects": len(records),
                    "workers": 1,
                    "wall_seconds": round(wall, 2),
                    "objects_per_second_per_core": round(len(records) / wall, 3),
                    "attempts": attempts,
                    "rejected_attempts": attempts - len(records),
                    "pass_fraction_before_filtering": round(len(records) / attempts, 4),
                    "pass_fraction_after_filtering": 1.0,
                    "triangles_median": float(np.median(tris)),
                    "triangles_max": int(tris.max()),
                    "per_category": per_cat,
                },
                indent=2,
            )
        )


if __name__ == "__main__":
    run_main(main)
