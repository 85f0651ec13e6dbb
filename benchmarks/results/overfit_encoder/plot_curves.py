"""Learning curves of the overfit-check variants (the JSON files beside this script) -> curves.png and a
Markdown table on stdout.

    python benchmarks/results/overfit_encoder/plot_curves.py
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

HERE = Path(__file__).resolve().parent
KEYS = (
    ("rotation_deg_median", "rotation (deg, median)"),
    ("translation_cm_median", "translation (cm, median)"),
    ("recall", "recall"),
    ("shape_code_l1_mean", "shape code L1 per dimension"),
)


def main() -> None:
    runs = {p.stem: json.loads(p.read_text()) for p in sorted(HERE.glob("*.json")) if "curve" in p.read_text()}
    runs = {k: v for k, v in runs.items() if v["curve"]}
    fig, axes = plt.subplots(1, len(KEYS), figsize=(4 * len(KEYS), 3.2))
    for name, run in runs.items():
        steps = [p["step"] for p in run["curve"]]
        for ax, (key, title) in zip(axes, KEYS, strict=True):
            ax.plot(steps, [p.get(key, float("nan")) for p in run["curve"]], marker="o", ms=3, label=name)
            ax.set_title(title)
            ax.set_xlabel("step")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(HERE / "curves.png", dpi=90)
    print("| run | step | rotation deg | translation cm | recall | code L1 / dim |")
    print("|---|---|---|---|---|---|")
    for name, run in runs.items():
        for p in run["curve"]:
            print(f"| {name} | {p['step']} | {p['rotation_deg_median']:.1f} | {p['translation_cm_median']:.2f} | "
                  f"{p['recall']:.2f} | {p['shape_code_l1_mean']:.4f} |")  # fmt: skip


if __name__ == "__main__":
    main()
