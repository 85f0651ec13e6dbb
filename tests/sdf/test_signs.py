"""Signed distances and the sign methods on analytic shapes (closed-form SDFs)."""

from __future__ import annotations

import numpy as np
import trimesh

from centerart.sdf.sampling import SamplingConfig, sample_points, signed_distance
from centerart.sdf.signs import (
    flood_fill_inside,
    ray_escape_inside,
    ray_parity_inside,
    raycasting_scene,
    winding_number,
)
from centerart.sdf.surface import dedupe_soup

HALF = np.array([0.3, 0.2, 0.1])


def box_sdf(p: np.ndarray, half: np.ndarray = HALF) -> np.ndarray:
    q = np.abs(p) - half
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)


def test_box_sdf_matches_closed_form():
    box = trimesh.creation.box(extents=2 * HALF)
    rng = np.random.default_rng(0)
    cfg = SamplingConfig(check_points=2_000)
    pts = sample_points(box, 20_000, cfg, rng)
    res = signed_distance(box, True, pts, cfg, rng)
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
    inside = flood_fill_inside(sphere, scene, pts, pts.min(0) - 0.05, pts.max(0) + 0.05, cells=96)
    assert (inside == truth).mean() > 0.999
    res = signed_distance(sphere, True, pts, SamplingConfig(check_points=1000), rng)
    np.testing.assert_allclose(res.sdf, r - 0.25, atol=1.5e-3)


def test_soup_of_double_sided_box_signs_like_a_solid():
    """A PartNet-style soup: every box face drawn twice (both orientations), vertices unmerged."""
    box = trimesh.creation.box(extents=2 * HALF)
    tri = box.vertices[box.faces]
    both = np.concatenate([tri, tri[:, ::-1]])
    soup = trimesh.Trimesh(both.reshape(-1, 3), np.arange(len(both) * 3).reshape(-1, 3), process=False)
    clean = dedupe_soup(soup)
    assert len(clean.faces) == 12
    rng = np.random.default_rng(2)
    cfg = SamplingConfig(check_points=5_000, soup_shell=0.002)
    pts = sample_points(clean, 20_000, cfg, rng)
    res = signed_distance(clean, False, pts, cfg, rng)
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
    res = signed_distance(sheet, False, pts, cfg, np.random.default_rng(0))
    np.testing.assert_allclose(
        res.sdf, [-0.001, -0.001, 0.008, 0.048, np.linalg.norm([0.3, 0.1, 0.1]) - 0.002], atol=1e-5
    )
