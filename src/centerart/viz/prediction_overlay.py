"""Pictures of a prediction: detections, poses, joint axes and top grasps drawn on the RGB image.

Colours: each object has a palette colour (its mask tint, caption and grasps); pose axes x red, y green, z blue
(0.2 m); the joint axis is yellow with a dot at the predicted axis point; grasps are drawn as the gripper's
outline (palm bar and two fingers), the best one thickest.
"""

from __future__ import annotations

import cv2
import numpy as np

from centerart.geometry.camera import project
from centerart.grasps.gripper import FINGER_LENGTH, MAX_OPENING, PALM_TO_TCP
from centerart.viz.encoder_sheet import detections_as_labels
from centerart.viz.scenes_sheet import PALETTE, draw_labels


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
        thick = 3 if rank == min(top_k, len(poses)) - 1 else 1
        for a, b in ((0, 1), (2, 3), (4, 5)):
            cv2.line(img, tuple(uv[a]), tuple(uv[b]), tuple(int(c) for c in color), thick, cv2.LINE_AA)


def draw_prediction(rgb: np.ndarray, preds, K: np.ndarray, top_k: int = 3) -> np.ndarray:
    """RGB with masks tinted, poses, joint axes, top grasps and a caption per object."""
    img = rgb[..., :3].copy()
    for k, p in enumerate(preds):
        if p.mask is not None:
            color = PALETTE[k % len(PALETTE)]
            img[p.mask] = (0.6 * img[p.mask] + 0.4 * color).astype(np.uint8)
    img = draw_labels(img, detections_as_labels(preds, K))
    scale = img.shape[1] / 640
    for k, p in enumerate(preds):
        color = PALETTE[k % len(PALETTE)]
        draw_grasps(img, p.grasp_poses, K, color, top_k)
        u, v = np.round(p.peak_uv).astype(int) if p.peak_uv is not None else (10, 20 + 15 * k)
        text = f"#{k} {p.joint_type[:4]} q={p.joint_state:.2f}{p.joint_unit} s={p.score:.2f} g={len(p.grasp_poses)}"
        cv2.putText(img, text, (int(u) + 6, int(v)), cv2.FONT_HERSHEY_SIMPLEX, 0.42 * scale, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(img, text, (int(u) + 6, int(v)), cv2.FONT_HERSHEY_SIMPLEX, 0.42 * scale,
                    tuple(int(c) for c in color), 1, cv2.LINE_AA)  # fmt: skip
    return img
