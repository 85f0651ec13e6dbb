"""Coarse-to-fine meshing against analytic SDFs (exact ground truth)."""

import numpy as np
import trimesh

from centerart.evaluation.decoder_eval import chamfer_fscore
from centerart.inference.reconstruction import MeshConfig, reconstruct, reconstruct_dense
from centerart.training.synthetic import BoxCabinet, box_sdf, sphere_sdf

#: Stated bound: at 128 cells over the box, an analytic shape is meshed within this Chamfer-L1 (mm, samples of
#: each surface to the other surface, evaluation.metrics). Measured: 0.016 mm (sphere), 0.012 mm (box).
CHAMFER_BOUND_MM = 0.5


def test_sphere_within_chamfer_bound_and_equal_to_dense():
    bounds = np.array([[-0.3] * 3, [0.3] * 3])
    field = lambda p: (sphere_sdf(p, 0.2), None)  # noqa: E731
    c2f = reconstruct(field, bounds, MeshConfig(resolution=128))
    dense = reconstruct_dense(field, bounds, 128)
    cd, fs = chamfer_fscore(c2f.mesh, trimesh.creation.icosphere(5, 0.2))
    assert cd < CHAMFER_BOUND_MM and fs > 0.99
    assert c2f.mesh.volume > 0  # outward normals
    assert abs(c2f.mesh.volume - dense.mesh.volume) < 1e-9 and len(c2f.mesh.faces) == len(dense.mesh.faces)
    assert c2f.stats["evaluated_points"] * 10 < dense.stats["evaluated_points"]


def test_box_within_chamfer_bound():
    half = np.array([0.15, 0.1, 0.2])
    bounds = np.array([-half - 0.05, half + 0.05])
    rec = reconstruct(lambda p: (box_sdf(p, half), None), bounds, MeshConfig(resolution=128))
    cd, fs = chamfer_fscore(rec.mesh, trimesh.creation.box(extents=2 * half))
    assert cd < CHAMFER_BOUND_MM and fs > 0.99


def test_articulated_cabinet_open_door_equal_to_dense():
    cab = BoxCabinet()
    bounds = np.array([[-0.2, -0.25, -0.2], [0.55, 0.25, 0.2]])
    field = lambda p: (cab.sdf(p, 0.6), None)  # noqa: E731
    c2f = reconstruct(field, bounds, MeshConfig(resolution=96))
    dense = reconstruct_dense(field, bounds, 96)
    assert len(c2f.mesh.faces) == len(dense.mesh.faces)
    assert abs(c2f.mesh.volume - dense.mesh.volume) < 1e-9
    # the door is there: mesh extends in front of the body as far as the open door
    assert c2f.mesh.bounds[1, 0] > cab.half_body[0] + 0.2


def test_empty_field_gives_empty_mesh():
    rec = reconstruct(lambda p: (np.ones(len(p)), None), np.array([[-1.0] * 3, [1.0] * 3]))
    assert len(rec.mesh.faces) == 0


def test_thin_wall_equal_to_dense():
    """A 6 mm plate between two planes of the 16^3 first lattice (37.5 mm cells here) but across one of the 32^3
    lattice (x = 18.75 mm): guided refinement from 16 alone misses it; the exhaustive 32 level keeps it. (A wall
    that also falls between 32-lattice planes can be missed, as with a 32^3 start.)"""
    bounds = np.array([[-0.3] * 3, [0.3] * 3])
    centre, half = np.array([0.0195, 0.01, -0.02]), np.array([0.003, 0.2, 0.15])
    field = lambda p: (box_sdf(p - centre, half), None)  # noqa: E731
    c2f = reconstruct(field, bounds, MeshConfig(resolution=128))
    dense = reconstruct_dense(field, bounds, 128)
    assert len(dense.mesh.faces) > 0
    assert len(reconstruct(field, bounds, MeshConfig(resolution=128, exhaustive_resolution=0)).mesh.faces) == 0
    assert len(c2f.mesh.faces) == len(dense.mesh.faces)
    assert abs(c2f.mesh.volume - dense.mesh.volume) < 1e-9


def test_points_evaluated_once_and_returned_with_values():
    bounds = np.array([[-0.3] * 3, [0.3] * 3])
    calls = []

    def field(p):
        calls.append(np.asarray(p))
        return sphere_sdf(p, 0.2), None

    rec = reconstruct(field, bounds, MeshConfig(resolution=64))
    allp = np.concatenate(calls)
    assert len(np.unique(np.round(allp, 9), axis=0)) == len(allp) == rec.stats["evaluated_points"]
    assert np.allclose(rec.sdf, sphere_sdf(rec.points, 0.2), atol=1e-6)
    assert np.abs(rec.sdf).min() < 0.01  # the surface points are among them
