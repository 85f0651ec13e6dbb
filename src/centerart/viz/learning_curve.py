"""The learning curve of a sliced run (``centerart slices status --plot``): each validation figure of its ledger
against the run's total steps, from where the run started (slice 0) to its last slice."""

from __future__ import annotations

from pathlib import Path

from centerart.utils.atomic import atomic_write_bytes


def draw_learning_curve(curve: dict, out: Path) -> Path:
    """Write ``out`` (a PNG) from :func:`centerart.recipe.slices.learning_curve`'s dict: one panel per figure,
    x the run's total steps, each point labelled with its slice (0: the start); encoder runs also name the
    distinct images seen by then."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns, points = curve["columns"], curve["points"]
    fig, axes = plt.subplots(1, len(columns), figsize=(3.4 * len(columns), 3.3), dpi=100, squeeze=False)
    for ax, column in zip(axes[0], columns, strict=True):
        _panel(ax, points, column, curve["units"][column])
    fig.suptitle(f"{Path(curve['run']).name}: validation after each slice ({curve['kind']} run)")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    plt.close(fig)
    atomic_write_bytes(Path(out), buffer.getvalue())  # no half-written picture if the call is interrupted
    return Path(out)


def _panel(ax, points: list[dict], column: str, unit: str) -> None:
    shown = [p for p in points if p[column] is not None]
    ax.plot([p["total_steps"] for p in shown], [p[column] for p in shown], "o-", color="#1f77b4")
    for p in shown:
        label = str(p["slice"])
        if p.get("distinct_images"):
            label += f" ({p['distinct_images'] / 1000:.1f}k img)"
        ax.annotate(label, (p["total_steps"], p[column]), textcoords="offset points", xytext=(4, 4), fontsize=7)
    ax.set_xlabel("total steps")
    ax.set_ylabel(f"{column} ({unit})")
    ax.grid(alpha=0.3)
