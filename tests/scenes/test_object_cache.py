"""Assets memoised per process for scene generation: each call gets its own copy, and a rewritten object reloads."""

import os
import shutil

import numpy as np

from centerart.scenes.description import cached_object, load_object_in_default_frame


def test_each_call_gets_a_copy_whose_fields_it_may_rebind(scene_objects):
    path = scene_objects / "oven_0000"
    a, b = cached_object(path), cached_object(path)
    assert a is not b and a.visual_parts is b.visual_parts  # meshes shared, loaded once
    a.canonical_T_base = np.eye(4) * 2.0
    assert not np.allclose(cached_object(path).canonical_T_base, a.canonical_T_base)


def test_held_states_keep_the_default_frame_as_before(scene_objects):
    path = scene_objects / "refrigerator_0000"
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
