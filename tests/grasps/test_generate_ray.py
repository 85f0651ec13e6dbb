"""Grasp generation through a local Ray instance gives the same labels as the process pool (the cluster path)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from centerart.grasps.generate import GenerateGraspsConfig, generate_grasps
from centerart.grasps.labels import load_object_labels

TIMING_KEYS = {"seconds", "sim_seconds", "cpu_seconds"}


def _config(objects: Path, out: Path, **kw) -> GenerateGraspsConfig:
    return GenerateGraspsConfig(objects=objects, out=out, states=2, per_state=4, max_trials=30, **kw)


def _stats(out: Path) -> list[dict]:
    rows = json.loads((out / "manifest.json").read_text())["items"]
    return [{k: v for k, v in r.items() if k not in TIMING_KEYS} for r in rows]


@pytest.mark.slow  # ~17 s on 2 cores: Ray's start-up and its workers' imports
def test_ray_local_instance_gives_the_process_pool_labels(objects_dir, known_ids, tmp_path, ray_shut_down_afterwards):
    import ray

    object_id = known_ids["door_bar"]
    objects = tmp_path / "objects"
    shutil.copytree(objects_dir / object_id, objects / object_id)
    pool_out, ray_out = tmp_path / "pool", tmp_path / "ray"
    generate_grasps(_config(objects, pool_out, workers=2))
    generate_grasps(_config(objects, ray_out, workers=2, ray_address="local"))
    assert not ray.is_initialized(), "the local instance parallel_map started must be shut down"

    pool, on_ray = load_object_labels(pool_out, object_id), load_object_labels(ray_out, object_id)
    assert [lab.state_index for lab in on_ray] == [0, 1]
    assert sum(lab.count for lab in pool) > 0
    for a, b in zip(pool, on_ray, strict=True):
        np.testing.assert_array_equal(a.poses, b.poses)
        np.testing.assert_array_equal(a.displacement, b.displacement)
        np.testing.assert_array_equal(a.failed_poses, b.failed_poses)
        np.testing.assert_array_equal(a.failed_displacement, b.failed_displacement)
    assert _stats(pool_out) == _stats(ray_out)
