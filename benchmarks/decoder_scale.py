"""Decoder generalization against the number of training objects: collects ``grasp_extraction_ab.py`` results of
several decoders (one folder each) into one table and draws the curves. Prints JSON.

    python benchmarks/decoder_scale.py --run 34 benchmarks/results/decoder_scale/objects_040 \
        --run 102 benchmarks/results/decoder_scale/objects_120 --out benchmarks/results/decoder_scale/curve.json

Each run folder holds, for one checkpoint, as many of these as were measured: ``test.json`` (the held-out test
objects, seed 9000, never trained on by any run; codes fitted to their SDF samples), ``real.json`` (the
PartNet-Mobility samples, codes fitted likewise) and ``train.json`` (training objects with their trained codes).
Per split and state kind (closed, fully open): Chamfer-L1 mean / median (mm), F-score@1cm, physics top-1 and any of
5 with the default grasp extraction.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from bench_report import emit, run_main

SPLITS = ("train", "test", "real")
KINDS = ("closed", "open")


def collect(folder: Path) -> dict:
    """Split -> state kind -> metrics of one run folder (splits without a file are left out)."""
    rows = {}
    for split in SPLITS:
        path = folder / f"{split}.json"
        if not path.is_file():
            continue
        summary = json.loads(path.read_text())["summary"]
        rows[split] = {
            kind: {"chamfer_mm": None, "fscore": None, **summary.get("shape", {}).get(kind, {}),
                   "top1": summary["default"][kind]["top1"],
                   "any5": summary["default"][kind]["any5"], "states": summary["default"][kind]["states"]}
            for kind in KINDS
        }  # fmt: skip
        rows[split]["both"] = {
            key: float(np.mean([rows[split][k][key] for k in KINDS]))
            for key in ("chamfer_mm", "fscore", "top1", "any5")
            if all(rows[split][k][key] is not None for k in KINDS)
        }
    return rows


def draw(runs: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8), dpi=100)
    for split in SPLITS:
        pts = [(r["training_objects"], r["splits"][split]["both"]) for r in runs if split in r["splits"]]
        for ax, key in zip(axes, ("chamfer_mm", "fscore", "top1"), strict=True):
            xy = [(n, row[key]) for n, row in pts if key in row]
            if xy:
                ax.plot(*zip(*xy, strict=True), marker="o", label=split)
    for ax, label in zip(axes, ("Chamfer-L1 mean (mm)", "F-score@1cm", "physics top-1"), strict=True):
        ax.set_xscale("log")
        ax.set_xlabel("training objects")
        ax.set_ylabel(f"{label}, closed and open")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", nargs=2, action="append", metavar=("TRAINING_OBJECTS", "FOLDER"), required=True)
    ap.add_argument("--out", type=Path, default=None, help="JSON path; the curves go beside it as .png")
    args = ap.parse_args()
    runs = [{"training_objects": int(n), "folder": str(f), "splits": collect(Path(f))} for n, f in args.run]
    runs.sort(key=lambda r: r["training_objects"])
    emit({"runs": runs}, args.out)
    if args.out:
        draw(runs, args.out.with_suffix(".png"))


if __name__ == "__main__":
    run_main(main)
