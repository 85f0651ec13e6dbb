"""Procedural surface textures generated in code (no downloads): wood, paint, brushed metal, tile and stone.

Every texture is a deterministic function of its :class:`~centerart.scenes.description.MaterialSpec` (kind,
colour, seed), returned as an sRGB ``uint8`` image of shape (S, S, 3) that tiles seamlessly (all noise is
periodic), so it can repeat across a wall. ``texture_scale_m`` in the spec says how many metres one tile of the
image covers; the renderer turns that into UV coordinates.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

TEXTURE_KINDS = ("wood", "painted", "metal", "tile", "stone", "plain")


def periodic_noise(rng: np.random.Generator, size: int, cells: int | tuple[int, int], octaves: int = 1) -> np.ndarray:
    """Smooth value noise in [0, 1] on a (size, size) grid that wraps around at the borders.

    ``cells`` is the number of random lattice values per side (frequency); octaves double the frequency and halve
    the amplitude.
    """
    cy, cx = (cells, cells) if isinstance(cells, int) else cells
    out = np.zeros((size, size))
    total = 0.0
    amp = 1.0
    for _ in range(octaves):
        lattice = rng.random((cy, cx))
        # Cubic interpolation over a periodic lattice via FFT-free separable resampling.
        ys = np.arange(size) * cy / size
        xs = np.arange(size) * cx / size
        out += amp * _periodic_bicubic(lattice, ys, xs)
        total += amp
        amp *= 0.5
        cy, cx = cy * 2, cx * 2
    out /= total
    lo, hi = out.min(), out.max()
    return (out - lo) / max(hi - lo, 1e-9)


def _periodic_bicubic(lattice: np.ndarray, ys: np.ndarray, xs: np.ndarray) -> np.ndarray:
    def weights(t):
        # Catmull-Rom
        return np.stack(
            [
                -0.5 * t**3 + t**2 - 0.5 * t,
                1.5 * t**3 - 2.5 * t**2 + 1.0,
                -1.5 * t**3 + 2.0 * t**2 + 0.5 * t,
                0.5 * t**3 - 0.5 * t**2,
            ],
            axis=-1,
        )

    ny, nx = lattice.shape
    y0 = np.floor(ys).astype(int)
    x0 = np.floor(xs).astype(int)
    wy = weights(ys - y0)
    wx = weights(xs - x0)
    iy = (y0[:, None] + np.arange(-1, 3)[None]) % ny
    ix = (x0[:, None] + np.arange(-1, 3)[None]) % nx
    rows = np.einsum("yk,ykx->yx", wy, lattice[iy])  # (size_y, nx)
    return np.einsum("xk,yxk->yx", wx, rows[:, ix])


def _shade(color: np.ndarray, value: np.ndarray) -> np.ndarray:
    """Colour modulated by a [0, 1]-ish field (1 = colour itself)."""
    return np.clip(value[..., None] * color[None, None, :3], 0.0, 1.0)


def make_texture(kind: str, color: tuple[float, ...], seed: int, size: int = 256) -> np.ndarray:
    """A tileable texture image (size, size, 3) uint8 of ``kind`` around base ``color`` (RGB in 0..1)."""
    rng = np.random.default_rng(seed)
    c = np.asarray(color[:3], dtype=float)
    if kind == "wood":
        # Growth rings: a periodic distortion field bends parallel stripes; fine fibres run along the grain.
        warp = periodic_noise(rng, size, (4, 1), octaves=2)
        y = np.arange(size)[:, None] / size
        rings_per_tile = int(rng.integers(10, 20))
        phase = 2 * np.pi * (rings_per_tile * y + 0.6 * warp)
        rings = (0.5 + 0.5 * np.sin(phase)) ** 4
        fibres = periodic_noise(rng, size, (96, 2), octaves=2)
        planks = periodic_noise(rng, size, (1, 4))  # tone varies slowly along the grain
        value = 0.8 + 0.14 * rings + 0.1 * (fibres - 0.5) + 0.1 * (planks - 0.5)
        img = _shade(c, value)
    elif kind == "painted":
        # Paint: nearly flat, low-frequency roller unevenness plus a faint orange-peel speckle.
        value = 0.94 + 0.06 * periodic_noise(rng, size, 4, 2) + 0.03 * (periodic_noise(rng, size, 64) - 0.5)
        img = _shade(c, value)
    elif kind == "metal":
        # Brushed metal: noise stretched along one direction (brush strokes) over a slight large-scale sheen.
        strokes = periodic_noise(rng, size, (128, 2), octaves=2)
        sheen = periodic_noise(rng, size, 3)
        value = 0.82 + 0.14 * strokes + 0.08 * sheen
        img = _shade(c, value)
    elif kind == "tile":
        # Square tiles with per-tile tone jitter and darker grout lines.
        n = int(rng.choice([2, 4]))
        cell = size // n
        yy, xx = np.mgrid[0:size, 0:size]
        ty, tx = yy // cell, xx // cell
        jitter = rng.uniform(0.9, 1.05, (n, n))[ty, tx]
        glaze = 0.04 * (periodic_noise(rng, size, 16) - 0.5)
        value = jitter + glaze
        img = _shade(c, value)
        grout_w = max(2, size // 96)
        grout = ((yy % cell) < grout_w) | ((xx % cell) < grout_w)
        img[grout] = np.clip(0.55 * np.array([0.85, 0.84, 0.8]) + 0.1, 0, 1)
    elif kind == "stone":
        # Granite-like: multi-octave mottling plus sparse dark and light flecks.
        mottle = periodic_noise(rng, size, 8, octaves=4)
        flecks = rng.random((size, size))
        value = 0.8 + 0.25 * (mottle - 0.5)
        value = np.where(flecks < 0.04, value * 0.55, value)
        value = np.where(flecks > 0.985, value * 1.25, value)
        img = _shade(c, value)
    elif kind == "plain":
        img = np.broadcast_to(c[None, None, :3], (size, size, 3)).copy()
    else:
        raise ValueError(f"unknown texture kind {kind!r}; choose from {TEXTURE_KINDS}")
    return (np.clip(img, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def write_texture(path: Path, image: np.ndarray) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(path, compress_level=1)  # fast zlib level, as the scene images (dataset.py)
    return path
