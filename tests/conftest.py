"""Shared fixtures: a tiny generated object set, the real PartNet-Mobility samples, and two tiny rendered scene
datasets (kitchen, single) that the scene and encoder tests share.

Rendering happens in this process (workers=1), so SAPIEN compiles its shaders once for the whole session.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes

PARTNET_SAMPLES = Path(
    os.environ.get(
        "CENTERART_PARTNET_SAMPLES", Path(__file__).resolve().parents[2] / "shared" / "partnet-mobility-samples"
    )
)


@pytest.fixture
def ray_shut_down_afterwards():
    """Leave no Ray instance behind, even when the run under test fails half-way (the grasps and recipe tests)."""
    import ray  # the `cluster` extra; scripts/setup.sh --dev installs it

    yield
    if ray.is_initialized():
        ray.shutdown()


@pytest.fixture(scope="session")
def partnet_dir() -> Path:
    if not PARTNET_SAMPLES.is_dir():
        pytest.skip(f"PartNet-Mobility samples not found at {PARTNET_SAMPLES} (set CENTERART_PARTNET_SAMPLES)")
    return PARTNET_SAMPLES


@pytest.fixture(scope="session")
def partnet_folders(partnet_dir) -> list[Path]:
    return sorted(p for p in partnet_dir.iterdir() if (p / "mobility.urdf").is_file())


@pytest.fixture(scope="session")
def generated_dir(tmp_path_factory) -> Path:
    """One checked object per category, seed 0."""
    out = tmp_path_factory.mktemp("objects")
    generate_objects(GenerateObjectsConfig(out=out, category="all", count=1, seed=0, workers=1))
    return out


@pytest.fixture(scope="session")
def generated_folders(generated_dir) -> list[Path]:
    return sorted(p for p in generated_dir.iterdir() if (p / "mobility.urdf").is_file())


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
