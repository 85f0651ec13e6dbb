"""Training augmentation for the encoder: colour jitter, depth realism, and scale/shift that keep K consistent.

Depth, chosen per sample (:class:`AugmentConfig` probabilities): the view's realistic depth as rendered (stereo
matching or the analytic model), the true depth through the analytic sensor model with random strength (noise,
holes, edge dropout: :func:`centerart.scenes.depth_noise.analytic_depth`), or the true depth unchanged. The
published code has a flag for depth noise that was never implemented; here it is.

Geometry: a random scale around the letterbox fit and a random shift. Both go through
:class:`~centerart.models.encoder.inputs.Letterbox`, which moves K with the pixels, so back-projected points do not
change (tested).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import cv2
import numpy as np

from centerart.models.encoder.inputs import Letterbox
from centerart.scenes.depth_noise import analytic_depth


@dataclass(frozen=True)
class AugmentConfig:
    enabled: bool = True
    brightness: float = 0.4
    contrast: float = 0.3
    saturation: float = 0.4
    hue: float = 0.04
    """Colour jitter ranges: factors 1 +- x (hue: fraction of the colour circle)."""
    p_realistic_depth: float = 0.5
    p_analytic_depth: float = 0.4
    """Otherwise true depth. A view without realistic depth uses the analytic model instead."""
    scale_range: tuple[float, float] = (0.8, 1.25)
    """Multiplies the letterbox's fit scale."""

    def to_dict(self) -> dict:
        return asdict(self)


def jitter_colour(rgb: np.ndarray, cfg: AugmentConfig, rng: np.random.Generator) -> np.ndarray:
    img = rgb.astype(np.float32)
    img *= rng.uniform(1 - cfg.brightness, 1 + cfg.brightness)
    mean = img.mean()
    img = (img - mean) * rng.uniform(1 - cfg.contrast, 1 + cfg.contrast) + mean
    grey = img.mean(axis=2, keepdims=True)
    img = (img - grey) * rng.uniform(1 - cfg.saturation, 1 + cfg.saturation) + grey
    img = np.clip(img, 0, 255).astype(np.uint8)
    if cfg.hue > 0:
        hsv = cv2.cvtColor(img, cv2.COLOR_RGB2HSV)
        shift = round(rng.uniform(-cfg.hue, cfg.hue) * 180)
        hsv[..., 0] = ((hsv[..., 0].astype(np.int32) + shift) % 180).astype(np.uint8)
        img = cv2.cvtColor(hsv, cv2.COLOR_HSV2RGB)
    return img


def choose_depth(
    depth_true: np.ndarray, depth_realistic: np.ndarray | None, K: np.ndarray, cfg: AugmentConfig, rng
) -> tuple[np.ndarray, str]:
    """The depth image a sample trains on, and which kind it is (realistic / analytic / true)."""
    r = rng.random()
    if r < cfg.p_realistic_depth and depth_realistic is not None:
        return depth_realistic, "realistic"
    if r < cfg.p_realistic_depth + cfg.p_analytic_depth or depth_realistic is None:
        noisy = analytic_depth(
            depth_true,
            K,
            rng,
            sigma_disparity_px=rng.uniform(0.04, 0.2),
            edge_dropout=rng.uniform(0.3, 0.9),
            hole_fraction=rng.uniform(0.0, 0.03),
        )
        return noisy, "analytic"
    return depth_true, "true"


def random_letterbox(width: int, height: int, out_w: int, out_h: int, cfg: AugmentConfig, rng) -> Letterbox:
    """A letterbox with a random scale (relative to the fit) and a random shift within the scaled image."""
    fit = Letterbox.fit(width, height, out_w, out_h).scale
    s = fit * rng.uniform(*cfg.scale_range)
    span_u, span_v = width * s - out_w, height * s - out_h
    u0 = rng.uniform(min(0.0, span_u), max(0.0, span_u))
    v0 = rng.uniform(min(0.0, span_v), max(0.0, span_v))
    return Letterbox(s, u0, v0, out_w, out_h)
