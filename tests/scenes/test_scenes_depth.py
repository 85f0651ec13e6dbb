"""Realistic depth: error band, holes at depth edges; analytic model statistics."""

from __future__ import annotations

import cv2
import numpy as np

from centerart.scenes.cameras import intrinsics
from centerart.scenes.dataset import list_views, load_view
from centerart.scenes.depth_noise import analytic_depth, dot_pattern, register_depth


def _edges(depth, width=2):
    d = depth.astype(np.float32)
    grad = np.maximum(np.abs(np.diff(d, axis=0, prepend=d[:1])), np.abs(np.diff(d, axis=1, prepend=d[:, :1])))
    edges = (grad > 0.05).astype(np.uint8)
    return cv2.dilate(edges, np.ones((2 * width + 1, 2 * width + 1), np.uint8)).astype(bool)


def test_stereo_depth_error_band_and_edge_holes(kitchen_dataset):
    """Stereo depth (IR pair + SGBM): outside the matcher's blind left band, >= 60% of pixels valid, median error
    under 3% of the depth, and holes at depth edges at least twice as frequent as elsewhere."""
    for view_dir in list_views(kitchen_dataset):
        view = load_view(view_dir)
        assert view.labels["depth_realistic"] == "stereo"
        true, real = view.depth_true, view.depth_realistic
        band = 60  # columns the matcher cannot search (numDisparities at this resolution)
        t, r = true[:, band:], real[:, band:]
        valid = r > 0
        assert valid.mean() > 0.6
        rel = np.abs(r[valid] - t[valid]) / t[valid]
        assert np.median(rel) < 0.03
        assert np.median(rel) > 1e-4  # it is not the true depth
        edges = _edges(t)
        hole_edge = (~valid[edges]).mean()
        hole_flat = (~valid[~edges]).mean()
        assert hole_edge > 2 * hole_flat, (hole_edge, hole_flat)
        assert (real[:, :20] == 0).all()  # the blind band on the left, as on a real D415


def test_analytic_depth_band_and_edge_holes(single_dataset):
    for view_dir in list_views(single_dataset):
        view = load_view(view_dir)
        true, real = view.depth_true, view.depth_realistic
        valid = real > 0
        assert 0.7 < valid.mean() < 0.995
        rel = np.abs(real[valid] - true[valid]) / true[valid]
        assert 1e-4 < np.median(rel) < 0.02
        edges = _edges(true)
        assert (~valid[edges]).mean() > 3 * (~valid[~edges]).mean()


def test_analytic_noise_grows_with_depth():
    _, _, K = intrinsics("tiny")
    rng = np.random.default_rng(0)
    errs = []
    for z in (0.8, 2.4):
        depth = np.full((240, 320), z, np.float32)
        noisy = analytic_depth(depth, K, rng, hole_fraction=0.0)
        errs.append(np.std(noisy[noisy > 0] - z))
    assert errs[1] > 4 * errs[0]  # axial noise ~ z^2


def test_register_depth_identity_and_shift():
    _, _, K = intrinsics("tiny")
    depth = np.full((240, 320), 2.0, np.float32)
    np.testing.assert_allclose(register_depth(depth, K, np.eye(4)), depth)
    T = np.eye(4)
    T[0, 3] = 0.1  # the destination camera sees the plane shifted right by f * 0.1 / 2 px
    out = register_depth(depth, K, T)
    shift = round(K[0, 0] * 0.1 / 2.0)
    assert (out[:, : shift - 1] == 0).all() and (out[:, shift + 1 :] > 0).all()


def test_dot_pattern_is_deterministic_and_sparse():
    a, b = dot_pattern(7, 320, 240), dot_pattern(7, 320, 240)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, dot_pattern(8, 320, 240))
    lit = (a[..., 0] > 64).mean()
    assert 0.02 < lit < 0.3
