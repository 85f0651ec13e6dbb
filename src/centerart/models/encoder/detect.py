"""One camera image in, detected objects out: letterbox, run the encoder, read the peaks, map back.

Returned detections are in the OpenCV camera frame of the given image (m, rad); their ``peak_uv`` and ``mask``
are in the given image's pixels (masks and the heatmap are warped back from the encoder's input).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import torch

from centerart.geometry.camera import Intrinsics
from centerart.models.encoder.inputs import Letterbox, to_tensors
from centerart.models.encoder.network import RGBDEncoder
from centerart.models.encoder.readout import PEAK_THRESHOLD, Detection, read_objects


@dataclass
class EncodedImage:
    detections: list[Detection]
    heatmap: np.ndarray
    """(H, W) predicted centre heatmap in the camera image's pixels."""
    letterbox: Letterbox
    seconds: float = 0.0
    """Wall time of the encoder pass (set by ``Predictor.encode``)."""


def back_to_camera(image: np.ndarray, box: Letterbox, width: int, height: int, nearest: bool = False) -> np.ndarray:
    """Warp an image of the encoder input back into the camera image (inverse letterbox)."""
    inv = cv2.invertAffineTransform(box.matrix)
    flags = cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR
    return cv2.warpAffine(image, inv, (width, height), flags=flags, borderMode=cv2.BORDER_CONSTANT)


@torch.no_grad()
def detect_objects(
    encoder: RGBDEncoder, rgb: np.ndarray, depth: np.ndarray, camera: Intrinsics, peak_threshold: float = PEAK_THRESHOLD
) -> EncodedImage:
    """Detections of one RGB (H, W, 3) uint8 and depth (H, W) metres image taken with ``camera``."""
    cfg = encoder.config
    box = Letterbox.fit(camera.width, camera.height, cfg.input_width, cfg.input_height)
    rgb_in, depth_in = box.warp(np.ascontiguousarray(rgb[..., :3]), depth)
    rgb_t, depth_t = to_tensors(rgb_in, depth_in)
    device = next(encoder.parameters()).device
    out = encoder(rgb_t[None].to(device), depth_t[None].to(device))
    dets = read_objects(
        out, box.intrinsics(camera).K, peak_threshold=peak_threshold, radius_cells=cfg.read_radius_cells
    )
    for d in dets:
        d.peak_uv = box.to_camera_pixels(d.peak_uv)
        d.mask = back_to_camera(d.mask.astype(np.uint8), box, camera.width, camera.height, nearest=True) > 0
    heat = back_to_camera(out.heatmap[0].float().cpu().numpy(), box, camera.width, camera.height)
    return EncodedImage(dets, heat, box)
