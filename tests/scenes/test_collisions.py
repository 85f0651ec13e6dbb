"""The collision check: an object's closed solid at a state, built from its parts moved into the world, and the
bounding boxes that let pairs apart skip the boolean without changing the report."""

from pathlib import Path

import numpy as np
import trimesh

from centerart.assets.articulated_object import moved_vertices
from centerart.assets.mesh_ops import union
from centerart.geometry.transforms import make_pose, rotation_about_axis
from centerart.scenes.collisions import (
    AABB_GAP_M,
    PENETRATION_TOL_M3,
    box_solid,
    boxes_apart,
    check_scene,
    check_states,
    object_box,
    object_solid,
)
from centerart.scenes.dataset import GenerateScenesConfig, asset_index, sample_checked_scene
from centerart.scenes.description import cached_object


def test_moved_vertices_match_trimesh_exactly():
    """Bit-identical to Trimesh.apply_transform (so layouts do not change), identity shortcut included."""
    mesh = trimesh.creation.icosphere(subdivisions=2)
    pose = make_pose(rotation_about_axis([0.3, -1.0, 0.2], 0.7), [0.1, -2.0, 0.35])
    for p in (pose, np.eye(4), np.eye(4) + 1e-10):
        moved = mesh.copy()
        moved.apply_transform(p)
        assert np.array_equal(moved_vertices(mesh, p), moved.vertices)


def test_object_solid_is_the_union_of_the_moved_parts(scene_objects):
    """Volume and bounds of the solid equal those of the trimesh union of parts(q) moved into the world, at both
    ends of the joint range (the open door sweeps out of the closed box)."""
    obj = cached_object(scene_objects / "oven_0000")
    world_T_object = make_pose(rotation_about_axis([0, 0, 1], 0.4), [1.0, 2.0, 0.1])
    for q in obj.joint_range:
        reference = union([p.mesh for p in obj.parts(q)])
        reference.apply_transform(world_T_object)
        solid = object_solid(obj, q, world_T_object)
        assert abs(solid.volume() - reference.volume) < 1e-6 * reference.volume  # float32 vertices in manifold3d
        np.testing.assert_allclose(np.reshape(solid.bounding_box(), (2, 3)), reference.bounds, atol=1e-6)
    closed, opened = (object_solid(obj, q, world_T_object).bounding_box() for q in obj.joint_range)
    assert not np.allclose(closed, opened)


def test_object_box_contains_the_solid(scene_objects, partnet_folders):
    """The bounds that decide which pairs skip the boolean contain the solid's bounds: a generated object (closed
    parts) and a real one (hulls of its soup parts), turned about z, at both ends of the range."""
    world_T_object = make_pose(rotation_about_axis([0, 0, 1], 0.7), [0.5, -1.0, 0.2])
    for obj in (cached_object(scene_objects / "oven_0000"), cached_object(partnet_folders[0])):
        for q in obj.joint_range:
            lo, hi = np.reshape(object_solid(obj, q, world_T_object).bounding_box(), (2, 3))
            box = object_box(obj, q, world_T_object)
            assert np.all(box[0] <= lo + 1e-6) and np.all(box[1] >= hi - 1e-6)


def test_boxes_apart_only_beyond_the_gap():
    a = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    for shift, apart in ((1.0, False), (1.0 + AABB_GAP_M / 2, False), (1.0 + 2 * AABB_GAP_M, True), (-0.5, False)):
        b = a + np.array([0.0, shift, 0.0])
        assert boxes_apart(a, b) is apart and boxes_apart(b, a) is apart


def _brute_force(scene, objects):
    """Every pair through the boolean: the check as it was before pairs apart were skipped."""
    poses = [scene.object_pose(i) for i in range(len(objects))]
    room = [(b.name, box_solid(np.asarray(b.world_T_box), b.half_size)) for b in scene.boxes]
    worst, problems = 0.0, []
    for i, (obj, spec) in enumerate(zip(objects, scene.objects, strict=True)):
        for q in check_states(obj, spec.joint_state):
            solid = object_solid(obj, q, poses[i])
            others = [(o.name, object_solid(objects[j], o.joint_state, poses[j])) for j, o in enumerate(scene.objects)]
            for name, other in [x for j, x in enumerate(others) if j != i] + room:
                vol = float((solid ^ other).volume())
                worst = max(worst, vol)
                if vol > PENETRATION_TOL_M3:
                    problems.append(
                        f"{spec.name} ({spec.object_id}) at q={q:.3f} overlaps {name} by {vol * 1e6:.2f} cm^3"
                    )
    return worst, problems


def test_check_scene_equals_every_pair_through_the_boolean(scene_objects):
    """Kitchens with their objects shaken into each other, the walls and the floor: the same verdict, worst
    overlap and problem list (in order) as running the boolean on every pair."""
    entries = asset_index(scene_objects)
    cfg = GenerateScenesConfig(objects=scene_objects, out=Path("."), layout="kitchen", seed=2, intrinsics="tiny")
    failing = 0
    for index in range(3):
        scene, objects, _ = sample_checked_scene(cfg, index, entries)
        rng = np.random.default_rng(index)
        for spread in (0.0, 0.05, 0.15):
            for spec in scene.objects:
                pose = np.asarray(spec.world_T_object)
                pose[:3, 3] += rng.normal(0.0, spread, 3)
                spec.world_T_object = pose.tolist()
            report = check_scene(scene, objects)
            worst, problems = _brute_force(scene, objects)
            assert (report.ok, report.worst_m3, report.problems) == (not problems, worst, problems)
            failing += not report.ok
    assert failing >= 3
