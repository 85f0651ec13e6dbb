"""Object fingerprints: the same content under another name is the same object; changed content is not."""

from __future__ import annotations

import json
import shutil

import pytest

from centerart.assets.fingerprint import fingerprint_folders, is_current, object_fingerprint
from centerart.errors import AssetError


def test_fingerprint_follows_content_not_name(generated_folders, tmp_path):
    src = generated_folders[0]
    copy = tmp_path / "renamed_object"
    shutil.copytree(src, copy)
    assert object_fingerprint(copy) == object_fingerprint(src)
    assert object_fingerprint(generated_folders[1]) != object_fingerprint(src)
    assert object_fingerprint(copy).startswith("v2:") and is_current(object_fingerprint(copy))
    meta = copy / "meta.json"
    blob = json.loads(meta.read_text())
    # How it was made is not what it is: another code version, or another layout of the file, is the same object.
    blob["generator"]["version"] = "9.9.9+gdeadbeef"
    meta.write_text(json.dumps(blob, indent=4))
    assert object_fingerprint(copy) == object_fingerprint(src)
    blob["generator"]["seed"] = blob["generator"]["seed"] + 1  # what made the geometry does count
    meta.write_text(json.dumps(blob))
    assert object_fingerprint(copy) != object_fingerprint(src)
    assert fingerprint_folders({"a": copy, "gone": tmp_path / "missing"})["gone"] is None


def test_first_scheme_fingerprints_are_not_current():
    assert not is_current("e246807b7cdb2e7abdcfe8938d6a67d42c09158428d51c0e2c997fa87cafc512") and not is_current(None)


def test_a_folder_without_urdf_is_refused(tmp_path):
    with pytest.raises(AssetError, match=r"no mobility\.urdf"):
        object_fingerprint(tmp_path)
