"""Snapping a regressed shape code onto the decoder's training codes."""

from __future__ import annotations

import numpy as np

from centerart.inference.reconstruction import MeshConfig, reconstruct_object
from centerart.inference.shape_prior import best_fit_code, nearest_code
from centerart.models.checkpoint import load_decoder


def test_nearest_code_is_the_closest_training_code():
    codes = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 2.0]])
    assert nearest_code(np.array([0.9, 0.2]), codes) == 1
    assert nearest_code(np.array([0.1, 1.2]), codes) == 2


def test_best_fit_picks_the_object_whose_surface_was_observed():
    loaded = load_decoder()
    ids = sorted(loaded.codes)
    codes = np.stack([loaded.codes[i] for i in ids])
    k, j = 0, 5
    surface = reconstruct_object(loaded.decoder, codes[k], 0.3, loaded.bounds, MeshConfig(resolution=32)).mesh
    camera_T_object = np.eye(4)
    camera_T_object[:3, 3] = [0.1, -0.2, 2.0]
    observed = surface.vertices + camera_T_object[:3, 3]
    between = 0.5 * (codes[k] + codes[j])  # a regression stuck between two objects
    chosen, info = best_fit_code(loaded.decoder, between, 0.3, codes, observed, camera_T_object)
    assert chosen == k, (ids[chosen], info)
    assert min(info["median_abs_sdf_m"]) < 0.01
