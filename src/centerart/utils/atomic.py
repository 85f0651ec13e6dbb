"""Atomic output: a dataset item is either complete on disk or absent, never half-written.

Every stage writes an item into a hidden temporary sibling first and renames it into place; a rename within one
file system is atomic on POSIX, so a crash or Ctrl-C leaves only a ``.tmp-*`` entry that a later run removes.

Temporaries are owned: their names carry the writing process's pid and a hash of its host name
(``.tmp-<name>.<pid>.<host>.<random>``), and :func:`remove_stale_temporaries` deletes only those whose owner is
gone (a dead pid on this host; a day old for another host; untagged names from older versions). Two runs writing
into one folder therefore never delete each other's work in progress. When two writers finish the same item,
the last rename wins; every stage's items are deterministic for their seed, so both hold the same content.
``tempfile`` creates its files 0600 and folders 0700 whatever the umask; they are given the permissions a plain
``open`` / ``mkdir`` would (0666 / 0777 less the umask) before the rename, so a dataset one user makes can be read by
a group as the umask intends.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import re
import shutil
import socket
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any


@contextlib.contextmanager
def atomic_directory(final: Path) -> Iterator[Path]:
    """Yield a temporary directory that is renamed to ``final`` when the block finishes without error."""
    final = Path(final)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=temporary_prefix(final.name), dir=final.parent))
    try:
        yield tmp
        os.chmod(tmp, 0o777 & ~current_umask())
        _commit_directory(tmp, final)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def _commit_directory(tmp: Path, final: Path) -> None:
    """Rename ``tmp`` to ``final``. An existing ``final`` is first renamed aside (never deleted in place, so a
    reader or a concurrent writer never sees it half-removed); if another writer puts its copy in place meanwhile,
    that copy is kept (same item, same content) and ``tmp`` is dropped by the caller."""
    try:
        os.rename(tmp, final)
        return
    except OSError as err:
        if err.errno not in (errno.ENOTEMPTY, errno.EEXIST):
            raise
    aside = final.parent / f"{temporary_prefix(final.name)}old"
    with contextlib.suppress(FileNotFoundError):
        os.rename(final, aside)
    try:
        os.rename(tmp, final)
    except OSError as err:
        if err.errno not in (errno.ENOTEMPTY, errno.EEXIST):
            raise
    finally:
        shutil.rmtree(aside, ignore_errors=True)


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and an atomic rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=temporary_prefix(path.name), dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o666 & ~current_umask())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def current_umask() -> int:
    """The process umask (reading it means setting it; it is set straight back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write_json(path: Path, obj: Any) -> None:
    atomic_write_bytes(path, (json.dumps(obj, indent=2, sort_keys=False, default=_json_default) + "\n").encode())


#: A temporary of another host is taken for stale after this long (its owner's pid cannot be checked from here).
FOREIGN_STALE_SECONDS = 24 * 3600
_OWNER = re.compile(r"\.(\d+)\.([0-9a-f]{8})\.[^.]*$")


def _host_tag() -> str:
    return hashlib.sha256(socket.gethostname().encode()).hexdigest()[:8]


def temporary_prefix(name: str) -> str:
    """Prefix of a temporary for ``name`` owned by this process: ``.tmp-<name>.<pid>.<host hash>.``"""
    return f".tmp-{name}.{os.getpid()}.{_host_tag()}."


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by another user
        return True
    return True


def is_stale(entry: Path) -> bool:
    """Whether the temporary ``entry`` was left by a process that is gone (see the module docstring)."""
    owner = _OWNER.search(entry.name)
    if owner is None:
        return True  # untagged: written by an older version, which never shared a folder safely anyway
    if owner.group(2) == _host_tag():
        return not _pid_alive(int(owner.group(1)))
    try:
        return time.time() - entry.lstat().st_mtime > FOREIGN_STALE_SECONDS
    except FileNotFoundError:
        return False


def remove_stale_temporaries(folder: Path) -> int:
    """Delete the ``.tmp-*`` leftovers of interrupted runs in ``folder`` (never a live run's); returns how many."""
    folder = Path(folder)
    if not folder.is_dir():
        return 0
    count = 0
    for entry in folder.glob(".tmp-*"):
        if not is_stale(entry):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            entry.unlink(missing_ok=True)
        count += 1
    return count


def _json_default(obj: Any) -> Any:
    import numpy as np

    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")
