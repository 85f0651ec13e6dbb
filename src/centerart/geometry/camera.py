"""Pinhole cameras, written once: intrinsics, projection, back-projection and camera-frame conventions.

Conventions (used by every stage):
- Camera frame: OpenCV (x right, y down, z forward), metres.
- Pixels: OpenCV's convention, the centre of pixel (u, v) (column u, row v) lies at integer coordinates (u, v);
  a W x H image spans u in [-0.5, W - 0.5]. ``K = [[fx, s, cx], [0, fy, cy], [0, 0, 1]]``.
- Depth images hold z along the optical axis (not the ray length) in metres; 0 or a non-finite value is a hole.
- Renderers that look along +x with z up (SAPIEN) or along -z with y up (OpenGL) are converted with the constant
  poses below: ``world_T_sapien = world_T_opencv @ OPENCV_T_SAPIEN``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Columns: SAPIEN camera axes (forward, left, up) written in OpenCV camera coordinates.
OPENCV_T_SAPIEN = np.array([[0.0, -1.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
#: Columns: OpenGL camera axes (right, up, backward) written in OpenCV camera coordinates.
OPENCV_T_OPENGL = np.diag([1.0, -1.0, -1.0, 1.0])


@dataclass(frozen=True)
class Intrinsics:
    """A pinhole camera's intrinsics and image size (pixels, OpenCV pixel-centre convention)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    skew: float = 0.0

    @classmethod
    def from_matrix(cls, K, width: int, height: int) -> Intrinsics:
        """From a 3x3 ``K`` (nested lists or array) and the image size it belongs to."""
        K = np.asarray(K, dtype=float)
        if K.shape != (3, 3):
            raise ValueError(f"K must be a finite 3x3 matrix, got shape {K.shape}")
        if not np.all(np.isfinite(K)):
            raise ValueError("K must be a finite 3x3 matrix, got NaN or infinite entries")
        return cls(int(width), int(height), K[0, 0], K[1, 1], K[0, 2], K[1, 2], K[0, 1])

    @property
    def K(self) -> np.ndarray:
        """The 3x3 intrinsic matrix."""
        return np.array([[self.fx, self.skew, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.width, self.height

    def problems(self) -> list[str]:
        """Why these intrinsics cannot describe a real camera of this image size (empty when they can)."""
        out = []
        if self.width <= 0 or self.height <= 0:
            out.append(f"image size {self.width}x{self.height} is not positive")
        if not (self.fx > 0 and self.fy > 0):
            out.append(f"focal lengths fx={self.fx}, fy={self.fy} must be positive")
        if not (-0.5 <= self.cx <= self.width - 0.5 and -0.5 <= self.cy <= self.height - 0.5):
            out.append(f"principal point ({self.cx}, {self.cy}) lies outside the {self.width}x{self.height} image")
        return out

    def scaled(self, width: int, height: int) -> Intrinsics:
        """Intrinsics of the same camera after resizing its image to ``width`` x ``height``.

        Pixel centres map as ``u' = (u + 0.5) * sx - 0.5`` (the image's outer edges stay its outer edges).
        """
        sx, sy = width / self.width, height / self.height
        return Intrinsics(
            width,
            height,
            self.fx * sx,
            self.fy * sy,
            (self.cx + 0.5) * sx - 0.5,
            (self.cy + 0.5) * sy - 0.5,
            self.skew * sx,
        )

    def cropped(self, u0: int, v0: int, width: int, height: int) -> Intrinsics:
        """Intrinsics of the ``width`` x ``height`` window whose top-left pixel is (u0, v0) of this image."""
        return Intrinsics(width, height, self.fx, self.fy, self.cx - u0, self.cy - v0, self.skew)

    def to_dict(self) -> dict:
        return {"width": self.width, "height": self.height, "K": self.K.tolist()}

    @classmethod
    def from_dict(cls, data: dict) -> Intrinsics:
        return cls.from_matrix(data["K"], data["width"], data["height"])


def project(points_camera: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixels (N, 2) as (u, v) and depths (N,) (z, m) of points (N, 3) in the OpenCV camera frame.

    Points at or behind the camera plane (z <= 0) get non-finite pixels.
    """
    pts = np.atleast_2d(np.asarray(points_camera, dtype=float))
    z = pts[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        x, y = pts[:, 0] / z, pts[:, 1] / z
        uv = np.stack([K[0, 0] * x + K[0, 1] * y + K[0, 2], K[1, 1] * y + K[1, 2]], axis=1)
    uv[z <= 0] = np.nan
    return uv, z


def pixel_rays(uv: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Directions (N, 3) with z = 1 through pixels (N, 2) (u, v), OpenCV camera frame."""
    uv = np.atleast_2d(np.asarray(uv, dtype=float))
    y = (uv[:, 1] - K[1, 2]) / K[1, 1]
    x = (uv[:, 0] - K[0, 2] - K[0, 1] * y) / K[0, 0]
    return np.stack([x, y, np.ones_like(x)], axis=1)


def backproject_pixels(uv: np.ndarray, depth: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Points (N, 3) in the OpenCV camera frame at pixels (N, 2) with depths (N,) (z, m)."""
    return pixel_rays(uv, K) * np.asarray(depth, dtype=float)[:, None]


def backproject_depth(depth: np.ndarray, K: np.ndarray, mask: np.ndarray | None = None, return_pixels: bool = False):
    """Points (N, 3) in the OpenCV camera frame of every valid pixel of a depth image (H, W) in metres.

    A pixel is valid when its depth is finite and positive and ``mask`` (H, W, bool) is true there. Points come in
    row-major pixel order. With ``return_pixels`` also returns their pixels (N, 2) as integer (u, v).
    """
    depth = np.asarray(depth, dtype=float)
    valid = np.isfinite(depth) & (depth > 0)
    if mask is not None:
        valid &= np.asarray(mask, dtype=bool)
    v, u = np.nonzero(valid)
    uv = np.stack([u, v], axis=1)
    points = backproject_pixels(uv, depth[v, u], K)
    return (points, uv) if return_pixels else points


def depth_to_point_map(depth: np.ndarray, K: np.ndarray) -> np.ndarray:
    """(H, W, 3) camera-frame point of every pixel (OpenCV frame, m); holes give NaN."""
    depth = np.asarray(depth, dtype=float)
    h, w = depth.shape
    v, u = np.mgrid[0:h, 0:w]
    uv = np.stack([u.ravel(), v.ravel()], axis=1)
    z = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan).ravel()
    return backproject_pixels(uv, z, K).reshape(h, w, 3)
