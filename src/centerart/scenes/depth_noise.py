"""Realistic depth: active stereo (IR pair + dot projector + OpenCV StereoSGBM) and a cheaper analytic model.

Stereo: the renderer draws the left and right IR images of a rectified pair (same intrinsics as the RGB camera,
right camera ``baseline_m`` to the right of the left one) under a projected random-dot pattern
(:func:`dot_pattern`). :func:`stereo_depth` matches them with semi-global block matching, converts disparity to
depth in the left IR frame (``z = f * b / d``) and re-projects that depth into the RGB camera frame
(:func:`register_depth`), which is offset by ``left_offset_m`` along x. Holes (0) appear where matching fails:
the left band the matcher cannot search, projector shadows and occlusion edges, low-texture dark or glossy
surfaces, and far away where the dots fade. This is what a RealSense D415 does on its ASIC.

Analytic (:func:`analytic_depth`): noise that grows with depth as a disparity error of ``sigma_disparity_px``
(axial sigma = z^2 sigma_d / (f b)), a lateral jitter of the depth map (Gaussian pixel shifts), dropout of pixels
on depth edges, and random blob-shaped holes. Depth maps are float32 metres; 0 marks invalid pixels.
"""

from __future__ import annotations

import cv2
import numpy as np

from centerart.geometry.camera import backproject_depth, project
from centerart.geometry.transforms import apply_transform

SGBM_BLOCK = 7


def dot_pattern(seed: int, width: int = 1280, height: int = 960, dot_fraction: float = 0.12) -> np.ndarray:
    """A random-dot projector pattern (height, width, 4) uint8 RGBA, white dots of 1-2 px on black."""
    rng = np.random.default_rng(seed)
    pattern = np.zeros((height, width), np.float32)
    n = int(dot_fraction * width * height / 2.5)
    ys = rng.integers(0, height, n)
    xs = rng.integers(0, width, n)
    pattern[ys, xs] = rng.uniform(0.6, 1.0, n)
    pattern = cv2.GaussianBlur(pattern, (3, 3), 0.6)
    pattern = np.clip(pattern / max(pattern.max(), 1e-6), 0, 1)
    img = (pattern * 255).astype(np.uint8)
    return np.dstack([img, img, img, np.full_like(img, 255)])


def to_ir_uint8(image: np.ndarray, rng: np.random.Generator | None, noise_sigma: float = 2.0) -> np.ndarray:
    """IR sensor readout: grey level with auto-exposure (99th percentile to 230) and Gaussian read noise."""
    grey = image[..., :3].mean(-1) if image.ndim == 3 else image
    gain = 230.0 / max(float(np.percentile(grey, 99)), 1e-4)
    out = grey * gain
    if rng is not None and noise_sigma > 0:
        out = out + rng.normal(0.0, noise_sigma, out.shape)
    return np.clip(out, 0, 255).astype(np.uint8)


def num_disparities(fx: float, baseline: float, min_depth: float = 0.45) -> int:
    d = fx * baseline / min_depth
    return int(min(256, max(32, 16 * int(np.ceil(d / 16)))))


def sgbm_disparity(left: np.ndarray, right: np.ndarray, n_disp: int) -> np.ndarray:
    """Disparity (float32 px, <= 0 invalid) of a rectified uint8 pair with OpenCV's semi-global matching."""
    matcher = cv2.StereoSGBM_create(
        minDisparity=0,
        numDisparities=n_disp,
        blockSize=SGBM_BLOCK,
        P1=8 * SGBM_BLOCK**2,
        P2=32 * SGBM_BLOCK**2,
        disp12MaxDiff=1,
        uniquenessRatio=15,
        speckleWindowSize=100,
        speckleRange=2,
        mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY,
    )
    return matcher.compute(left, right).astype(np.float32) / 16.0


def register_depth(depth_src: np.ndarray, K: np.ndarray, dst_T_src: np.ndarray) -> np.ndarray:
    """Re-project a depth map (float32 m, 0 = hole) from one camera into another with the same K.

    ``dst_T_src`` maps the source camera's OpenCV frame into the destination's. Each source pixel lands on the
    nearest destination pixel; where several land on one, the nearest surface wins (z-buffer).
    """
    h, w = depth_src.shape
    dst_T_src = np.asarray(dst_T_src, float)
    if _is_x_shift(dst_T_src, K):
        u2, v2, z = _shift_along_x(depth_src, K, float(dst_T_src[0, 3]))
    else:
        pts = apply_transform(dst_T_src, backproject_depth(depth_src, K))
        pts = pts[pts[:, 2] > 1e-3]
        uv = np.round(project(pts, K)[0]).astype(np.int64)
        u2, v2, z = uv[:, 0], uv[:, 1], pts[:, 2]
    inside = (u2 >= 0) & (u2 < w) & (v2 >= 0) & (v2 < h)
    out = np.full(h * w, np.inf, np.float32)
    np.minimum.at(out, v2[inside] * w + u2[inside], z[inside].astype(np.float32))
    out[np.isinf(out)] = 0.0
    return out.reshape(h, w)


def _is_x_shift(dst_T_src: np.ndarray, K: np.ndarray) -> bool:
    """True for a pure translation along x and a camera without skew: the case of a rectified stereo rig."""
    return (
        np.array_equal(dst_T_src[:3, :3], np.eye(3))
        and dst_T_src[1, 3] == 0.0
        and dst_T_src[2, 3] == 0.0
        and np.array_equal(dst_T_src[3], [0.0, 0.0, 0.0, 1.0])
        and K[0, 1] == 0.0
    )


def _shift_along_x(depth_src: np.ndarray, K: np.ndarray, tx: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Destination pixels (u, v) and depths of every valid source pixel when the destination camera sits ``-tx``
    along x of the source (points move by ``+tx``): rows stay, columns move by ``fx * tx / z`` pixels. Same
    result as back-projecting, transforming and projecting every pixel, at a fraction of the cost (the
    registration of every stereo depth map takes this path)."""
    depth = np.asarray(depth_src, dtype=float)
    v, u = np.nonzero(np.isfinite(depth) & (depth > 1e-3))
    z = depth[v, u]
    u2 = np.round(u + K[0, 0] * tx / z).astype(np.int64)
    return u2, v, z


def stereo_occlusion(
    depth_left: np.ndarray, depth_right: np.ndarray, K: np.ndarray, baseline: float, tolerance: float = 0.02
) -> np.ndarray:
    """Pixels of the left IR image whose surface point is hidden from the right IR camera (True = occluded).

    Uses the true depth seen by each camera of the rectified pair: the left pixel (u, v) at depth z appears in the
    right image at u - f b / z; it is occluded when the right camera sees something nearer there.
    """
    h, w = depth_left.shape
    v, u = np.nonzero(depth_left > 0)
    z = depth_left[v, u]
    ur = np.round(u - K[0, 0] * baseline / z).astype(np.int64)
    inside = (ur >= 0) & (ur < w)
    occluded = np.zeros((h, w), bool)
    zr = depth_right[v[inside], ur[inside]]
    occluded[v[inside], u[inside]] = (zr > 0) & (zr < z[inside] * (1.0 - tolerance))
    return occluded


def stereo_depth(
    ir_left: np.ndarray,
    ir_right: np.ndarray,
    K: np.ndarray,
    baseline: float,
    left_offset: float,
    min_depth: float = 0.45,
    max_depth: float = 6.0,
    occluded: np.ndarray | None = None,
) -> np.ndarray:
    """Depth (float32 m, 0 = hole) in the RGB frame from a rectified uint8 IR pair.

    ``occluded`` (left-image pixels hidden from the right camera, :func:`stereo_occlusion`) are invalidated as the
    sensor's left-right consistency check does; SGBM alone tends to fill them with the background's disparity.
    """
    n_disp = num_disparities(K[0, 0], baseline, min_depth)
    disp = sgbm_disparity(ir_left, ir_right, n_disp)
    depth = np.zeros_like(disp)
    ok = disp > 0.5
    depth[ok] = K[0, 0] * baseline / disp[ok]
    depth[(depth < min_depth) | (depth > max_depth)] = 0.0
    if occluded is not None:
        depth[cv2.dilate(occluded.astype(np.uint8), np.ones((1, 3), np.uint8)).astype(bool)] = 0.0
    rgb_T_left = np.eye(4)
    rgb_T_left[0, 3] = left_offset
    return register_depth(depth, K, rgb_T_left)


def analytic_depth(
    depth: np.ndarray,
    K: np.ndarray,
    rng: np.random.Generator,
    baseline: float = 0.055,
    sigma_disparity_px: float = 0.08,
    lateral_sigma_px: float = 0.5,
    edge_threshold_m: float = 0.03,
    edge_dropout: float = 0.7,
    hole_fraction: float = 0.01,
    max_depth: float = 6.0,
) -> np.ndarray:
    """Depth with a structured-light-like error model (float32 m, 0 = hole); see the module docstring."""
    h, w = depth.shape
    fb = K[0, 0] * baseline
    # Lateral noise: sample the true depth at jittered pixel positions (nearest, so edges do not blend).
    mx = (np.arange(w)[None, :] + rng.normal(0, lateral_sigma_px, (h, w))).astype(np.float32)
    my = (np.arange(h)[:, None] + rng.normal(0, lateral_sigma_px, (h, w))).astype(np.float32)
    out = cv2.remap(depth.astype(np.float32), mx, my, cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE)
    valid = out > 0
    # Axial noise: Gaussian in disparity, spatially correlated over a few pixels like block matching.
    disp = np.where(valid, fb / np.maximum(out, 1e-6), 0.0)
    noise = cv2.GaussianBlur(rng.normal(0, 1, (h, w)).astype(np.float32), (0, 0), 1.5)
    noise *= sigma_disparity_px / max(float(noise.std()), 1e-6)
    disp = disp + noise
    out = np.where(valid & (disp > 0.1), fb / np.maximum(disp, 1e-6), 0.0).astype(np.float32)
    # Quantise to 1/8 px of disparity (sub-pixel resolution of a typical matcher).
    out = np.where(out > 0, fb / (np.round(fb / np.maximum(out, 1e-6) * 8) / 8), 0.0).astype(np.float32)
    # Edge dropout: pixels next to a depth discontinuity vanish with probability ``edge_dropout``.
    dmax = cv2.dilate(depth.astype(np.float32), np.ones((3, 3), np.uint8))
    dmin = -cv2.dilate(-np.where(depth > 0, depth, 1e3).astype(np.float32), np.ones((3, 3), np.uint8))
    edges = (dmax - dmin) > edge_threshold_m * np.maximum(depth, 0.5)
    edges = cv2.dilate(edges.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    out[edges & (rng.random((h, w)) < edge_dropout)] = 0.0
    # Holes: a few blobs of invalid pixels (specular spots, absorbing patches).
    n_holes = rng.poisson(max(hole_fraction * h * w / 150.0, 0.0))
    hole_mask = np.zeros((h, w), np.uint8)
    for _ in range(n_holes):
        cx, cy = int(rng.integers(w)), int(rng.integers(h))
        ax = (int(rng.integers(2, 9)), int(rng.integers(2, 9)))
        cv2.ellipse(hole_mask, (cx, cy), ax, float(rng.uniform(0, 180)), 0, 360, 1, -1)
    out[hole_mask > 0] = 0.0
    out[out > max_depth] = 0.0
    return out
