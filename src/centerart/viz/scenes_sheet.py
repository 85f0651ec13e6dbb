"""``centerart scenes show``: contact sheet of rendered views with their labels drawn on top.

One row per view: RGB with each object's label pose drawn as axes (x red, y green, z blue, 0.2 m) and its target
joint axis (yellow line through the axis origin; a dot at the origin) | true depth | realistic depth (holes black) |
instance masks with object names and joint states | centre heatmap over the image.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import cv2
import numpy as np
import tyro

from centerart.geometry.camera import project
from centerart.utils.checks import at_least
from centerart.viz.contact_sheet import grid, labelled, save_png

PALETTE = np.array(
    [
        [230, 25, 75],
        [60, 180, 75],
        [255, 225, 25],
        [0, 130, 200],
        [245, 130, 48],
        [145, 30, 180],
        [70, 240, 240],
        [240, 50, 230],
    ],
    np.uint8,
)


@dataclass
class ShowScenesConfig:
    """Contact sheet of a scene dataset: RGB | true depth | realistic depth | masks | heatmaps, with label poses."""

    path: Annotated[Path, tyro.conf.Positional]
    """A scene dataset folder (output of ``centerart scenes generate``)."""
    out: Path = Path("scenes.png")
    """PNG file to write."""
    max_views: int = 8
    """Show at most this many views (sorted by scene and view)."""
    tile_width: int = 400
    """Width of each tile in pixels (height follows the image aspect)."""

    def __post_init__(self):
        at_least("--max-views", self.max_views, 1)
        at_least("--tile-width", self.tile_width, 16)


def colorize_depth(depth: np.ndarray, lo: float, hi: float) -> np.ndarray:
    valid = depth > 0
    norm = np.clip((depth - lo) / max(hi - lo, 1e-6), 0, 1)
    img = cv2.applyColorMap((255 * (1 - norm)).astype(np.uint8), cv2.COLORMAP_TURBO)[..., ::-1].copy()
    img[~valid] = 0
    return img


def _project(K: np.ndarray, pts: np.ndarray) -> np.ndarray | None:
    if (pts[:, 2] < 0.05).any():
        return None
    return np.round(project(pts, K)[0]).astype(int)


def draw_labels(rgb: np.ndarray, labels: dict, axis_len: float = 0.2) -> np.ndarray:
    img = rgb.copy()
    K = np.asarray(labels["K"], float)
    thick = max(1, img.shape[1] // 320)
    for obj in labels["objects"]:
        T = np.asarray(obj["camera_T_object"], float)
        pts = np.array([[0, 0, 0], [axis_len, 0, 0], [0, axis_len, 0], [0, 0, axis_len]], float)
        uv = _project(K, pts @ T[:3, :3].T + T[:3, 3])
        if uv is not None:
            for end, color in zip(uv[1:], [(255, 0, 0), (0, 255, 0), (0, 80, 255)], strict=True):
                cv2.line(img, tuple(uv[0]), tuple(end), color, thick + 1, cv2.LINE_AA)
        j = obj["joint"]
        o = np.asarray(j["axis_origin_camera"], float)
        d = np.asarray(j["axis_direction_camera"], float)
        uv = _project(K, np.stack([o - 0.3 * d, o + 0.3 * d, o]))
        if uv is not None:
            cv2.line(img, tuple(uv[0]), tuple(uv[1]), (255, 230, 0), thick, cv2.LINE_AA)
            cv2.circle(img, tuple(uv[2]), 3 * thick, (255, 230, 0), -1)
    return img


def masks_image(rgb: np.ndarray, instances: np.ndarray, labels: dict) -> np.ndarray:
    img = (rgb.astype(float) * 0.35).astype(np.uint8)
    for obj in labels["objects"]:
        k = obj["instance"]
        m = instances == k
        img[m] = (0.35 * rgb[m] + 0.65 * PALETTE[(k - 1) % len(PALETTE)]).astype(np.uint8)
    scale = img.shape[1] / 640
    for obj in labels["objects"]:
        x0, y0, _x1, y1 = obj["bbox_xyxy"]
        j = obj["joint"]
        text = f"{obj['category'][:10]} q={j['state']:.2f}{j['unit']} vis={obj['visible_fraction']:.2f}"
        cv2.putText(
            img,
            text,
            (x0 + 2, max(12, (y0 + y1) // 2)),
            cv2.FONT_HERSHEY_SIMPLEX,
            0.4 * scale,
            (255, 255, 255),
            max(1, int(scale)),
            cv2.LINE_AA,
        )
    return img


def heatmap_image(rgb: np.ndarray, heat: np.ndarray) -> np.ndarray:
    colored = cv2.applyColorMap((np.clip(heat, 0, 1) * 255).astype(np.uint8), cv2.COLORMAP_JET)[..., ::-1]
    return (0.45 * rgb + 0.55 * colored).astype(np.uint8)


def show_scenes(cfg: ShowScenesConfig) -> Path:
    from centerart.scenes.dataset import list_views, load_view

    rows = []
    for view_dir in list_views(cfg.path)[: cfg.max_views]:
        v = load_view(view_dir)
        valid = v.depth_true[v.depth_true > 0]
        lo, hi = (np.percentile(valid, 1), np.percentile(valid, 99)) if valid.size else (0.0, 1.0)
        name = f"{view_dir.parent.parent.name}/{view_dir.name}"
        tiles = [
            labelled(draw_labels(v.rgb, v.labels), f"{name} RGB + label poses"),
            labelled(colorize_depth(v.depth_true, lo, hi), f"true depth {lo:.2f}-{hi:.2f} m"),
        ]
        if v.depth_realistic is not None:
            holes = float((v.depth_realistic == 0).mean())
            kind = v.labels.get("depth_realistic") or "realistic"
            tiles.append(labelled(colorize_depth(v.depth_realistic, lo, hi), f"{kind} depth, {holes:.0%} holes"))
        else:
            tiles.append(labelled(np.zeros_like(v.rgb), "no realistic depth"))
        tiles.append(labelled(masks_image(v.rgb, v.instances, v.labels), f"{len(v.labels['objects'])} instances"))
        tiles.append(labelled(heatmap_image(v.rgb, v.heatmap), "centre heatmap"))
        h, w = v.rgb.shape[:2]
        size = (cfg.tile_width, round(cfg.tile_width * h / w))
        rows.append([cv2.resize(t, size, interpolation=cv2.INTER_AREA) for t in tiles])
    return save_png(grid(rows), cfg.out)
