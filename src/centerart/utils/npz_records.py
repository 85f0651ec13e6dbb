"""Per-(object, state) dataset records stored as ``.npz``: scalar metadata plus float32 arrays, written atomically.

Grasp labels and SDF samples share this layout (``<folder>/<object_id>/state_<k:02d>.npz``); each record is a
dataclass whose fields are ``str``/``int``/``float`` scalars or numpy arrays.
"""

from __future__ import annotations

import dataclasses
import io
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
    """Read a record written by :func:`save_record`; arrays are cast to ``dtype`` when given.

    Raises:
        CenterArtError: naming the file when it is missing, truncated or lacks a field.
    """
    path = Path(path)
    try:
        with np.load(path) as data:
            values = {}
            for f in dataclasses.fields(cls):
                raw = data[f.name]
                if f.type in SCALAR_TYPES:
                    values[f.name] = SCALAR_TYPES[f.type](raw)
                else:
                    values[f.name] = raw.astype(dtype) if dtype is not None else raw
            return cls(**values)
    except (OSError, KeyError, ValueError) as err:
        raise CenterArtError(f"{path}: not a readable {what} file ({err})") from None
