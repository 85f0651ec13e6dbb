"""Signed distances and the sign methods on analytic shapes (closed-form SDFs)."""

from __future__ import annotations

import numpy as np
import trimesh

from centerart.assets.mesh_ops import from_manifold, to_manifold
from centerart.sdf.sampling import SamplingConfig, sample_points, signed_distance
from centerart.sdf.signs import (
    encloses_volume,
    flood_fill_inside,
    flood_pitch,
    opening_targets,
    ray_escape_inside,
    ray_parity_inside,
    raycasting_scene,
    soup_escape_inside,
    soup_flood_fill_inside,
    winding_number,
)
from centerart.sdf.surface import ObjectSurface, dedupe_soup

HALF = np.array([0.3, 0.2, 0.1])


def box_sdf(p: np.ndarray, half: np.ndarray = HALF) -> np.ndarray:
    q = np.abs(p) - half
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)


def test_box_sdf_matches_closed_form():
    box = trimesh.creation.box(extents=2 * HALF)
    rng = np.random.default_rng(0)
    cfg = SamplingConfig(check_points=2_000)
    pts = sample_points(box, 20_000, cfg, rng)
    res = signed_distance(ObjectSurface(box, True), pts, cfg, rng)
    assert res.points.shape == (20_000, 3) and res.sdf.dtype == np.float32
    np.testing.assert_allclose(res.sdf, box_sdf(res.points.astype(float)), atol=1e-5)
    assert res.sign_agreement == 1.0
    # The mix: near points cluster at the surface, uniform ones fill the padded bounds.
    near = np.abs(res.sdf[:9000])
    assert np.median(near) < 0.006
    assert (res.sdf < 0).mean() > 0.2


def test_sphere_sdf_and_methods_agree():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.25)
    rng = np.random.default_rng(1)
    pts = rng.uniform(-0.4, 0.4, (4000, 3))
    r = np.linalg.norm(pts, axis=1)
    keep = np.abs(r - 0.25) > 0.003  # the icosphere deviates from the sphere by < 1 mm
    pts, r = pts[keep], r[keep]
    scene = raycasting_scene(sphere)
    truth = r < 0.25
    assert (ray_parity_inside(scene, pts) == truth).all()
    assert ((winding_number(sphere, pts) > 0.5) == truth).all()
    assert (ray_escape_inside(scene, pts) == truth).all()
    inside = flood_fill_inside(sphere, scene, pts, pts.min(0) - 0.05, pts.max(0) + 0.05, pitch=0.9 / 96)
    assert (inside == truth).mean() > 0.999
    res = signed_distance(ObjectSurface(sphere, True), pts, SamplingConfig(check_points=1000), rng)
    np.testing.assert_allclose(res.sdf, r - 0.25, atol=1.5e-3)


def _double_sided(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """A PartNet-style soup of ``mesh``: every face drawn twice (both orientations), vertices unmerged, then
    deduplicated as :func:`object_surface` does."""
    tri = mesh.vertices[mesh.faces]
    both = np.concatenate([tri, tri[:, ::-1]])
    return dedupe_soup(trimesh.Trimesh(both.reshape(-1, 3), np.arange(len(both) * 3).reshape(-1, 3), process=False))


def test_soup_of_double_sided_box_signs_like_a_solid():
    """A PartNet-style soup: every box face drawn twice (both orientations), vertices unmerged."""
    clean = _double_sided(trimesh.creation.box(extents=2 * HALF))
    assert len(clean.faces) == 12
    rng = np.random.default_rng(2)
    cfg = SamplingConfig(check_points=5_000, soup_shell=0.002)
    pts = sample_points(clean, 20_000, cfg, rng)
    res = signed_distance(ObjectSurface(clean, False, [clean]), pts, cfg, rng)
    truth = box_sdf(res.points.astype(float)) - 0.002
    decided = np.abs(truth) > 0.001
    assert ((res.sdf < 0) == (truth < 0))[decided].mean() > 0.995
    np.testing.assert_allclose(np.abs(res.sdf + 0.002), np.abs(truth + 0.002), atol=1e-5)
    assert res.sign_agreement >= 0.99


def test_open_sheet_gets_a_shell():
    """An open square sheet has no inside; the soup shell makes its field negative within 2 mm only."""
    sheet = trimesh.Trimesh([[0, -0.2, -0.2], [0, 0.2, -0.2], [0, 0.2, 0.2], [0, -0.2, 0.2]], [[0, 1, 2], [0, 2, 3]])
    pts = np.array([[0.001, 0, 0], [-0.001, 0.05, 0], [0.01, 0, 0], [-0.05, 0, 0.1], [0.3, 0.3, 0.3]])
    cfg = SamplingConfig(check_points=5, soup_shell=0.002)
    res = signed_distance(ObjectSurface(sheet, False, [sheet]), pts, cfg, np.random.default_rng(0))
    np.testing.assert_allclose(
        res.sdf, [-0.001, -0.001, 0.008, 0.048, np.linalg.norm([0.3, 0.1, 0.1]) - 0.002], atol=1e-5
    )


def _board(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return _double_sided(trimesh.creation.box(bounds=[lo, hi]))


def test_closed_cabinet_soup_keeps_its_cavity_empty():
    """Five 2 cm boards and a closed door, each a separate soup piece (as PartNet-Mobility parts): the space
    they enclose is air, the boards are solid, with both sign methods. Signing the whole soup at once would
    call the cavity solid (no ray escapes it)."""
    t = 0.02
    pieces = [
        _board([-0.2, -0.3, -0.3], [-0.2 + t, 0.3, 0.3]),  # back
        _board([-0.2, -0.3, -0.3], [0.2, -0.3 + t, 0.3]),  # sides
        _board([-0.2, 0.3 - t, -0.3], [0.2, 0.3, 0.3]),
        _board([-0.2, -0.3, -0.3], [0.2, 0.3, -0.3 + t]),  # bottom, top
        _board([-0.2, -0.3, 0.3 - t], [0.2, 0.3, 0.3]),
        _board([0.2, -0.3, -0.3], [0.2 + t, 0.3, 0.3]),  # door, closed
    ]
    cavity = np.random.default_rng(0).uniform([-0.17, -0.27, -0.27], [0.19, 0.27, 0.27], (500, 3))
    in_boards = np.array([[-0.19, 0.0, 0.0], [0.0, -0.29, 0.1], [0.0, 0.0, 0.29], [0.21, 0.1, -0.1]])
    pts = np.concatenate([cavity, in_boards])
    truth = np.r_[np.zeros(len(cavity), bool), np.ones(len(in_boards), bool)]
    assert (soup_escape_inside(pieces, pts) == truth).all()
    assert (soup_flood_fill_inside(pieces, pts) == truth).all()
    whole = dedupe_soup(trimesh.util.concatenate(pieces))
    assert ray_escape_inside(raycasting_scene(whole), cavity).all()  # why the signs are taken part by part


def test_flat_pieces_enclose_nothing_and_change_no_sign():
    """A tilted zero-thickness pane is skipped by both soup methods (no inside, no grid); a 2 mm board is not."""
    pane = trimesh.Trimesh([[0, -0.2, -0.2], [0, 0.2, -0.2], [0, 0.2, 0.2], [0, -0.2, 0.2]], [[0, 1, 2], [0, 2, 3]])
    pane.apply_transform(trimesh.transformations.euler_matrix(0.3, 0.5, 0.7))
    board = _board([-0.1, -0.1, -0.001], [0.1, 0.1, 0.001])
    assert not encloses_volume(pane) and encloses_volume(board)
    pts = np.random.default_rng(1).uniform(-0.25, 0.25, (400, 3))
    for method in (soup_escape_inside, soup_flood_fill_inside):
        assert not method([pane], pts).any()
        assert (method([pane, board], pts) == method([board], pts)).all()


def _quad(corners) -> trimesh.Trimesh:
    return trimesh.Trimesh(np.asarray(corners, float), [[0, 1, 2], [0, 2, 3]], process=False)


def _slotted_door() -> tuple[trimesh.Trimesh, np.ndarray]:
    """A door slab as PartNet-Mobility draws one (11700): back sheet, four rims and a front sheet with a
    2 x 50 cm slot near the top, all open sheets in one piece; and points in the slab far below the slot."""
    x0, x1, y, z0, z1 = -0.02, 0.02, 0.3, -0.4, 0.4
    slot_lo, slot_hi, slot_y = 0.33, 0.35, 0.25
    quads = [
        [[x0, -y, z0], [x0, y, z0], [x0, y, z1], [x0, -y, z1]],  # back
        [[x0, -y, z0], [x1, -y, z0], [x1, -y, z1], [x0, -y, z1]],  # rims
        [[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]],
        [[x0, -y, z0], [x1, -y, z0], [x1, y, z0], [x0, y, z0]],
        [[x0, -y, z1], [x1, -y, z1], [x1, y, z1], [x0, y, z1]],
        [[x1, -y, z0], [x1, y, z0], [x1, y, slot_lo], [x1, -y, slot_lo]],  # front, around the slot
        [[x1, -y, slot_hi], [x1, y, slot_hi], [x1, y, z1], [x1, -y, z1]],
        [[x1, -y, slot_lo], [x1, -slot_y, slot_lo], [x1, -slot_y, slot_hi], [x1, -y, slot_hi]],
        [[x1, slot_y, slot_lo], [x1, y, slot_lo], [x1, y, slot_hi], [x1, slot_y, slot_hi]],
    ]
    door = dedupe_soup(trimesh.util.concatenate([_quad(q) for q in quads]))
    far = np.random.default_rng(2).uniform([-0.012, -0.28, -0.38], [0.012, 0.28, -0.1], (300, 3))
    return door, far


def test_aimed_rays_find_a_slot_that_spread_rays_miss():
    """The slab behind a slot is open space by connectivity (flood fill) and by visibility (every point in it
    sees out through the slot), but from 50-70 cm below the slot is too thin a target for 256 spread rays:
    without the rays aimed through the openings most of those points were called solid."""
    door, far = _slotted_door()
    targets = opening_targets(door)
    slot_edge = (np.abs(targets[:, 0] - 0.02) < 1e-9) & (targets[:, 2] > 0.33) & (targets[:, 2] < 0.35)
    assert slot_edge.any()  # targets lie in the slot, 2 mm off its rim
    spread_only = soup_escape_inside([door], far, opening_spacing=0.0)
    assert spread_only.mean() > 0.5
    assert not soup_escape_inside([door], far).any()
    assert not soup_flood_fill_inside([door], far).any()
    closed = dedupe_soup(
        trimesh.util.concatenate(
            [door, _quad([[0.02, -0.3, 0.33], [0.02, 0.3, 0.33], [0.02, 0.3, 0.35], [0.02, -0.3, 0.35]])]
        )
    )
    assert soup_escape_inside([closed], far).all()  # with the slot covered the seams stay closed


def test_flood_pitch_resolves_thin_boards_within_the_voxel_cap():
    board = np.array([1.0, 0.6, 0.018])
    pitch = flood_pitch(board, cells=256, thin_cells=12, max_voxels=4e6)
    assert pitch <= 0.018 / 6 and np.prod(np.ceil(board / pitch)) <= 4.2e6
    assert abs(flood_pitch(np.array([0.5, 0.5, 0.5]), 256, 12, 1e9) - 0.5 / 256) < 1e-12


def test_escape_needs_min_escaping_rays():
    """A hollow box with a 4 cm hole in its 2 cm thick top: from the centre the hole is a small target (about
    one ray in 256), so asking for several escaping rays counts it as closed; just below the hole it is not."""
    box = trimesh.creation.box(extents=[0.4, 0.4, 0.4])
    hole = trimesh.creation.box(extents=[0.04, 0.04, 0.1])
    hole.apply_translation([0.0, 0.0, 0.2])
    cavity = trimesh.creation.box(extents=[0.36, 0.36, 0.36])
    shell = from_manifold(to_manifold(box) - to_manifold(cavity) - to_manifold(hole))
    scene = raycasting_scene(shell)
    centre = np.zeros((1, 3))
    assert ray_escape_inside(scene, centre, rays=256, min_escaping=4)[0]
    near_hole = np.array([[0.0, 0.0, 0.17]])
    assert not ray_escape_inside(scene, near_hole, rays=256, min_escaping=4)[0]
