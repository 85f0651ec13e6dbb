"""The collision check's solids: an object's closed solid at a state, built from its parts moved into the world."""

import numpy as np
import trimesh

from centerart.assets.articulated_object import moved_vertices
from centerart.assets.mesh_ops import union
from centerart.geometry.transforms import make_pose, rotation_about_axis
from centerart.scenes.collisions import object_solid
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
