"""Object fingerprints: the same content under another name is the same object; changed content is not."""

from __future__ import annotations

import shutil

import pytest

from centerart.assets.fingerprint import fingerprint_folders, object_fingerprint
from centerart.errors import AssetError


def test_fingerprint_follows_content_not_name(generated_folders, tmp_path):
    src = generated_folders[0]
    copy = tmp_path / "renamed_object"
    shutil.copytree(src, copy)
    assert object_fingerprint(copy) == object_fingerprint(src)
    assert object_fingerprint(generated_folders[1]) != object_fingerprint(src)
    meta = copy / "meta.json"
    meta.write_text(meta.read_text().replace("}", " }", 1))
    assert object_fingerprint(copy) != object_fingerprint(src)
    assert fingerprint_folders({"a": copy, "gone": tmp_path / "missing"})["gone"] is None


def test_a_folder_without_urdf_is_refused(tmp_path):
    with pytest.raises(AssetError, match=r"no mobility\.urdf"):
        object_fingerprint(tmp_path)
