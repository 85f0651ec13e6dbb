"""Pictures of a scene evaluation (``centerart eval scenes``): SR per category, the distribution of the distance
from the top grasp to the nearest label, and a contact sheet of the worst failures with the executed grasp drawn
(red: the learned method's top grasp; green: the ground-truth label the oracle executed)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from centerart.viz.contact_sheet import grid, labelled, save_png
from centerart.viz.prediction_overlay import draw_grasps

MAX_FAILURES = 12
THUMB_WIDTH = 400


def _records(out: Path) -> list[dict]:
    """The records the report was made from: the scenes ``testset.json`` selected (an earlier, larger run into the
    same folder may have left more)."""
    from centerart.evaluation.scene_report import load_records

    testset = json.loads((Path(out) / "testset.json").read_text())
    sets = {n: [Path(s["folder"]) / scene for scene in s["scenes"]] for n, s in testset["sets"].items()}
    return load_records(out, sets)[0]


METHOD_COLOURS = {"centerart": "#1f77b4", "centerart+icp": "#9467bd", "centerart+sdf": "#17becf",
                  "baseline": "#ff7f0e", "oracle": "#2ca02c"}  # fmt: skip


def plot_sr_by_category(report: dict, path: Path) -> Path:
    """One panel per test set: SR per category, a bar per method (colour) and depth mode (solid: true depth,
    hatched: realistic)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sets = list(report["sets"])
    fig, axes = plt.subplots(len(sets), 1, figsize=(9.0, 2.6 * len(sets)), dpi=110, squeeze=False)
    for ax, name in zip(axes[:, 0], sets, strict=True):
        keys = [k for k in report["groups"] if k.split("|")[0] == name and report["groups"][k]["sr"] is not None]
        cats = sorted({c for k in keys for c in report["groups"][k]["by_category"]})
        width = 0.8 / max(1, len(keys))
        for i, key in enumerate(sorted(keys, key=lambda k: (k.split("|")[1], k.split("|")[2] != "true"))):
            _, method, depth = key.split("|")
            by_cat = report["groups"][key]["by_category"]
            vals = [(by_cat.get(c) or {}).get("sr") or 0.0 for c in cats]
            style = {"color": METHOD_COLOURS.get(method, "grey"), "hatch": "//" if depth != "true" else None}
            ax.bar(
                np.arange(len(cats)) + i * width, vals, width, edgecolor="white", label=f"{method}, {depth}", **style
            )
        ax.set_xticks(np.arange(len(cats)) + 0.4 - width / 2, cats)
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("SR")
        ax.set_title(f"{report['sets'][name].get('label', name)} ({report['sets'][name]['layout']})", fontsize=9)
    axes[0, 0].legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, 1.45))
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path


def plot_nearest_label(report: dict, records: list[dict], path: Path) -> Path:
    """One panel per test set: the share of objects whose top grasp lies within x of a ground-truth label
    (method = colour, solid = true depth, dashed = realistic); misses count as never within."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sets = list(report["sets"])
    fig, axes = plt.subplots(1, len(sets), figsize=(3.4 * len(sets), 3.2), dpi=110, squeeze=False, sharey=True)
    for ax, name in zip(axes[0], sets, strict=True):
        by: dict[tuple[str, str], list[float]] = {}
        for rec in (r for r in records if r["set"] == name):
            for r in (r for r in rec["rows"] if r["method"] != "oracle"):
                d = r.get("nearest_label_m")
                by.setdefault((r["method"], r["depth"]), []).append(np.inf if d is None else d)
        for (method, depth), d in sorted(by.items()):
            d = np.sort(np.asarray(d))
            ax.step(d, np.arange(1, len(d) + 1) / len(d), where="post", color=METHOD_COLOURS.get(method, "grey"),
                    ls="-" if depth == "true" else "--", label=f"{method}, {depth}")  # fmt: skip
        ax.axvline(0.03, color="k", ls=":", lw=0.8)
        ax.set_xlim(0, 0.5)
        ax.set_ylim(0, 1)
        ax.set_title(report["sets"][name].get("label", name), fontsize=9)
        ax.set_xlabel("top grasp to nearest label (m)")
    axes[0, 0].set_ylabel("share of objects (dotted: RSR 3 cm)")
    axes[0, 0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def failure_tile(folder: Path, row: dict, oracle: dict | None) -> np.ndarray:
    from PIL import Image

    view_dir = Path(folder) / row["scene"] / "views" / f"{row['view']:02d}"
    rgb = np.asarray(Image.open(view_dir / "rgb.png").convert("RGB")).copy()
    K = np.asarray(json.loads((view_dir / "labels.json").read_text())["K"], float)
    mask = np.asarray(Image.open(view_dir / "instances.png")) == row["instance"] + 1
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    cv2.drawContours(rgb, contours, -1, (255, 255, 0), 2)
    if oracle and oracle.get("grasp_camera"):
        draw_grasps(rgb, np.asarray([oracle["grasp_camera"]]), K, (40, 220, 40), top_k=1)
    if row.get("grasp_camera"):
        draw_grasps(rgb, np.asarray([row["grasp_camera"]]), K, (230, 30, 30), top_k=1)
    scale = THUMB_WIDTH / rgb.shape[1]
    rgb = cv2.resize(rgb, (THUMB_WIDTH, round(rgb.shape[0] * scale)), interpolation=cv2.INTER_AREA)
    d = row.get("nearest_label_m")
    text = (f"{row['scene']} {row['category']} {row['depth']}: {row['sr_abort']}"
            + (f", {100 * d:.0f} cm from a label" if d is not None else ""))  # fmt: skip
    return labelled(rgb, text, 11)


def plot_failures(out: Path, report: dict, records: list[dict], path: Path) -> Path | None:
    """Contact sheet of the learned method's worst failures: matched objects whose top grasp lay furthest from
    every label first, then misses."""
    oracle = {(rec["set"], r["scene"], r["view"], r["instance"]): r for rec in records for r in rec["rows"]
              if r["method"] == "oracle"}  # fmt: skip
    fails = [(rec["set"], r) for rec in records for r in rec["rows"] if r["method"].startswith("centerart")]
    fails = [(s, r) for s, r in fails if not r["sr"]]
    if not fails:
        return None
    fails.sort(key=lambda sr: (not sr[1]["matched"], -(sr[1].get("nearest_label_m") or 0.0)))
    tiles = [
        failure_tile(Path(report["sets"][s]["folder"]), r, oracle.get((s, r["scene"], r["view"], r["instance"])))
        for s, r in fails[:MAX_FAILURES]
    ]
    h = max(t.shape[0] for t in tiles)
    tiles = [np.pad(t, ((0, h - t.shape[0]), (0, 0), (0, 0)), constant_values=255) for t in tiles]
    rows = [tiles[i : i + 4] for i in range(0, len(tiles), 4)]
    return save_png(grid(rows), path)


def draw_eval_pictures(out: Path, report: dict) -> list[Path]:
    """Write ``plots/sr_by_category.png``, ``plots/nearest_label.png`` and ``failures.png`` under ``out``."""
    out = Path(out)
    records = _records(out)
    written = [plot_sr_by_category(report, out / "plots" / "sr_by_category.png")]
    written.append(plot_nearest_label(report, records, out / "plots" / "nearest_label.png"))
    sheet = plot_failures(out, report, records, out / "failures.png")
    return written + ([sheet] if sheet else [])
