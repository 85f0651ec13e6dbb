"""Query points and their signed distances for one (object, joint state), canonical frame, metres.

Point mix (fractions of the point count), each set drawn around area-weighted surface samples:

- ``near`` (default 45%): surface + N(0, 5 mm). Puts most of the budget where the zero level set must be
  accurate: reconstruction is judged by Chamfer distance at the millimetre level and DeepSDF's clamped loss only
  sees |sdf| < 0.1 m.
- ``far`` (35%): surface + N(0, 3 cm). Covers the band where grasps live (the TCP sits 0-4 cm from the part
  and the control points reach 10 cm behind it) and teaches the field's slope away from the surface.
- ``uniform`` (rest): uniform in the object's bounds at that state, padded by ``padding`` on every side, so
  that the decoder sees far-field signs and does not invent surfaces in empty space.

Signed distance: exact unsigned distance to the surface (open3d RaycastingScene) times the sign of
:mod:`centerart.sdf.signs`. For triangle soups the field is that of the soup thickened by ``soup_shell`` m
(``sdf = s * d - soup_shell``): without it an open sheet (most PartNet-Mobility walls) has no inside, so the field
never changes sign there and marching cubes cannot find it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d
import trimesh

from centerart.sdf.signs import (
    ray_parity_inside,
    raycasting_scene,
    soup_escape_inside,
    soup_flood_fill_inside,
    winding_number,
)
from centerart.sdf.surface import ObjectSurface


@dataclass
class SamplingConfig:
    """How query points are drawn and signed (see the module docstring for why)."""

    near_fraction: float = 0.45
    """Share of points at surface + N(0, near_sigma)."""
    near_sigma: float = 0.005
    """m, standard deviation of the near-surface noise."""
    far_fraction: float = 0.35
    """Share of points at surface + N(0, far_sigma); the rest is uniform in the padded bounds."""
    far_sigma: float = 0.03
    """m, standard deviation of the wider band."""
    padding: float = 0.05
    """m added on every side of the object's bounds for the uniform points."""
    parity_rays: int = 5
    """Rays voting on ray parity (closed meshes; odd)."""
    escape_rays: int = 256
    """Rays of the escape test (soups' sign)."""
    escape_min_rays: int = 1
    """A soup point is outside when at least this many of the escape rays leave the piece without a hit."""
    escape_opening_spacing: float = 0.01
    """m between the aimed rays' targets along a soup piece's open edges (0 turns the aimed rays off)."""
    escape_opening_offset: float = 0.002
    """m off each open edge, in its triangle's plane, of the aimed rays' targets: narrower seams stay closed."""
    flood_cells: int = 256
    """Voxels along the longest side of each soup piece's flood-fill grid (soups' check)."""
    flood_thin_cells: int = 12
    """At least this many voxels across a piece's thinnest side (so boards have an interior)."""
    flood_max_voxels: int = 4_000_000
    """Cap on one piece's grid (bounds memory and time; coarsens the pitch of large pieces)."""
    soup_shell: float = 0.002
    """m, half-thickness given to triangle soups (0 for closed meshes)."""
    check_points: int = 10_000
    """Points (a seeded subsample) on which the second sign method is run (winding numbers cost O(points x
    triangles)); 10k points give the agreement to about +-0.2%."""


@dataclass
class SignedSamples:
    points: np.ndarray  # (N, 3) float32
    sdf: np.ndarray  # (N,) float32
    sign_agreement: float  # share of checked points whose sign the second method confirms
    checked: int
    sign_method: str
    check_method: str


def sample_points(mesh: trimesh.Trimesh, count: int, cfg: SamplingConfig, rng: np.random.Generator) -> np.ndarray:
    """``count`` query points (count, 3) around ``mesh``, near set first, then far, then uniform; deterministic
    given ``rng``."""
    n_near = round(count * cfg.near_fraction)
    n_far = round(count * cfg.far_fraction)
    n_uniform = count - n_near - n_far
    if min(n_near, n_far, n_uniform) < 0:
        raise ValueError("near_fraction + far_fraction must be <= 1")
    surface, _ = trimesh.sample.sample_surface(mesh, n_near + n_far, seed=int(rng.integers(2**31)))
    near = surface[:n_near] + rng.normal(0.0, cfg.near_sigma, (n_near, 3))
    far = surface[n_near:] + rng.normal(0.0, cfg.far_sigma, (n_far, 3))
    lo, hi = mesh.bounds[0] - cfg.padding, mesh.bounds[1] + cfg.padding
    uniform = rng.uniform(lo, hi, (n_uniform, 3))
    return np.concatenate([near, far, uniform]).astype(np.float32)


def signed_distance(
    surface: ObjectSurface, points: np.ndarray, cfg: SamplingConfig, rng: np.random.Generator
) -> SignedSamples:
    """SDF of ``points`` w.r.t. ``surface`` plus the sign agreement with the independent second method."""
    points = np.asarray(points, np.float32)
    mesh = surface.mesh
    scene = raycasting_scene(mesh)
    dist = scene.compute_distance(o3d.core.Tensor(points)).numpy().astype(np.float64)
    check_idx = np.sort(rng.choice(len(points), min(cfg.check_points, len(points)), replace=False))
    if surface.closed:
        inside = ray_parity_inside(scene, points, cfg.parity_rays)
        check_inside = winding_number(mesh, points[check_idx]) > 0.5
        shell, methods = 0.0, ("ray_parity", "winding_number")
    else:
        inside = soup_sign_inside(surface, points, cfg)
        check_inside = soup_check_inside(surface, points[check_idx], cfg)
        shell, methods = cfg.soup_shell, ("ray_escape_per_part", "flood_fill_per_part")
    sdf = np.where(inside, -dist, dist) - shell
    # Agreement on the sign of the final field: within the shell both methods give a negative value.
    check_sdf = np.where(check_inside, -dist[check_idx], dist[check_idx]) - shell
    agreement = float(np.mean((sdf[check_idx] < 0) == (check_sdf < 0)))
    return SignedSamples(points, sdf.astype(np.float32), agreement, len(check_idx), *methods)


def soup_sign_inside(surface: ObjectSurface, points: np.ndarray, cfg: SamplingConfig) -> np.ndarray:
    """The soup sign (ray escape per part, aimed rays included) with the settings of ``cfg``."""
    return soup_escape_inside(
        surface.pieces,
        points,
        cfg.escape_rays,
        cfg.escape_min_rays,
        opening_spacing=cfg.escape_opening_spacing,
        opening_offset=cfg.escape_opening_offset,
    )


def soup_check_inside(surface: ObjectSurface, points: np.ndarray, cfg: SamplingConfig) -> np.ndarray:
    """The soup check (flood fill per part, grids moving with the parts) with the settings of ``cfg``."""
    return soup_flood_fill_inside(
        surface.pieces,
        points,
        cfg.flood_cells,
        cfg.flood_thin_cells,
        cfg.flood_max_voxels,
        frames=surface.piece_frames or None,
    )
