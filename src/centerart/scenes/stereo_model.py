"""The errors of the simulated stereo sensor, drawn from the true depth at any image size (``--depth stereo-model``).

Why: the encoder trains at 320x240. Matching an IR pair rendered at that size does not give the depth a full-size
(640x480) stereo image has once the loader shrinks it: disparities halve, so the same sub-pixel matching error is
twice the depth error, and the 7-px block spans twice the scene (measured: median errors 2.0-2.6x and holes 1.6-3.3x
those of the full-size sensor, ``benchmarks/results/cheap_scenes``). Rendering and matching the pair at full size
costs more than the rest of a small image. This model instead applies what :func:`~centerart.scenes.depth_noise.
stereo_depth` does at the reference resolution, measured on it, to the rasterised true depth:

* geometry, exact: the matcher's blind band (left IR columns below its disparity range, at the reference size),
  surfaces the left IR camera, the right IR camera or the projector cannot see (each a rectified partner of the
  RGB camera along x: :func:`~centerart.scenes.ir_synthesis.projector_visibility`), the 0.45-6 m range;
* disparity error in reference pixels (``fx_ref * b / z``): a bias plus a Gaussian field that is smooth over the
  matcher's window (two blur scales, fitted to the error's autocorrelation), quantised to SGBM's 1/16 px;
* edges: the depth is sampled at smoothly jittered positions (block matching fattens and wobbles edges) and pixels
  on depth discontinuities drop out with a probability;
* other holes (dark or far surfaces, the speckle filter): blobs at a rate per pixel.

Every length in pixels is given at the reference focal length ``reference_fx`` and scaled by ``fx / reference_fx``,
so the model's output, at any size, has the error statistics of the reference sensor seen at that size. Frames:
depth is z along the RGB camera's optical axis (OpenCV), metres, float32, 0 = hole; offsets along the RGB camera's
x axis as in :class:`~centerart.scenes.description.StereoSpec`.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from centerart.scenes.depth_noise import num_disparities
from centerart.scenes.ir_synthesis import projector_visibility


@dataclass(frozen=True)
class StereoErrorModel:
    """Parameters of :func:`modelled_stereo_depth`, in pixels of the reference sensor (640x480, fx = 615: the
    ``d415`` preset matched by :func:`~centerart.scenes.depth_noise.stereo_depth`); fitted on kitchen views of
    seed 0 and checked on other seeds (``benchmarks/cheap_scenes.py``)."""

    reference_fx: float = 615.0
    disparity_bias_px: float = 0.06
    """Mean disparity error (the matcher reads surfaces slightly near)."""
    disparity_sigma_px: float = 0.2
    sigma_growth_per_m2: float = 0.01
    """The error's standard deviation is ``disparity_sigma_px * (1 + sigma_growth_per_m2 * z^2)``: the dots fade
    with distance, so far surfaces match a little worse (0.155 px median at 2 m, 0.175 px at 4.2 m)."""
    fine_share: float = 0.38
    """Share of the disparity error's variance in the fine field; the rest is coarse."""
    fine_blur_px: float = 2.4
    coarse_blur_px: float = 12.0
    lateral_sigma_px: float = 0.5
    """Smooth jitter of where the depth is sampled: the matcher's edge fattening and wobble."""
    lateral_blur_px: float = 4.0
    edge_threshold: float = 0.03
    """A pixel is on a depth edge when its 3x3 neighbourhood spans more than this share of its depth."""
    edge_dropout: float = 0.08
    hole_rate: float = 1e-4
    """Blob holes per reference pixel."""
    hole_radius_px: tuple[float, float] = (2.0, 8.0)
    min_depth_m: float = 0.45
    max_depth_m: float = 6.0


def smooth_field(rng: np.random.Generator, shape: tuple[int, int], blur_px: float) -> np.ndarray:
    """A zero-mean, unit-variance Gaussian field (float32) blurred over ``blur_px`` pixels."""
    field = cv2.GaussianBlur(rng.standard_normal(shape, dtype=np.float32), (0, 0), max(blur_px, 1e-3))
    return field / max(float(field.std()), 1e-6)


def sensor_visibility(depth: np.ndarray, fx: float, left_offset: float, baseline: float, projector_offset: float):
    """(H, W) True where the left IR camera, the right IR camera and the projector all see each RGB pixel's surface
    point (a pixel the sensor can measure); offsets in metres along the RGB camera's x axis."""
    seen = depth > 0
    for partner_x in (left_offset, left_offset + baseline, projector_offset):
        seen &= projector_visibility(depth, fx, -partner_x)
    return seen


def blind_band(depth: np.ndarray, K: np.ndarray, left_offset: float, baseline: float, reference_fx: float):
    """(H, W) True where an RGB pixel's point falls in the left IR image's columns that the matcher cannot search
    (below its number of disparities, counted at the reference size)."""
    w = depth.shape[1]
    scale = K[0, 0] / reference_fx
    u_left = np.arange(w, dtype=np.float32)[None, :] - K[0, 0] * left_offset / np.where(depth > 0, depth, np.inf)
    u_reference = (u_left + 0.5) / scale - 0.5
    return u_reference < num_disparities(reference_fx, baseline)


def depth_edges(depth: np.ndarray, threshold: float) -> np.ndarray:
    """(H, W) True on depth discontinuities: the 3x3 neighbourhood (holes excluded) spans more than ``threshold``
    times the depth (at least 0.5 m)."""
    kernel = np.ones((3, 3), np.uint8)
    dmax = cv2.dilate(depth, kernel)
    dmin = -cv2.dilate(-np.where(depth > 0, depth, 1e3).astype(np.float32), kernel)
    return (dmax - dmin) > threshold * np.maximum(depth, 0.5)


def modelled_stereo_depth(
    depth: np.ndarray,
    K: np.ndarray,
    rng: np.random.Generator,
    left_offset: float = 0.015,
    baseline: float = 0.055,
    projector_offset: float = 0.030,
    model: StereoErrorModel | None = None,
) -> np.ndarray:
    """Stereo-like depth (float32 m, 0 = hole) in the RGB frame from the true depth (H, W) and K; see the module
    docstring."""
    m = model or StereoErrorModel()
    depth = np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)
    h, w = depth.shape
    scale = float(K[0, 0]) / m.reference_fx
    # Lateral: sample the true depth at smoothly jittered positions (nearest, so no depth between surfaces).
    jx, jy = (smooth_field(rng, (h, w), m.lateral_blur_px * scale) * (m.lateral_sigma_px * scale) for _ in "xy")
    mx = np.arange(w, dtype=np.float32)[None, :] + jx
    my = np.arange(h, dtype=np.float32)[:, None] + jy
    z = cv2.remap(depth, mx, my, cv2.INTER_NEAREST, borderMode=cv2.BORDER_REPLICATE)
    valid = z > 0
    # Axial: disparity error in reference pixels, a fine and a coarse smooth field; SGBM's 1/16 px steps.
    fb = m.reference_fx * baseline
    noise = np.sqrt(m.fine_share) * smooth_field(rng, (h, w), m.fine_blur_px * scale)
    noise += np.sqrt(1.0 - m.fine_share) * smooth_field(rng, (h, w), m.coarse_blur_px * scale)
    sigma = m.disparity_sigma_px * (1.0 + m.sigma_growth_per_m2 * z * z)
    disparity = fb / np.where(valid, z, 1.0) + m.disparity_bias_px + sigma * noise
    disparity = np.round(disparity * 16.0) / 16.0
    valid &= disparity > 0.5
    out = np.where(valid, fb / np.maximum(disparity, 1e-6), 0.0).astype(np.float32)
    # Holes: what the sensor cannot see or search, edges, blobs, range.
    measurable = sensor_visibility(depth, float(K[0, 0]), left_offset, baseline, projector_offset)
    measurable &= ~blind_band(depth, K, left_offset, baseline, m.reference_fx)
    edges = depth_edges(depth, m.edge_threshold)
    measurable &= ~(edges & (rng.random((h, w)) < m.edge_dropout))
    measurable &= blob_holes(rng, (h, w), m.hole_rate / scale**2, m.hole_radius_px, scale) == 0
    out[~measurable | (out < m.min_depth_m) | (out > m.max_depth_m)] = 0.0
    return out


def blob_holes(
    rng: np.random.Generator, shape: tuple[int, int], rate: float, radius_px: tuple[float, float], scale: float
) -> np.ndarray:
    """(H, W) uint8 mask of elliptic blobs, Poisson(``rate`` * pixels) of them, half axes uniform in ``radius_px``
    (reference pixels) times ``scale``."""
    h, w = shape
    mask = np.zeros(shape, np.uint8)
    for _ in range(rng.poisson(rate * h * w)):
        centre = (int(rng.integers(w)), int(rng.integers(h)))
        axes = tuple(max(1, round(float(rng.uniform(*radius_px)) * scale)) for _ in range(2))
        cv2.ellipse(mask, centre, axes, float(rng.uniform(0, 180)), 0, 360, 1, -1)
    return mask


#: True-depth bands (m) of :func:`error_bands`.
ERROR_BANDS_M = ((0.5, 1.5), (1.5, 2.5), (2.5, 3.5), (3.5, 5.0))


def error_bands(views: list[tuple[np.ndarray, np.ndarray]], skip_left_px: int = 0) -> dict:
    """Error statistics of realistic depth against true depth over views ``[(true, realistic), ...]`` (H, W) m,
    0 = nothing / hole: per band of true depth the median and 90th percentile of the absolute error of measured
    pixels (mm) and the hole share; the hole share on depth edges (:func:`depth_edges`, 3 %) and off them; all
    right of ``skip_left_px`` columns, whose hole share is reported alone (the matcher's blind band)."""
    errors: dict = {b: [] for b in ERROR_BANDS_M}
    counts = {key: np.zeros(2) for key in (*ERROR_BANDS_M, "edge", "flat", "left")}
    for true, real in views:
        true, real = np.asarray(true, np.float32), np.asarray(real, np.float32)
        edges = depth_edges(true, 0.03)
        seen = true > 0
        counts["left"] += [(seen[:, :skip_left_px] & (real[:, :skip_left_px] == 0)).sum(), seen[:, :skip_left_px].sum()]
        t, r, e, s = true[:, skip_left_px:], real[:, skip_left_px:], edges[:, skip_left_px:], seen[:, skip_left_px:]
        hole = s & (r == 0)
        counts["edge"] += [(hole & e).sum(), (s & e).sum()]
        counts["flat"] += [(hole & ~e).sum(), (s & ~e).sum()]
        for lo, hi in ERROR_BANDS_M:
            band = s & (t >= lo) & (t < hi)
            counts[(lo, hi)] += [(band & hole).sum(), band.sum()]
            ok = band & ~hole
            errors[(lo, hi)].append(np.abs(r[ok] - t[ok]))
    out: dict = {}
    for lo, hi in ERROR_BANDS_M:
        e = np.concatenate(errors[(lo, hi)]) * 1000.0
        n_hole, n = counts[(lo, hi)]
        out[f"{lo}-{hi}m"] = {
            "median_mm": round(float(np.median(e)), 1) if len(e) else None,
            "p90_mm": round(float(np.percentile(e, 90)), 1) if len(e) else None,
            "holes": round(float(n_hole / max(n, 1)), 4),
            "pixels": int(n),
        }
    for key in ("edge", "flat", "left"):
        out[f"{key}_holes"] = round(float(counts[key][0] / max(counts[key][1], 1)), 4)
    return out
