"""Output folders shared safely: checked before anything is written, locked while a run updates shared files.

Several runs may write into one folder at once (two categories of objects, a rerun started by mistake): items are
written atomically by their own process (:mod:`centerart.utils.atomic`), and the few files every run rewrites
(``manifest.json``) are updated under an exclusive lock (``fcntl.flock`` on ``<folder>/.lock``), which the kernel
releases when its holder dies, so a killed run never leaves a folder locked.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from collections.abc import Iterator
from pathlib import Path

from centerart.errors import CenterArtError
from centerart.utils.atomic import remove_stale_temporaries

LOCK_NAME = ".lock"


def check_output_folder(path: Path, option: str = "--out") -> Path:
    """Refuse an output folder that is an existing file (or under one); nothing is created."""
    path = Path(path)
    for p in (path, *path.parents):
        if p.exists() or p.is_symlink():
            if not p.is_dir():
                what = "is an existing file" if p == path else f"is inside {p}, which is a file"
                raise CenterArtError(f"{option} {path}: {what}; give a folder")
            return path
    return path


def output_folder(path: Path, option: str = "--out") -> Path:
    """Create the output folder (after :func:`check_output_folder`) and remove stale temporaries in it."""
    path = check_output_folder(path, option)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise CenterArtError(f"{option} {path}: cannot create the folder ({err.strerror})") from None
    remove_stale_temporaries(path)
    return path


@contextlib.contextmanager
def folder_lock(folder: Path, blocking: bool = True) -> Iterator[None]:
    """Hold the folder's exclusive lock for the block. ``blocking=False``: raise :class:`FolderBusy` at once when
    another process holds it."""
    path = Path(folder) / LOCK_NAME
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
        except BlockingIOError:
            raise FolderBusy(folder) from None
        yield
    finally:
        os.close(fd)  # closing releases the lock


class FolderBusy(CenterArtError):
    """Another run holds the folder's lock."""

    def __init__(self, folder: Path):
        super().__init__(f"{folder}: another run is writing into this folder; wait for it or use another --out")
