"""Pictures of a decoder evaluation (``centerart eval decoder``): shape and grasp metrics per group, and the
reliability diagram of the grasp confidences against their physics outcomes."""

from __future__ import annotations

from pathlib import Path

import numpy as np

GROUP_COLOURS = {"train": "#1f77b4", "heldout_state": "#2ca02c", "heldout_object": "#d62728"}


def draw_decoder_eval(report: dict, out: Path) -> Path:
    """``out/report.png`` from a report of ``evaluation.decoder_eval.evaluate_decoder``: Chamfer-L1 per group
    (box plot over states), F-score, grasp metrics, and calibration (success rate per confidence bin)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    states = report["states"]
    groups = [g for g in GROUP_COLOURS if g in report["summary"]]
    fig, axes = plt.subplots(1, 4, figsize=(17, 3.8), dpi=100)
    data = [[s["chamfer_mm"] for s in states if s["group"] == g and np.isfinite(s["chamfer_mm"])] for g in groups]
    if groups:
        axes[0].boxplot([d or [np.nan] for d in data], tick_labels=groups)
        axes[1].bar(groups, [report["summary"][g]["fscore"] for g in groups])
    axes[0].set_ylabel("Chamfer-L1 (mm)")
    axes[1].set_ylabel(f"F-score@{report['thresholds']['fscore_m'] * 100:.0f}cm")
    _grasp_bars(axes[2], report, groups)
    _reliability(axes[3], report, groups)
    fig.tight_layout()
    path = Path(out) / "report.png"
    fig.savefig(path)
    plt.close(fig)
    return path


def _grasp_bars(ax, report: dict, groups: list[str]) -> None:
    for i, key in enumerate(("precision_at_k", "coverage", "physics_top1")):
        vals = [report["summary"][g].get(key, np.nan) for g in groups]
        ax.bar(np.arange(len(groups)) + (i - 1) * 0.27, vals, width=0.27, label=key)
    ax.set_xticks(np.arange(len(groups)), groups)
    ax.set_ylim(0, 1)
    ax.legend(fontsize=8)
    ax.set_title("grasps")


def _reliability(ax, report: dict, groups: list[str]) -> None:
    """Success rate against mean confidence per bin (marker area ~ grasps in the bin); the diagonal is perfect
    calibration."""
    ax.plot([0, 1], [0, 1], color="0.6", lw=1, ls="--")
    for g in groups:
        cal = report["summary"][g].get("calibration", {})
        rows = [b for b in cal.get("bins", []) if b["count"]]
        if rows:
            auc = cal["auroc"]
            label = f"{g} (n={cal['count']}, AUC {'-' if auc is None else f'{auc:.2f}'})"
            x, y = [b["mean_score"] for b in rows], [b["success_rate"] for b in rows]
            sizes = [12 + 16 * b["count"] ** 0.5 for b in rows]
            ax.scatter(x, y, s=sizes, color=GROUP_COLOURS[g], label=label)
            ax.plot(x, y, color=GROUP_COLOURS[g])
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.set_xlabel("grasp confidence (bin mean)")
    ax.set_ylabel("physics success rate")
    ax.set_title("calibration of the top-5 grasps")
    ax.legend(fontsize=7)
