"""``centerart encoder show``: what the encoder sees and finds, one row per view.

RGB | depth the encoder got | predicted centre heatmap | predictions: peaks (white rings), poses as axes (x red,
y green, z blue, 0.2 m), joint axes (yellow) and a caption per object (type, state, score) | ground truth drawn
the same way. Everything is drawn in the camera image, in the view's own K.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import cv2
import numpy as np

from centerart.utils.checks import at_least
from centerart.viz.contact_sheet import grid, labelled, save_png
from centerart.viz.scenes_sheet import colorize_depth, draw_labels, heatmap_image


@dataclass
class ShowEncoderConfig:
    """Encoder predictions next to the ground truth on rendered views."""

    scenes: Path
    """A scene dataset folder (``centerart scenes generate`` output)."""
    checkpoint: Path | None = None
    """Encoder checkpoint (default: the shipped encoder)."""
    out: Path = Path("encoder.png")
    max_views: int = 6
    depth: Literal["realistic", "true"] = "realistic"
    tile_width: int = 360

    def __post_init__(self):
        at_least("--max-views", self.max_views, 1)
        at_least("--tile-width", self.tile_width, 16)


def detections_as_labels(dets, K: np.ndarray) -> dict:
    """Predictions in the labels.json layout :func:`draw_labels` reads."""
    objects = []
    for d in dets:
        objects.append(
            {
                "camera_T_object": d.camera_T_object.tolist(),
                "joint": {
                    "axis_origin_camera": d.axis_point.tolist(),
                    "axis_direction_camera": d.axis_direction.tolist(),
                },
            }
        )
    return {"K": K.tolist(), "objects": objects}


def draw_predictions(rgb: np.ndarray, dets, K: np.ndarray) -> np.ndarray:
    img = draw_labels(rgb, detections_as_labels(dets, K))
    scale = img.shape[1] / 640
    for d in dets:
        u, v = np.round(d.peak_uv).astype(int)
        cv2.circle(img, (int(u), int(v)), max(4, int(6 * scale)), (255, 255, 255), max(1, int(2 * scale)))
        unit = "rad" if d.joint_type == "revolute" else "m"
        text = f"{d.joint_type[:4]} q={d.joint_state:.2f}{unit} s={d.score:.2f}"
        cv2.putText(img, text, (int(u) + 6, int(v) - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.4 * scale, (255, 255, 255), 1,
                    cv2.LINE_AA)  # fmt: skip
    return img


def show_encoder(cfg: ShowEncoderConfig) -> Path:
    from centerart.models.encoder.checkpoint import load_encoder
    from centerart.models.encoder.detect import detect_objects
    from centerart.scenes.dataset import list_views, load_view

    encoder = load_encoder(cfg.checkpoint).encoder
    rows = []
    for view_dir in list_views(cfg.scenes)[: cfg.max_views]:
        v = load_view(view_dir)
        depth, camera = v.depth(cfg.depth)[0], v.camera
        enc = detect_objects(encoder, v.rgb, depth, camera)
        valid = depth[depth > 0]
        lo, hi = (np.percentile(valid, 1), np.percentile(valid, 99)) if valid.size else (0.0, 1.0)
        name = f"{view_dir.parent.parent.name}/{view_dir.name}"
        n_true = len(v.labels["objects"])
        tiles = [
            labelled(v.rgb[..., :3].copy(), f"{name} RGB"),
            labelled(colorize_depth(depth, lo, hi), f"input depth ({cfg.depth})"),
            labelled(heatmap_image(v.rgb[..., :3], enc.heatmap), "predicted centre heatmap"),
            labelled(draw_predictions(v.rgb[..., :3], enc.detections, camera.K), f"{len(enc.detections)} found"),
            labelled(draw_labels(v.rgb[..., :3], v.labels), f"ground truth: {n_true} objects"),
        ]
        h, w = v.rgb.shape[:2]
        size = (cfg.tile_width, round(cfg.tile_width * h / w))
        rows.append([cv2.resize(t, size, interpolation=cv2.INTER_AREA) for t in tiles])
    return save_png(grid(rows), cfg.out)
