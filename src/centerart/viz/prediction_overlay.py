"""Pictures of a prediction: detections, poses, joint axes and top grasps drawn on the RGB image.

Colours: each object has a palette colour (its region's outline and light tint, its caption's swatch and its
grasps); pose axes x red, y green, z blue (0.2 m); the joint axis is yellow with a dot at the predicted axis point;
grasps are drawn as the open gripper's outline (palm bar and two fingers), the best one thickest.

With ``show_rejected`` the candidates that grasp anchoring rejected (``ObjectPrediction.rejected_grasps``) are drawn
too, beneath the kept grasps: thin 1-pixel outlines (no anti-aliasing) in the colour of their reason
(:data:`REASON_COLORS`), at most ``max_rejected`` per object, with a legend (reason, count) in the top-left corner.
They are off by default: an object has tens to hundreds of rejected candidates, which would bury the three kept
grasps that the picture is for; the toggle is for asking why a grasp was not kept.
"""

from __future__ import annotations

import cv2
import numpy as np

from centerart.geometry.camera import project
from centerart.grasps.gripper import FINGER_LENGTH, MAX_OPENING, PALM_TO_TCP
from centerart.viz.encoder_sheet import detections_as_labels
from centerart.viz.scenes_sheet import PALETTE, draw_labels

#: RGB of each rejection reason (grasp anchoring's checks), away from the object palette's hues where possible.
REASON_COLORS = {
    "far_from_material": (170, 170, 235),  # pale blue-grey: a neutral grey occurs in anti-aliased text
    "no_material_between_pads": (0, 255, 255),
    "collides_with_observed": (255, 0, 255),
}
OTHER_REASON_COLOR = (255, 255, 255)


def gripper_outline_tcp() -> np.ndarray:
    """(6, 3) segment end points of the open gripper's outline in the TCP frame (palm bar + two fingers)."""
    y, z0, z1 = MAX_OPENING / 2, -PALM_TO_TCP, -PALM_TO_TCP + FINGER_LENGTH
    return np.array([[0, -y, z0], [0, y, z0], [0, -y, z0], [0, -y, z1], [0, y, z0], [0, y, z1]], float)


def draw_grasps(img: np.ndarray, poses: np.ndarray, K: np.ndarray, color, top_k: int = 3) -> None:
    outline = gripper_outline_tcp()
    for rank, pose in enumerate(poses[:top_k][::-1]):
        pts = outline @ pose[:3, :3].T + pose[:3, 3]
        uv, _ = project(pts, K)
        if not np.isfinite(uv).all():
            continue
        uv = np.round(uv).astype(int)
        best = rank == min(top_k, len(poses)) - 1
        for a, b in ((0, 1), (2, 3), (4, 5)):  # a dark outline keeps the gripper visible on any background
            cv2.line(img, tuple(uv[a]), tuple(uv[b]), (20, 20, 20), 5 if best else 3, cv2.LINE_AA)
            cv2.line(img, tuple(uv[a]), tuple(uv[b]), tuple(int(c) for c in color), 3 if best else 1, cv2.LINE_AA)


def caption(img: np.ndarray, text: str, org: tuple[int, int], color, scale: float) -> None:
    """White text on a dark box, with a colour swatch that links it to its object."""
    font, size = cv2.FONT_HERSHEY_SIMPLEX, 0.45 * scale
    (w, h), base = cv2.getTextSize(text, font, size, 1)
    x = int(np.clip(org[0], 0, max(0, img.shape[1] - w - 14)))
    y = int(np.clip(org[1], h + 4, img.shape[0] - base - 2))
    cv2.rectangle(img, (x, y - h - 4), (x + w + 14, y + base + 2), (25, 25, 25), -1)
    cv2.rectangle(img, (x + 2, y - h - 1), (x + 9, y + base - 1), tuple(int(c) for c in color), -1)
    cv2.putText(img, text, (x + 12, y), font, size, (245, 245, 245), 1, cv2.LINE_AA)


def draw_rejected(img: np.ndarray, preds, K: np.ndarray, max_rejected: int = 60) -> dict[str, int]:
    """Draw every object's rejected candidates (camera-frame TCP poses, K: 3x3 pixels) as 1-pixel outlines in their
    reason's colour, at most ``max_rejected`` per object (evenly spaced in the saved order); returns the number
    of rejected candidates per reason (all of them, drawn or not)."""
    outline, counts = gripper_outline_tcp(), {}
    for p in preds:
        poses, reasons = p.rejected_grasps, list(p.rejected_reasons)
        if poses is None or len(poses) == 0:
            continue
        for reason in reasons:
            counts[reason] = counts.get(reason, 0) + 1
        pick = np.unique(np.linspace(0, len(poses) - 1, min(len(poses), max_rejected)).round().astype(int))
        for i in pick:
            pts = outline @ poses[i, :3, :3].T + poses[i, :3, 3]
            uv, _ = project(pts, K)
            if not np.isfinite(uv).all() or np.abs(uv).max() > 1e5:
                continue
            uv = np.round(uv).astype(int)
            color = REASON_COLORS.get(reasons[i], OTHER_REASON_COLOR)
            for a, b in ((0, 1), (2, 3), (4, 5)):
                cv2.line(img, tuple(uv[a]), tuple(uv[b]), color, 1, cv2.LINE_8)
    return counts


def draw_reason_legend(img: np.ndarray, counts: dict[str, int], scale: float) -> None:
    """A dark box in the top-left corner: one swatch (the reason's colour) and "reason: count" per line."""
    if not counts:
        return
    font, size = cv2.FONT_HERSHEY_SIMPLEX, 0.42 * scale
    lines = [(f"rejected, {reason.replace('_', ' ')}: {n}", REASON_COLORS.get(reason, OTHER_REASON_COLOR))
             for reason, n in sorted(counts.items(), key=lambda kv: _reason_order(kv[0]))]  # fmt: skip
    (_, h), base = cv2.getTextSize("Ag", font, size, 1)
    width = max(cv2.getTextSize(t, font, size, 1)[0][0] for t, _ in lines) + 22
    step = h + base + 4
    cv2.rectangle(img, (4, 4), (4 + width, 8 + step * len(lines)), (25, 25, 25), -1)
    for i, (text, color) in enumerate(lines):
        y = 6 + step * (i + 1) - base - 2
        cv2.rectangle(img, (8, y - h), (16, y), color, -1)
        cv2.putText(img, text, (20, y), font, size, (245, 245, 245), 1, cv2.LINE_AA)


def _reason_order(reason: str) -> int:
    names = list(REASON_COLORS)
    return names.index(reason) if reason in names else len(names)


def draw_prediction(
    rgb: np.ndarray, preds, K: np.ndarray, top_k: int = 3, show_rejected: bool = False, max_rejected: int = 60
) -> np.ndarray:
    """RGB with each object's region outlined, its pose, joint axis, top grasps and a caption; with
    ``show_rejected`` also the rejected grasp candidates by reason, and their legend (module docstring)."""
    img = rgb[..., :3].copy()
    for k, p in enumerate(preds):
        if p.mask is not None:
            color = PALETTE[k % len(PALETTE)]
            img[p.mask] = (0.8 * img[p.mask] + 0.2 * color).astype(np.uint8)
            contours, _ = cv2.findContours(p.mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
            cv2.drawContours(img, contours, -1, tuple(int(c) for c in color), 2, cv2.LINE_AA)
    img = draw_labels(img, detections_as_labels(preds, K))
    scale = img.shape[1] / 640
    reasons = draw_rejected(img, preds, K, max_rejected) if show_rejected else {}
    for k, p in enumerate(preds):
        color = PALETTE[k % len(PALETTE)]
        draw_grasps(img, p.grasp_poses, K, color, top_k)
        u, v = np.round(p.peak_uv).astype(int) if p.peak_uv is not None else (10, 20 + 15 * k)
        text = (
            f"#{k} {p.joint_type} {p.joint_state:.2f} {p.joint_unit}  score {p.score:.2f}  {len(p.grasp_poses)} grasps"
        )
        caption(img, text, (int(u) + 8, int(v) - 8), color, scale)
    draw_reason_legend(img, reasons, scale)
    return img
