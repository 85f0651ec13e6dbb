"""Fixtures for the grasp stage: a few generated objects with known handles (the real samples: tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from centerart.assets.dataset import GenerateObjectsConfig, generate_objects

#: With seed 0: dishwasher_0001 has a bar handle on its bottom-hinged door; storage_furniture_0003's target is a
#: drawer with a bar handle; microwave_0001 has a U handle on a side-hinged door.
DOOR_BAR = "dishwasher_0001"
DRAWER_BAR = "storage_furniture_0003"
DOOR_U = "microwave_0001"


@pytest.fixture(scope="session")
def objects_dir(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("grasp_objects")
    generate_objects(GenerateObjectsConfig(out=out, category="dishwasher", count=2, seed=0, workers=1))
    generate_objects(GenerateObjectsConfig(out=out, category="microwave", count=2, seed=0, workers=1))
    generate_objects(GenerateObjectsConfig(out=out, category="storage_furniture", count=4, seed=0, workers=1))
    (out / "manifest.json").unlink()
    return out


@pytest.fixture(scope="session")
def known_ids() -> dict[str, str]:
    return {"door_bar": DOOR_BAR, "drawer_bar": DRAWER_BAR, "door_u": DOOR_U}
