"""Grasp anchoring on a hand-made observation: a door face 1 m in front of the camera with a vertical bar handle.

Camera frame (OpenCV): the camera looks along +z; the door's face is the plane z = 1.0 and the bar's observed front
is z = 0.96 (4 cm proud), 2 cm wide at x = 0.20. A grasp on the bar approaches along +z and closes along x.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from centerart.inference.grasp_anchoring import (
    LADDER,
    AnchoringConfig,
    ObjectView,
    anchor_grasps,
    anchoring_setting,
    handle_cue,
)
from centerart.inference.handles import face_noise, handle_min_height
from centerart.inference.observed_checks import ObservedCheckConfig, closing_points, collision_points

HANDLE_X, HANDLE_FRONT_Z, DOOR_Z = 0.20, 0.96, 1.00


def _grid(xs, ys, z) -> np.ndarray:
    x, y = np.meshgrid(xs, ys, indexing="ij")
    return np.stack([x.ravel(), y.ravel(), np.full(x.size, z)], 1)


def door_with_handle() -> np.ndarray:
    """Observed points (N, 3): the door face (minus what the bar hides) and the bar's front face, 4 mm apart."""
    door = _grid(np.arange(-0.30, 0.30, 0.004), np.arange(-0.40, 0.40, 0.004), DOOR_Z)
    hidden = (np.abs(door[:, 0] - HANDLE_X) < 0.011) & (np.abs(door[:, 1]) < 0.10)
    bar = _grid(np.arange(HANDLE_X - 0.01, HANDLE_X + 0.0101, 0.004), np.arange(-0.10, 0.10, 0.004), HANDLE_FRONT_Z)
    return np.concatenate([door[~hidden], bar])


def grasp(x: float, y: float, z: float) -> np.ndarray:
    """TCP pose approaching along +z (away from the camera), closing along x (across the vertical bar)."""
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    pose[:3, 3] = [x, y, z]
    return pose


def anchored(candidates, cfg=None):
    points = door_with_handle()
    view = ObjectView(None, np.zeros(4), 0.5, np.eye(4), points, "revolute", np.array([-0.3, 0, 1.0]),
                      np.array([0.0, 1.0, 0.0]))  # fmt: skip
    cfg = cfg or AnchoringConfig(observed_candidates=False, handle_candidates=False, square=False)
    return anchor_grasps(view, np.array(candidates), cKDTree(points), None, cfg, top_k=10)


ON_HANDLE = (HANDLE_X, 0.0, HANDLE_FRONT_Z + ObservedCheckConfig().grasp_depth_m)


def test_a_grasp_on_the_handle_is_kept_where_it_is():
    result = anchored([grasp(*ON_HANDLE)])
    assert result.counts["kept"] == 1 and result.rejected_reasons == []
    np.testing.assert_allclose(result.poses[0, :3, 3], ON_HANDLE, atol=2e-3)
    assert result.closing_points[0] >= 8


def test_a_candidate_2cm_off_the_handle_is_re_anchored_onto_it():
    """2 cm off along the closing axis and 2 cm short of the bar along the approach."""
    result = anchored([grasp(HANDLE_X + 0.02, 0.0, HANDLE_FRONT_Z - 0.01)])
    assert result.counts["kept"] == 1
    np.testing.assert_allclose(result.poses[0, :3, 3], ON_HANDLE, atol=3e-3)
    # Without the snap the same candidate closes on free air in front of the bar and is rejected.
    unsnapped = anchored([grasp(HANDLE_X + 0.02, 0.0, HANDLE_FRONT_Z - 0.01)], AnchoringConfig(
        observed_candidates=False, handle_candidates=False, square=False, snap=False))  # fmt: skip
    assert unsnapped.counts["kept"] == 0 and unsnapped.rejected_reasons == ["no_material_between_pads"]


def test_a_grasp_in_free_air_is_rejected():
    result = anchored([grasp(HANDLE_X, 0.0, 0.80)])  # 16 cm in front of the bar
    assert result.counts["kept"] == 0 and result.rejected_reasons == ["far_from_material"]


def test_a_grasp_whose_fingers_pass_through_an_observed_surface_is_rejected():
    """On the flat door (no handle): the fingers straddling the TCP would enter the door face."""
    result = anchored([grasp(-0.10, 0.0, DOOR_Z + 0.01)])
    assert result.counts["kept"] == 0 and result.rejected_reasons == ["collides_with_observed"]
    # The same check is what rejects it: the fingers hold door points, the handle grasp's hold none.
    tree, cfg = cKDTree(door_with_handle()), ObservedCheckConfig()
    assert collision_points(np.array([grasp(-0.10, 0.0, DOOR_Z + 0.01)]), tree, cfg)[0] > cfg.max_collision_points
    assert collision_points(np.array([grasp(*ON_HANDLE)]), tree, cfg)[0] <= cfg.max_collision_points
    assert closing_points(np.array([grasp(*ON_HANDLE)]), tree)[0] >= cfg.min_closing_points


def test_an_approach_through_a_neighbouring_surface_is_rejected():
    """A board 5 cm in front of the handle (a neighbour's door): clear at the grasp, blocked on the approach."""
    board = _grid(np.arange(0.10, 0.30, 0.004), np.arange(-0.05, 0.05, 0.004), HANDLE_FRONT_Z - 0.05)
    points = np.concatenate([door_with_handle(), board])
    cfg = ObservedCheckConfig()
    assert collision_points(np.array([grasp(*ON_HANDLE)]), cKDTree(points), cfg)[0] > cfg.max_collision_points


def test_handle_candidates_find_the_bar_and_the_cue_prefers_it():
    result = anchored([], AnchoringConfig(observed_candidates=False))
    assert result.counts["candidates_handle"] >= 1 and result.counts["kept"] >= 1
    assert result.sources[0] == "handle"
    np.testing.assert_allclose(result.poses[0, :3, 3], ON_HANDLE, atol=5e-3)
    plane = (np.array([0.0, 0.0, -1.0]), DOOR_Z)  # n . p + d = 0 on the door, n toward the camera
    floor = handle_min_height(face_noise(door_with_handle(), *plane))
    cue = handle_cue(np.array([grasp(*ON_HANDLE), grasp(-0.10, 0.0, DOOR_Z + 0.01)]), plane,
                     cKDTree(door_with_handle()), floor)  # fmt: skip
    assert cue[0] == pytest.approx(1.0) and cue[1] == pytest.approx(0.0)


def test_ladder_settings_add_one_lever_each():
    assert not anchoring_setting("proposal").enabled
    full = anchoring_setting("full")
    assert full == AnchoringConfig()
    on = [anchoring_setting(n) for n in LADDER]
    assert [c.snap for c in on] == [False, False, True, True, True, True, True, True]
    assert [c.use_ranker for c in on] == [False] * 6 + [True, True]
    assert [c.observed_candidates for c in on][-3:] == [True, True, True]
    with pytest.raises(ValueError, match="grasp setting"):
        anchoring_setting("everything")


def test_first_surface_is_a_point_of_the_column_even_with_a_gap_behind_the_front():
    """Two stray points 3 cm in front of a surface: the slab never comes out empty (no NaN pose)."""
    from centerart.inference.observed_checks import first_surface

    z = np.concatenate([[-0.05, -0.049], np.full(40, -0.02)])
    front = first_surface(z, noise_m=0.0)
    assert np.isfinite(front) and front == pytest.approx(-0.02)
