"""Assets memoised per process for scene generation: each call gets its own copy, and a rewritten object reloads."""

import os
import shutil

import numpy as np
import pytest

from centerart.scenes.description import cached_object, load_object_in_default_frame


def test_each_call_gets_a_copy_whose_fields_it_may_rebind(scene_objects):
    path = scene_objects / "oven_0000"
    a, b = cached_object(path), cached_object(path)
    assert a is not b and a.visual_parts is b.visual_parts  # meshes shared, loaded once
    a.canonical_T_base = np.eye(4) * 2.0
    assert not np.allclose(cached_object(path).canonical_T_base, a.canonical_T_base)


def test_held_states_keep_the_default_frame_as_before(scene_objects):
    path = scene_objects / "storage_furniture_0000"  # four drawers and a door held besides its target door
    obj = load_object_in_default_frame(path)
    held = {name: 0.5 * (j.lower + j.upper) for name, j in obj.joints.items() if name != obj.target_joint and j.upper}
    moved = load_object_in_default_frame(path, obj.target_joint, obj.scale, held)
    np.testing.assert_allclose(moved.canonical_T_base, obj.canonical_T_base)


def test_an_object_rewritten_on_disk_is_loaded_again(scene_objects, tmp_path):
    folder = tmp_path / "obj"
    shutil.copytree(scene_objects / "microwave_0000", folder)
    first = cached_object(folder)
    urdf = folder / "mobility.urdf"
    urdf.write_text(urdf.read_text().replace("<robot ", "<robot  ", 1))
    stamp = urdf.stat().st_mtime_ns + 10**9
    os.utime(urdf, ns=(stamp, stamp))
    assert cached_object(folder).visual_parts is not first.visual_parts


def test_held_states_are_the_same_as_loading_with_them(scene_objects):
    """with_held_states (no reload) gives what ArticulatedObject.load with held_states gives, in the default frame;
    a name that is not a non-target movable joint is still refused, naming the URDF."""
    from centerart.assets.articulated_object import ArticulatedObject
    from centerart.errors import AssetError

    path = scene_objects / "storage_furniture_0000"  # four drawers and a door held besides its target door
    obj = load_object_in_default_frame(path)
    held = {name: 0.5 * (j.lower + j.upper) for name, j in obj.joints.items() if name != obj.target_joint and j.upper}
    assert held
    fast = load_object_in_default_frame(path, obj.target_joint, obj.scale, held)
    loaded = ArticulatedObject.load(path, obj.target_joint, obj.scale, held)
    assert fast.held_states == loaded.held_states and fast.held_states != obj.held_states
    q = obj.joint_range[1]
    for link, pose in loaded.link_poses(q).items():  # same kinematics once both sit in the same frame
        shift = obj.canonical_T_base @ np.linalg.inv(loaded.canonical_T_base)
        np.testing.assert_allclose(fast.link_poses(q)[link], shift @ pose, atol=1e-12)
    with pytest.raises(AssetError, match=r"mobility\.urdf.*not a non-target movable joint"):
        obj.with_held_states({"no_such_joint": 0.1})
