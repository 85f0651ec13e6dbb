"""Checkpoint files written and read one way: a plain dict saved with ``torch.save`` and written atomically,
read back with ``torch.load(weights_only=True)`` (no code runs), its ``format`` and ``version`` checked.

Errors name the file and say what is wrong in one line. Torch's own message for a damaged file runs to several
lines and advises ``weights_only=False``, which must never be followed for an untrusted file, so none of its text is
kept: only the error's type.
"""

from __future__ import annotations

import hashlib
import io
from pathlib import Path

import torch

from centerart.errors import CenterArtError


def file_sha256(path: Path) -> str:
    """The SHA-256 of a file's bytes (hex): how reports and linked files name the exact checkpoint they used."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def write_blob(path: Path, blob: dict) -> Path:
    from centerart.utils.atomic import atomic_write_bytes

    buf = io.BytesIO()
    torch.save(blob, buf)
    atomic_write_bytes(Path(path), buf.getvalue())
    return Path(path)


def load_torch_file(path: Path, kind: str):
    """``torch.load(path, weights_only=True)`` on the CPU; a damaged, truncated or foreign file is one
    :class:`CenterArtError` line that calls it not a valid centerart ``kind`` checkpoint."""
    path = Path(path)
    if not path.is_file():
        raise CenterArtError(f"{path}: {kind} checkpoint file not found")
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:  # torch raises many types for truncated, corrupt or foreign files
        raise CenterArtError(
            f"{path}: not a readable {kind} checkpoint (not a valid centerart checkpoint: damaged, truncated or "
            f"not a torch file; {type(err).__name__})"
        ) from None


def read_blob(path: Path, fmt: str, version: int, kind: str) -> dict:
    """The checkpoint dict at ``path``; ``kind`` ("decoder", "encoder") names it in errors."""
    blob = load_torch_file(path, kind)
    if not isinstance(blob, dict) or blob.get("format") != fmt:
        raise CenterArtError(
            f"{path}: not a centerart {kind} checkpoint (not a valid centerart checkpoint: expected format {fmt!r})"
        )
    if blob.get("version") != version:
        raise CenterArtError(
            f"{path}: {kind} checkpoint version {blob.get('version')} unsupported (expected {version})"
        )
    return blob


def check_fields(blob: dict, path: Path, kind: str, fields: dict[str, type]) -> None:
    """Every key of ``fields`` is in ``blob`` with that type; else one line naming the file and the field."""
    for key, typ in fields.items():
        if not isinstance(blob.get(key), typ):
            found = "missing" if key not in blob else f"a {type(blob[key]).__name__}"
            raise CenterArtError(
                f"{path}: not a valid centerart {kind} checkpoint (field {key!r} is {found}, expected {typ.__name__})"
            )
