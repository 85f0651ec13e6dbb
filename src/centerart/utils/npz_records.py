"""Per-(object, state) dataset records stored as ``.npz``: scalar metadata plus float32 arrays, written atomically.

Grasp labels and SDF samples share this layout (``<folder>/<object_id>/state_<k:02d>.npz``); each record is a
dataclass whose fields are ``str``/``int``/``float`` scalars or numpy arrays. A record class may declare
``SHAPES`` (field -> shape, with letters for sizes that must agree between fields, e.g. ``("N", 4, 4)``) and
``NO_NAN`` / ``FINITE`` (fields whose values must have no NaN / be finite); :func:`load_record` checks them, so a
damaged or hand-edited file is one clear error naming the file and the field instead of a crash deep in a stage.
"""

from __future__ import annotations

import dataclasses
import io
import math
import zipfile
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from centerart.errors import CenterArtError
from centerart.utils.atomic import atomic_write_bytes

T = TypeVar("T")
# Field annotations are strings (``from __future__ import annotations`` in the record modules).
SCALAR_TYPES = {"str": str, "int": int, "float": float}


def state_file(folder: Path, object_id: str, state_index: int) -> Path:
    return Path(folder) / object_id / f"state_{state_index:02d}.npz"


def save_record(path: Path, record: Any, compressed: bool = False, shapes: dict[str, tuple] | None = None) -> Path:
    """Write a record dataclass: scalars as 0-d arrays, arrays as float32 (reshaped where ``shapes`` says)."""
    arrays = {}
    for f in dataclasses.fields(record):
        value = getattr(record, f.name)
        if f.type in SCALAR_TYPES:
            arrays[f.name] = np.array(value)
        else:
            array = np.asarray(value, np.float32)
            arrays[f.name] = array.reshape(shapes[f.name]) if shapes and f.name in shapes else array
    buf = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(buf, **arrays)
    atomic_write_bytes(path, buf.getvalue())
    return Path(path)


def load_record(cls: type[T], path: Path, what: str, dtype: Any = None) -> T:
    """Read a record written by :func:`save_record`, checked against the class's ``SHAPES`` / ``NO_NAN`` /
    ``FINITE``; arrays are cast to ``dtype`` when given.

    Raises:
        CenterArtError: naming the file when it is missing, truncated, lacks a field or holds a wrong value.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            values = {f.name: _field(f, data[f.name]) for f in dataclasses.fields(cls)}
    except (OSError, KeyError, ValueError, TypeError, EOFError, zipfile.BadZipFile) as err:
        raise CenterArtError(f"{path}: not a readable {what} file ({safe_reason(err)})") from None
    problem = record_problem(cls, values)
    if problem:
        raise CenterArtError(f"{path}: not a valid {what} file ({problem})")
    if dtype is not None:
        values = {k: v.astype(dtype) if isinstance(v, np.ndarray) else v for k, v in values.items()}
    return cls(**values)


def safe_reason(err: Exception) -> str:
    """A one-line reason for a failed array read. numpy's message for pickled content advises
    ``allow_pickle=True``, which must never be followed for an untrusted file: that advice is not repeated."""
    text = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    if "pickle" in text.lower():
        return "holds pickled Python objects or is not a numpy file (refused: only plain arrays are read)"
    return text


def _field(f: dataclasses.Field, raw: np.ndarray):
    if f.type in SCALAR_TYPES:
        if raw.shape != ():
            raise ValueError(f"{f.name} should be one value, got shape {raw.shape}")
        return SCALAR_TYPES[f.type](raw)
    if not np.issubdtype(raw.dtype, np.number) or np.issubdtype(raw.dtype, np.complexfloating):
        raise ValueError(f"{f.name} holds {raw.dtype} values, expected real numbers")
    return raw


def record_problem(cls: type, values: dict[str, Any]) -> str | None:
    """What is wrong with a record's values according to its class's checks, or None."""
    sizes: dict[str, int] = {}
    for name, spec in getattr(cls, "SHAPES", {}).items():
        shape = np.shape(values[name])
        if len(shape) != len(spec):
            return f"{name} has shape {shape}, expected {spec}"
        for got, want in zip(shape, spec, strict=True):
            if isinstance(want, str):
                want = sizes.setdefault(want, got)
            if got != want:
                return f"{name} has shape {shape}, expected {spec} (letters must agree between fields)"
    for name in getattr(cls, "FINITE", ()):
        if not np.isfinite(values[name]).all():
            return f"{name} holds NaN or infinite values"
    for name in getattr(cls, "NO_NAN", ()):
        if np.isnan(values[name]).any():
            return f"{name} holds NaN values"
    for name, value in values.items():
        if isinstance(value, float) and not math.isfinite(value):
            return f"{name} is {value}"
    return None
