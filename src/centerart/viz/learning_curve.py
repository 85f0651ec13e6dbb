"""The learning curve of a sliced run (``centerart slices status --plot``): each validation figure of its ledger
against the run's total steps, from where the run started (slice 0) to its last slice."""

from __future__ import annotations

from pathlib import Path

from centerart.utils.atomic import atomic_write_bytes


def draw_learning_curve(curve: dict, out: Path) -> Path:
    """Write ``out`` (a PNG) from :func:`centerart.recipe.slices.learning_curve`'s dict: one panel per figure,
    x the run's total steps, each point labelled with its slice (0: the start); for encoder runs a line under
    the title names the distinct images seen by each slice (beside the points they overlapped once slices were
    close together)."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns, points = curve["columns"], curve["points"]
    fig, axes = plt.subplots(1, len(columns), figsize=(3.4 * len(columns), 3.3), dpi=100, squeeze=False)
    for ax, column in zip(axes[0], columns, strict=True):
        _panel(ax, points, column, curve["units"][column])
    fig.suptitle(f"{Path(curve['run']).name}: validation after each slice ({curve['kind']} run)" + _images_line(points))
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    plt.close(fig)
    atomic_write_bytes(Path(out), buffer.getvalue())  # no half-written picture if the call is interrupted
    return Path(out)


def _panel(ax, points: list[dict], column: str, unit: str) -> None:
    from matplotlib.ticker import FuncFormatter

    shown = [p for p in points if p[column] is not None]
    ax.plot([p["total_steps"] for p in shown], [p[column] for p in shown], "o-", color="#1f77b4")
    for i, p in enumerate(shown):
        # alternate above and below the line so that neighbouring slices' numbers do not print over each other
        offset = (3, 5) if i % 2 == 0 else (3, -11)
        ax.annotate(
            str(p["slice"]), (p["total_steps"], p[column]), textcoords="offset points", xytext=offset, fontsize=8
        )
    # thousands, so that five-digit step counts do not run into each other under a narrow panel
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x / 1000:g}k"))
    ax.set_xlabel("total steps")
    ax.set_ylabel(f"{column} ({unit})")
    ax.grid(alpha=0.3)


def _images_line(points: list[dict]) -> str:
    """A second title line, 'distinct images seen by slice 1: 4.5k, 2: 9.0k, ...', for an encoder run; empty
    for a decoder run (its ledger counts no images)."""
    seen = [f"{p['slice']}: {p['distinct_images'] / 1000:.1f}k" for p in points if p.get("distinct_images")]
    return "\ndistinct images seen by slice " + ", ".join(seen) if seen else ""
