"""Image preparation shared by training and inference: letterboxing with the intrinsics carried along.

An image of any size and K is scaled by ``s`` and shifted so that its pixel (u, v) lands on
``(s (u + 0.5) - 0.5 - u0, s (v + 0.5) - 0.5 - v0)`` of the network input (OpenCV pixel-centre convention, as in
:meth:`centerart.geometry.camera.Intrinsics.scaled`); the input's intrinsics are the camera's scaled and shifted
the same way, so points back-projected from the input's depth are the camera's points, unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from centerart.geometry.camera import Intrinsics


@dataclass(frozen=True)
class Letterbox:
    """The map from a camera image to the network input: scale ``s`` then shift by (-u0, -v0) pixels."""

    scale: float
    u0: float
    v0: float
    width: int
    height: int

    @classmethod
    def fit(cls, width: int, height: int, out_width: int, out_height: int) -> Letterbox:
        """Scale to fit inside the input (aspect kept), image at the top-left, zero padding right/bottom."""
        return cls(min(out_width / width, out_height / height), 0.0, 0.0, out_width, out_height)

    @property
    def matrix(self) -> np.ndarray:
        """2x3 affine map (camera pixel -> input pixel) for ``cv2.warpAffine``."""
        s = self.scale
        return np.array([[s, 0.0, 0.5 * s - 0.5 - self.u0], [0.0, s, 0.5 * s - 0.5 - self.v0]])

    def intrinsics(self, camera: Intrinsics) -> Intrinsics:
        s = self.scale
        return Intrinsics(
            self.width,
            self.height,
            camera.fx * s,
            camera.fy * s,
            (camera.cx + 0.5) * s - 0.5 - self.u0,
            (camera.cy + 0.5) * s - 0.5 - self.v0,
            camera.skew * s,
        )

    def to_input_pixels(self, uv: np.ndarray) -> np.ndarray:
        return self.scale * (np.asarray(uv, float) + 0.5) - 0.5 - np.array([self.u0, self.v0])

    def to_camera_pixels(self, uv: np.ndarray) -> np.ndarray:
        return (np.asarray(uv, float) + 0.5 + np.array([self.u0, self.v0])) / self.scale - 0.5

    def warp(self, rgb: np.ndarray, depth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """RGB (linear interpolation) and depth (nearest: no depth is invented between a surface and its
        background) resampled into the input; outside the camera image both are 0."""
        size = (self.width, self.height)
        m = self.matrix
        if self.scale < 0.75:  # shrinking: low-pass first so thin structures do not alias away in the RGB
            rgb = cv2.GaussianBlur(rgb, (0, 0), 0.25 / self.scale)
        rgb_out = cv2.warpAffine(rgb, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
        depth = np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)
        depth_out = cv2.warpAffine(depth, m, size, flags=cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT)
        return rgb_out, depth_out


def to_tensors(rgb: np.ndarray, depth: np.ndarray):
    """(3, H, W) float RGB in [0, 1] and (1, H, W) depth in metres, as torch tensors."""
    import torch

    rgb_t = torch.from_numpy(np.ascontiguousarray(rgb)).permute(2, 0, 1).float() / 255.0
    return rgb_t, torch.from_numpy(np.ascontiguousarray(depth, dtype=np.float32))[None]
