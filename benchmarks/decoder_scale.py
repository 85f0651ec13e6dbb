"""Decoder generalization against the number of training objects: collects ``centerart eval decoder`` reports of
several decoders (one folder each) into one table and draws the curves. Prints JSON.

    python benchmarks/decoder_scale.py --run 17 benchmarks/results/decoder_scale/objects_020 \
        --run 34 benchmarks/results/decoder_scale/objects_040 --run 102 benchmarks/results/decoder_scale/objects_120 \
        --out benchmarks/results/decoder_scale/curve.json

Each run folder holds the reports of one checkpoint, as many as were measured: ``train/report.json`` (the
checkpoint's own SDF folder: training objects at training states, held-out states, its own held-out objects),
``test/report.json`` (the held-out test objects, seed 9000, never trained on by any run) and ``real/report.json``
(the PartNet-Mobility samples). Splits: train, heldout_state (from ``train``), test and real (the ``heldout_object``
group of ``test`` and ``real``: codes fitted to the object's SDF samples, decoder frozen).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bench_report import emit

KEYS = ("chamfer_mm", "chamfer_mm_median", "fscore", "physics_top1", "physics_top5", "physics_any5", "states")
SPLITS = {"train": ("train", "train"), "heldout_state": ("train", "heldout_state"),
          "test": ("test", "heldout_object"), "real": ("real", "heldout_object")}  # fmt: skip


def collect(folder: Path) -> dict:
    """Split -> metric row (with the closed-state top-1 and the confidence ROC AUC) of one run folder."""
    rows = {}
    for split, (report_name, group) in SPLITS.items():
        path = folder / report_name / "report.json"
        if not path.is_file():
            continue
        summary = json.loads(path.read_text())["summary"]
        if group not in summary:
            continue
        g = summary[group]
        row = {k: g.get(k) for k in KEYS}
        row["physics_top1_by_state_kind"] = {k: v.get("physics_top1") for k, v in g.get("by_state_kind", {}).items()}
        row["confidence_auroc"] = g.get("calibration", {}).get("auroc")
        rows[split] = row
    return rows


def draw(runs: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8), dpi=100)
    for split in SPLITS:
        pts = [(r["training_objects"], r["splits"][split]) for r in runs if split in r["splits"]]
        if not pts:
            continue
        n = [p[0] for p in pts]
        for ax, key in zip(axes, ("chamfer_mm", "fscore", "physics_top1"), strict=True):
            ax.plot(n, [p[1][key] for p in pts], marker="o", label=split)
    for ax, label in zip(axes, ("Chamfer-L1 mean (mm)", "F-score@1cm", "physics top-1"), strict=True):
        ax.set_xscale("log")
        ax.set_xlabel("training objects")
        ax.set_ylabel(label)
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
    main()
