"""Checkpoint files written and read one way: a plain dict saved with ``torch.save`` and written atomically,
read back with ``torch.load(weights_only=True)`` (no code runs), its ``format`` and ``version`` checked.

Errors name the file and say what is wrong in one line. Torch's own message for a damaged file runs to several
lines and advises ``weights_only=False``, which must never be followed for an untrusted file, so only the error's
type is kept.
"""

from __future__ import annotations

import io
from pathlib import Path

import torch

from centerart.errors import CenterArtError


def write_blob(path: Path, blob: dict) -> Path:
    from centerart.utils.atomic import atomic_write_bytes

    buf = io.BytesIO()
    torch.save(blob, buf)
    atomic_write_bytes(Path(path), buf.getvalue())
    return Path(path)


def read_blob(path: Path, fmt: str, version: int, kind: str) -> dict:
    """The checkpoint dict at ``path``; ``kind`` ("decoder", "encoder") names it in errors."""
    path = Path(path)
    if not path.is_file():
        raise CenterArtError(f"{path}: {kind} checkpoint file not found")
    try:
        blob = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:  # torch raises many types for truncated, corrupt or foreign files
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise CenterArtError(
            f"{path}: not a readable {kind} checkpoint (damaged or not a torch file: {first})"
        ) from None
    if not isinstance(blob, dict) or blob.get("format") != fmt:
        raise CenterArtError(f"{path}: not a centerart {kind} checkpoint (expected format {fmt!r})")
    if blob.get("version") != version:
        raise CenterArtError(
            f"{path}: {kind} checkpoint version {blob.get('version')} unsupported (expected {version})"
        )
    return blob
