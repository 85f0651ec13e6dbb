"""Shared fixtures: a tiny generated object set and the real PartNet-Mobility samples."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from centerart.assets.dataset import GenerateObjectsConfig, generate_objects

PARTNET_SAMPLES = Path(
    os.environ.get(
        "CENTERART_PARTNET_SAMPLES", Path(__file__).resolve().parents[2] / "shared" / "partnet-mobility-samples"
    )
)


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
