"""Label consistency: label poses + K reproduce the rendered masks and the rendered depth lies on the true mesh."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from centerart.geometry.transforms import apply_transform, invert_pose
from centerart.scenes.dataset import list_views, load_view
from centerart.scenes.description import SceneDescription, load_scene_object
from centerart.scenes.labels import heatmap_from_masks, project_silhouette


def _scene_objects(view_dir):
    scene = SceneDescription.load(view_dir.parent.parent / "scene.json")
    objects = [load_scene_object(o) for o in scene.objects]
    return scene, objects


def _views(*datasets):
    return [v for d in datasets for v in list_views(d)]


def test_label_pose_projects_onto_mask(kitchen_dataset, single_dataset):
    """The true mesh drawn with the label pose and K covers the instance mask (IoU >= 0.9) for unoccluded objects."""
    checked = 0
    for view_dir in _views(kitchen_dataset, single_dataset):
        view = load_view(view_dir)
        scene, objects = _scene_objects(view_dir)
        K = np.asarray(view.labels["K"])
        h, w = view.instances.shape
        for lab in view.labels["objects"]:
            if lab["visible_fraction"] < 0.9:
                continue  # occluded or cut by the image border: the silhouette is larger than the mask
            k = lab["instance"] - 1
            obj = objects[k]
            sil = project_silhouette(
                obj.mesh(scene.objects[k].joint_state), np.asarray(lab["camera_T_object"]), K, w, h
            )
            mask = view.instances == lab["instance"]
            iou = (sil & mask).sum() / (sil | mask).sum()
            assert iou >= 0.9, f"{view_dir} {lab['name']}: IoU {iou:.3f}"
            checked += 1
    assert checked >= 3


def test_label_pose_matches_description(kitchen_dataset):
    for view_dir in list_views(kitchen_dataset):
        view = load_view(view_dir)
        scene, _ = _scene_objects(view_dir)
        camera_T_world = invert_pose(np.asarray(view.labels["world_T_camera"]))
        for lab in view.labels["objects"]:
            expected = camera_T_world @ scene.object_pose(lab["instance"] - 1)
            np.testing.assert_allclose(lab["camera_T_object"], expected, atol=1e-9)
            # The camera frame is OpenCV: a visible object lies in front of the camera (z > 0).
            assert lab["camera_T_object"][2][3] > 0


def test_true_depth_lies_on_mesh(kitchen_dataset, single_dataset):
    """Back-projected true depth of each object's pixels lies on its mesh (median distance < 2 mm)."""
    rng = np.random.default_rng(0)
    tested = 0
    for view_dir in _views(kitchen_dataset, single_dataset):
        view = load_view(view_dir)
        scene, objects = _scene_objects(view_dir)
        K = np.asarray(view.labels["K"])
        for lab in view.labels["objects"]:
            k = lab["instance"] - 1
            v, u = np.nonzero((view.instances == lab["instance"]) & (view.depth_true > 0))
            pick = rng.choice(len(u), min(300, len(u)), replace=False)
            u, v = u[pick], v[pick]
            z = view.depth_true[v, u]
            pts = np.stack([(u - K[0, 2]) * z / K[0, 0], (v - K[1, 2]) * z / K[1, 1], z], 1)
            local = apply_transform(invert_pose(np.asarray(lab["camera_T_object"])), pts)
            mesh = objects[k].mesh(scene.objects[k].joint_state)
            _, dist, _ = trimesh.proximity.closest_point(mesh, local)
            assert np.median(dist) < 0.002, f"{view_dir} {lab['name']}: median {np.median(dist) * 1000:.2f} mm"
            tested += 1
    assert tested >= 3


def test_joint_axis_in_camera_frame(kitchen_dataset):
    for view_dir in list_views(kitchen_dataset):
        view = load_view(view_dir)
        scene, objects = _scene_objects(view_dir)
        for lab in view.labels["objects"]:
            k = lab["instance"] - 1
            axis = objects[k].target_axis(scene.objects[k].joint_state)
            T = np.asarray(lab["camera_T_object"])
            np.testing.assert_allclose(lab["joint"]["axis_direction_camera"], T[:3, :3] @ axis.direction, atol=1e-9)
            np.testing.assert_allclose(lab["joint"]["axis_origin_camera"], apply_transform(T, axis.origin), atol=1e-9)
            lo, hi = lab["joint"]["range"]
            q = lab["joint"]["state"]
            assert lo <= q <= hi
            assert lab["joint"]["state_normalized"] == pytest.approx((q - lo) / (hi - lo))


def test_heatmap_is_gaussian_of_mask():
    mask = np.zeros((60, 80), bool)
    mask[10:30, 20:60] = True
    heat, stats = heatmap_from_masks([mask])
    mean = stats[0]["mean_uv"]
    assert mean == [39.0, 19.0]
    assert heat[19, 39] == pytest.approx(1.0)
    cov = np.asarray(stats[0]["cov_uv"])
    assert cov[0, 0] > 3 * cov[1, 1]  # wider than tall, like the mask
    # Wider mask -> slower fall-off along u than along v.
    assert heat[19, 39 + 10] > heat[19 + 10, 39]


def test_stored_heatmap_peaks_at_visible_objects(kitchen_dataset):
    for view_dir in list_views(kitchen_dataset):
        view = load_view(view_dir)
        for lab in view.labels["objects"]:
            u, v = (int(x) for x in lab["heatmap_gaussian"]["mean_uv"])
            assert view.heatmap[v, u] > 0.99


def test_silhouette_projection_rejects_wrong_frame(single_dataset):
    """The IoU test can fail: the same mesh drawn in SAPIEN's camera convention misses the mask."""
    view_dir = list_views(single_dataset)[0]
    view = load_view(view_dir)
    scene, objects = _scene_objects(view_dir)
    lab = view.labels["objects"][0]
    T = np.asarray(lab["camera_T_object"]).copy()
    T[0, 3] += 0.15  # 15 cm sideways
    h, w = view.instances.shape
    sil = project_silhouette(objects[0].mesh(scene.objects[0].joint_state), T, np.asarray(view.labels["K"]), w, h)
    mask = view.instances == lab["instance"]
    assert (sil & mask).sum() / (sil | mask).sum() < 0.9


def test_heatmap_outside_its_window_is_below_the_floor():
    """The Gaussians are evaluated in a window only: the full-image evaluation differs from it by less than the
    floor everywhere, so the stored 16-bit heatmap (65535 steps) is the same. A tilted, elongated mask near a
    border and a small one exercise the covariance and the clipping."""
    from centerart.scenes.labels import HEATMAP_FLOOR

    h, w = 120, 160
    vv, uu = np.mgrid[0:h, 0:w]
    tilted = np.abs((uu - 30) - 0.8 * (vv - 20)) < 6
    small = (uu - 120) ** 2 + (vv - 90) ** 2 < 16
    heat, stats = heatmap_from_masks([tilted, small])
    full = np.zeros((h, w))
    for st in stats:
        mean, inv = np.asarray(st["mean_uv"]), np.linalg.inv(np.asarray(st["cov_uv"]))
        d = np.stack([uu - mean[0], vv - mean[1]], -1)
        full = np.maximum(full, np.exp(-0.5 * np.einsum("...i,ij,...j->...", d, inv, d)))
    assert np.abs(full - heat).max() < HEATMAP_FLOOR
    assert np.array_equal(np.round(full.astype(np.float32) * 65535), np.round(heat * 65535))
