"""Fixtures for the scene tests: a few generated objects and two tiny rendered datasets (kitchen, single).

Rendering happens in this process (workers=1), so SAPIEN compiles its shaders once for the whole session.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes


@pytest.fixture(scope="session")
def scene_objects(tmp_path_factory) -> Path:
    """Two checked objects per category (seed 3)."""
    out = tmp_path_factory.mktemp("scene_objects")
    generate_objects(GenerateObjectsConfig(out=out, category="all", count=2, seed=3, workers=1))
    return out


@pytest.fixture(scope="session")
def kitchen_config(scene_objects):
    """The kitchen set's config (seed 5, stereo depth, tiny images) for a given output folder and scene count."""

    def make(out: Path, count: int = 2) -> GenerateScenesConfig:
        return GenerateScenesConfig(
            objects=scene_objects,
            out=out,
            layout="kitchen",
            count=count,
            views_per_scene=2,
            seed=5,
            depth="stereo",
            intrinsics="tiny",
            workers=1,
        )

    return make


@pytest.fixture(scope="session")
def kitchen_dataset(tmp_path_factory, kitchen_config) -> Path:
    out = tmp_path_factory.mktemp("kitchen")
    generate_scenes(kitchen_config(out))
    return out


@pytest.fixture(scope="session")
def single_dataset(tmp_path_factory, scene_objects) -> Path:
    out = tmp_path_factory.mktemp("single")
    cfg = GenerateScenesConfig(
        objects=scene_objects,
        out=out,
        layout="single",
        count=3,
        views_per_scene=1,
        seed=1,
        depth="analytic",
        intrinsics="tiny",
        radius_m=(1.2, 2.2),
        workers=1,
    )
    generate_scenes(cfg)
    return out
