"""Atomic writes give files and folders the permissions the umask asks for (tempfile alone makes them private)."""

import os
import stat

import pytest

from centerart.utils.atomic import atomic_directory, atomic_write_bytes


@pytest.mark.parametrize(("umask", "file_mode", "dir_mode"), [(0o022, 0o644, 0o755), (0o077, 0o600, 0o700)])
def test_modes_follow_the_umask(tmp_path, umask, file_mode, dir_mode):
    old = os.umask(umask)
    try:
        atomic_write_bytes(tmp_path / "a.bin", b"x")
        with atomic_directory(tmp_path / "item") as d:
            (d / "f").write_bytes(b"y")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.bin").stat().st_mode) == file_mode
    assert stat.S_IMODE((tmp_path / "item").stat().st_mode) == dir_mode
