"""Contact sheets: grids of labelled images that a person can scan at a glance."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont


def _font(size: int):
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # very old Pillow
        return ImageFont.load_default()


def labelled(image: np.ndarray, text: str, size: int = 12, min_size: int = 7) -> np.ndarray:
    """Image with a dark caption bar at the top; a caption too long for the image gets a smaller font (down to
    ``min_size`` px) rather than running past the edge into the next tile."""
    img = Image.fromarray(image)
    draw = ImageDraw.Draw(img)
    font = _font(size)
    while size > min_size and draw.textlength(text, font=font) > img.width - 8:
        size -= 1
        font = _font(size)
    draw.rectangle([0, 0, img.width, size + 6], fill=(20, 20, 20))
    draw.text((4, 2), text, fill=(240, 240, 240), font=font)
    return np.asarray(img)


def titled(image: np.ndarray, text: str, size: int = 14) -> np.ndarray:
    """Image with a white title bar added above it (the image grows by the bar's height)."""
    bar = Image.new("RGB", (image.shape[1], size + 10), (255, 255, 255))
    ImageDraw.Draw(bar).text((6, 4), text, fill=(20, 20, 20), font=_font(size))
    return np.concatenate([np.asarray(bar), image[..., :3]], axis=0)


def grid(rows: Sequence[Sequence[np.ndarray]], pad: int = 4, background=(255, 255, 255)) -> np.ndarray:
    """Tile rows of equally sized images into one image."""
    h, w = rows[0][0].shape[:2]
    ncols = max(len(r) for r in rows)
    out = np.full((len(rows) * (h + pad) + pad, ncols * (w + pad) + pad, 3), background, np.uint8)
    for i, row in enumerate(rows):
        for j, img in enumerate(row):
            y, x = pad + i * (h + pad), pad + j * (w + pad)
            out[y : y + h, x : x + w] = img[..., :3]
    return out


def save_png(image: np.ndarray, path: Path) -> Path:
    """Write ``image`` (format from the suffix, PNG by default) to a temporary sibling and rename it into place,
    so a reader never sees half a picture."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".tmp-{path.name}")
    Image.fromarray(image).save(tmp, format=Image.registered_extensions().get(path.suffix.lower(), "PNG"))
    tmp.replace(path)
    return path
