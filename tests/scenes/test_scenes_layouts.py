"""Layouts: no interpenetration (exact mesh check, which can fail), kitchen rules, determinism, JSON round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest

from centerart.errors import CenterArtError
from centerart.scenes.collisions import check_scene
from centerart.scenes.dataset import GenerateScenesConfig, asset_index, sample_checked_scene
from centerart.scenes.description import SceneDescription
from centerart.scenes.layouts import TALL_M


@pytest.fixture(scope="module")
def entries(scene_objects):
    return asset_index(scene_objects)


def _cfg(scene_objects, tmp_path, **kw):
    return GenerateScenesConfig(objects=scene_objects, out=tmp_path, intrinsics="tiny", **kw)


def test_kitchens_have_no_interpenetration(scene_objects, entries, tmp_path):
    cfg = _cfg(scene_objects, tmp_path, layout="kitchen", seed=11)
    for i in range(6):
        scene, objects, _ = sample_checked_scene(cfg, i, entries)
        report = check_scene(scene, objects)
        assert report.ok, report.problems
        assert 2 <= len(scene.objects) <= 5
        micro = [o for o in scene.objects if o.category == "microwave"]
        assert len(micro) <= 1
        assert all(o.support == "counter" for o in micro)
        # Tall objects stand only at the ends of the floor row.
        floor = sorted((o for o in scene.objects if o.support == "floor"), key=lambda o: o.world_T_object[1][3])
        heights = {e.object_id: e.height for e in entries}
        for o in floor[1:-1]:
            assert heights[o.object_id] <= TALL_M


def test_collision_check_detects_overlap(scene_objects, entries, tmp_path):
    cfg = _cfg(scene_objects, tmp_path, layout="kitchen", seed=11)
    scene, objects, _ = sample_checked_scene(cfg, 0, entries)
    floor = [k for k, o in enumerate(scene.objects) if o.support == "floor"]
    a, b = floor[0], floor[1]
    # Move object b onto object a.
    scene.objects[b].world_T_object[1][3] = scene.objects[a].world_T_object[1][3]
    report = check_scene(scene, objects)
    assert not report.ok
    assert any(scene.objects[b].name in p for p in report.problems)


def test_layout_is_deterministic_and_round_trips(scene_objects, entries, tmp_path):
    cfg = _cfg(scene_objects, tmp_path, layout="kitchen", seed=4)
    a, _, _ = sample_checked_scene(cfg, 3, entries)
    b, _, _ = sample_checked_scene(cfg, 3, entries)
    assert a.to_dict() == b.to_dict()
    c, _, _ = sample_checked_scene(_cfg(scene_objects, tmp_path, layout="kitchen", seed=5), 3, entries)
    assert a.to_dict() != c.to_dict()
    path = tmp_path / "scene.json"
    a.save(path)
    assert SceneDescription.load(path).to_dict() == json.loads(path.read_text())
    assert SceneDescription.load(path).to_dict() == a.to_dict()


def test_cameras_on_the_shell(scene_objects, entries, tmp_path):
    cfg = _cfg(scene_objects, tmp_path, layout="single", seed=2, views_per_scene=5, radius_m=(1.0, 2.5))
    scene, _, _ = sample_checked_scene(cfg, 0, entries)
    for k in range(5):
        T = scene.camera_pose(k)
        np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-9)
        assert np.linalg.det(T[:3, :3]) == pytest.approx(1.0)
        assert T[2, 3] > 0.1 and T[0, 3] > 0.5  # above the floor, in the room in front of the wall
        assert T[:3, 2] @ np.array([0, 0, 1.0]) < 0  # looking down


def test_bad_scene_file_is_a_clear_error(tmp_path):
    bad = tmp_path / "scene.json"
    bad.write_text("{not json")
    with pytest.raises(CenterArtError, match="malformed JSON"):
        SceneDescription.load(bad)
    bad.write_text(json.dumps({"format_version": 1, "scene_id": "x"}))
    with pytest.raises(CenterArtError, match="not a valid scene description"):
        SceneDescription.load(bad)


def test_scene_objects_keep_the_default_frame_when_other_joints_are_held_open(scene_objects):
    from centerart.assets.articulated_object import ArticulatedObject
    from centerart.scenes.description import load_object_in_default_frame

    for folder in sorted(p for p in scene_objects.iterdir() if p.is_dir()):
        default = ArticulatedObject.load(folder)
        if not default.held_states:
            continue
        name = next(iter(default.held_states))
        j = default.joints[name]
        opened = load_object_in_default_frame(folder, held_states={name: j.upper})
        np.testing.assert_allclose(opened.canonical_T_base, default.canonical_T_base)
        assert opened.held_states[name] == j.upper
        # The opened joint's link moved, the frame did not.
        assert not np.allclose(opened.link_poses(0.0)[j.child], default.link_poses(0.0)[j.child])
        return
    pytest.skip("no test object with a second movable joint")
