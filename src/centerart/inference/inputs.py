"""Reading what a user has: RGB (PNG / JPG / array), depth (metres as .npy / float TIFF, or a 16-bit PNG in
millimetres with a depth scale), intrinsics (a JSON with a 3x3 ``K``, or a ROS ``camera_info`` as YAML or JSON).

Every problem is a :class:`~centerart.errors.CenterArtError` that names the input and what is wrong with it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from centerart.errors import CenterArtError
from centerart.geometry.camera import Intrinsics
from centerart.utils.npz_records import safe_reason

#: A depth image whose median valid value exceeds this many "metres" is almost surely millimetres.
MILLIMETRE_SUSPICION_M = 20.0


def read_rgb(path: Path) -> np.ndarray:
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    if not path.is_file():
        raise CenterArtError(f"--rgb {path}: file not found")
    try:
        return np.asarray(Image.open(path).convert("RGB"))
    except (UnidentifiedImageError, OSError) as err:
        raise CenterArtError(f"--rgb {path}: not a readable image ({err})") from None


def read_depth(path: Path, depth_scale: float | None = None) -> np.ndarray:
    """Depth in metres (float32, holes 0 or NaN). ``depth_scale``: metres per unit of an integer image
    (default 0.001 for 16-bit PNGs, i.e. millimetres). 8-bit images (any format) are refused: they cannot hold
    metric depth."""
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    if not path.is_file():
        raise CenterArtError(f"--depth {path}: file not found")
    try:
        if path.suffix == ".npy":
            raw = np.load(path, allow_pickle=False)
        else:
            raw = np.asarray(Image.open(path))
    except (UnidentifiedImageError, OSError, ValueError) as err:
        raise CenterArtError(f"--depth {path}: not a readable depth image ({safe_reason(err)})") from None
    if not np.issubdtype(raw.dtype, np.integer) and not np.issubdtype(raw.dtype, np.floating):
        raise CenterArtError(f"--depth {path}: holds {raw.dtype} values, expected integer or real numbers")
    if raw.dtype.itemsize == 1 and np.issubdtype(raw.dtype, np.integer):
        # 256 levels cannot hold metric depth (at millimetres they end at 0.255 m): an 8-bit depth image is almost
        # always a visualisation (normalised or colour-mapped), and reading it would give silently wrong metres.
        raise CenterArtError(
            f"--depth {path}: 8-bit depth image cannot hold metric depth; "
            "expected a 16-bit PNG in millimetres or a .npy in metres"
        )
    if raw.ndim == 3 and raw.shape[-1] == 1:
        raw = raw[..., 0]
    if raw.ndim != 2:
        raise CenterArtError(f"--depth {path}: expected a single-channel image, got shape {raw.shape}")
    if np.issubdtype(raw.dtype, np.integer):
        return raw.astype(np.float32) * np.float32(0.001 if depth_scale is None else depth_scale)
    return raw.astype(np.float32) * np.float32(1.0 if depth_scale is None else depth_scale)


def read_intrinsics(path: Path, width: int | None = None, height: int | None = None) -> Intrinsics:
    """From ``{"K": 3x3, "width", "height"}`` or a ROS camera_info (``K``/``k`` as 9 numbers, width, height).
    Width and height may come from the image instead."""
    path = Path(path)
    if not path.is_file():
        raise CenterArtError(f"--intrinsics {path}: file not found")
    try:
        text = path.read_text()
        if path.suffix in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(text)
        else:
            data = json.loads(text)
    except Exception as err:  # json / yaml raise several types
        raise CenterArtError(f"--intrinsics {path}: not readable JSON/YAML ({str(err).splitlines()[0]})") from None
    return intrinsics_from_dict(data, str(path), width, height)


def intrinsics_from_dict(data, name: str, width: int | None, height: int | None) -> Intrinsics:
    if not isinstance(data, dict):
        raise CenterArtError(f"--intrinsics {name}: expected a mapping with K, width and height")
    k = data.get("K", data.get("k", data.get("camera_matrix")))
    if isinstance(k, dict):  # OpenCV YAML style {rows, cols, data}
        k = k.get("data")
    try:
        K = np.asarray(k, dtype=float).reshape(3, 3)
    except (TypeError, ValueError):
        raise CenterArtError(f"--intrinsics {name}: no 3x3 K (keys K, k or camera_matrix)") from None
    w, h = data.get("width", width), data.get("height", height)
    if w is None or h is None:
        raise CenterArtError(f"--intrinsics {name}: width and height missing")
    if not all(isinstance(v, int | float) and not isinstance(v, bool) and v > 0 and float(v).is_integer()
               for v in (w, h)):  # fmt: skip
        raise CenterArtError(f"--intrinsics {name}: width and height must be positive integers, got {w!r}, {h!r}")
    try:
        return Intrinsics.from_matrix(K, int(w), int(h))
    except ValueError as err:  # a non-finite or singular K
        raise CenterArtError(f"--intrinsics {name}: {str(err).splitlines()[0]}") from None


def check_inputs(rgb: np.ndarray, depth: np.ndarray, camera: Intrinsics) -> np.ndarray:
    """Validate one RGB-D frame; returns depth with holes as 0. Names the problem, never a library traceback."""
    if rgb.ndim != 3 or rgb.shape[2] < 3:
        raise CenterArtError(f"rgb: expected an (H, W, 3) colour image, got shape {rgb.shape}")
    if depth.ndim != 2:
        raise CenterArtError(f"depth: expected an (H, W) image, got shape {depth.shape}")
    if rgb.shape[:2] != depth.shape:
        raise CenterArtError(f"rgb is {rgb.shape[1]}x{rgb.shape[0]} but depth is {depth.shape[1]}x{depth.shape[0]}")
    if (camera.width, camera.height) != (depth.shape[1], depth.shape[0]):
        raise CenterArtError(
            f"intrinsics are for a {camera.width}x{camera.height} image but the images are "
            f"{depth.shape[1]}x{depth.shape[0]}"
        )
    problems = camera.problems()
    if problems:
        raise CenterArtError("intrinsics: " + "; ".join(problems))
    depth = np.where(np.isfinite(depth) & (depth > 0), depth, 0.0).astype(np.float32)
    valid = depth[depth > 0]
    if valid.size == 0:
        raise CenterArtError("depth: no valid pixel (all zero or non-finite)")
    if float(np.median(valid)) > MILLIMETRE_SUSPICION_M:
        raise CenterArtError(
            f"depth: median {np.median(valid):.0f} m looks like millimetres passed as metres "
            "(use --depth-scale 0.001, or divide by 1000)"
        )
    return depth
