"""Encoder labels for one image: per visible object its pose, joint, mask statistics and centre heatmap.

All poses and joint axes are in the **OpenCV camera frame** (x right, y down, z forward), metres. The object pose
``camera_T_object`` places the object's canonical frame (x out of the front, z up, origin at the centre of the
closed bounding box; :mod:`centerart.assets.canonical_frame`).

Centre heatmap (the paper's ground truth, published-implementation.md section 3.5): for every visible instance
mask a 2-D Gaussian with mean ``floor(mean pixel)`` and covariance = covariance of the mask's pixel coordinates,
normalised to a peak of 1; the image's heatmap is the pixel-wise maximum over objects.

Visible fraction: visible mask pixels divided by the pixels the whole object would cover with nothing in front of
it and an unbounded image (its projected silhouette), so it drops for both occlusion and truncation.
"""

from __future__ import annotations

import cv2
import numpy as np
import trimesh

from centerart.assets.articulated_object import ArticulatedObject
from centerart.geometry.camera import project
from centerart.geometry.transforms import apply_transform, invert_pose
from centerart.scenes.description import SceneDescription

MIN_VISIBLE_PIXELS = 50
#: Heatmap values below this are stored as 0 (a 16-bit PNG step is 1.5e-5: they would round to 0 anyway).
HEATMAP_FLOOR = 1e-6


def project_silhouette(
    mesh: trimesh.Trimesh, camera_T_mesh: np.ndarray, K: np.ndarray, width: int, height: int, pad: int = 0
) -> np.ndarray:
    """Boolean (height + 2 pad, width + 2 pad) mask of the mesh's projection (no occlusion by other things).

    Pixel (u, v) of the image is at (u + pad, v + pad) of the result. Triangles with a vertex closer than 1 cm to
    the camera plane are skipped.
    """
    pts = apply_transform(camera_T_mesh, mesh.vertices)
    tris = pts[mesh.faces]
    keep = (tris[..., 2] > 0.01).all(1)
    tris = tris[keep]
    uv = project(tris.reshape(-1, 3), K)[0].reshape(-1, 3, 2) + pad
    mask = np.zeros((height + 2 * pad, width + 2 * pad), np.uint8)
    shift = 4  # sub-pixel vertex precision for the rasterisation
    poly = np.round(uv * (1 << shift)).astype(np.int32)
    # Clip absurdly far vertices (grazing triangles) so int32 fixed point does not overflow.
    lim = (1 << 30) >> shift
    poly = np.clip(poly, -lim, lim)
    # One call per triangle: fillPoly on a list of polygons would apply an even-odd rule to overlapping triangles.
    for tri in poly:
        cv2.fillConvexPoly(mask, tri, 1, lineType=cv2.LINE_8, shift=shift)
    return mask.astype(bool)


def heatmap_from_masks(masks: list[np.ndarray]) -> tuple[np.ndarray, list[dict]]:
    """The paper's centre heatmap (float32 in 0..1) and each mask's Gaussian (mean (u, v) px, 2x2 covariance).

    Each Gaussian is evaluated only inside the box where it is at least ``HEATMAP_FLOOR`` (zero beyond): the whole
    image per object was a third of a view's labelling time, and the stored 16-bit heatmap rounds such values to 0.
    """
    if not masks:
        return np.zeros((0, 0), np.float32), []
    h, w = masks[0].shape
    heat = np.zeros((h, w), np.float32)
    stats = []
    for m in masks:
        v, u = np.nonzero(m)
        if len(u) < 3:
            stats.append({"mean_uv": None, "cov_uv": None})
            continue
        mean = np.floor(np.array([u.mean(), v.mean()]))
        cov = np.cov(np.stack([u, v]).astype(float)) + 1e-3 * np.eye(2)
        inv = np.linalg.inv(cov)
        # exp(-d^2 / 2) >= floor inside the ellipse d^2 <= 2 ln(1 / floor): half extents sqrt(2 ln(1 / floor) cov_ii).
        reach = np.ceil(np.sqrt(2.0 * np.log(1.0 / HEATMAP_FLOOR) * np.diag(cov))) + 1
        (u0, v0), (u1, v1) = np.maximum(mean - reach, 0).astype(int), np.minimum(mean + reach + 1, (w, h)).astype(int)
        du, dv = np.meshgrid(np.arange(u0, u1) - mean[0], np.arange(v0, v1) - mean[1])
        g = np.exp(-0.5 * (inv[0, 0] * du * du + 2 * inv[0, 1] * du * dv + inv[1, 1] * dv * dv))
        heat[v0:v1, u0:u1] = np.maximum(heat[v0:v1, u0:u1], (g / g.max()).astype(np.float32))
        stats.append({"mean_uv": mean.tolist(), "cov_uv": cov.tolist()})
    return heat, stats


def view_labels(
    scene: SceneDescription,
    objects: list[ArticulatedObject],
    view: int,
    instances: np.ndarray,
    link_ids: dict[int, tuple[int, str]],
    shape_codes: dict[str, np.ndarray] | None = None,
    meshes: dict[int, trimesh.Trimesh] | None = None,
) -> tuple[dict, np.ndarray]:
    """Labels (JSON-ready dict) and heatmap of one view, from the description and the instance image.

    ``meshes`` memoises object k's whole mesh (canonical frame, at its scene state) across the views of one scene:
    pass the same dict for every view of a scene (the silhouettes need it; building it is ~10 ms per object)."""
    cam = scene.cameras[view]
    K = np.asarray(cam.K, float)
    world_T_camera = scene.camera_pose(view)
    camera_T_world = invert_pose(world_T_camera)
    h, w = instances.shape
    labels, masks = [], []
    meshes = {} if meshes is None else meshes
    for k, (spec, obj) in enumerate(zip(scene.objects, objects, strict=True)):
        mask = instances == k + 1
        n_visible = int(mask.sum())
        if n_visible < MIN_VISIBLE_PIXELS:
            continue
        camera_T_object = camera_T_world @ scene.object_pose(k)
        pad = max(w, h)
        if k not in meshes:
            meshes[k] = obj.mesh(spec.joint_state)
        silhouette = project_silhouette(meshes[k], camera_T_object, K, w, h, pad)
        full = int(silhouette.sum())
        axis = obj.target_axis(spec.joint_state)
        v, u = np.nonzero(mask)
        code = None
        if shape_codes is not None:
            if spec.object_id in shape_codes:
                code = np.asarray(shape_codes[spec.object_id], float).tolist()
        labels.append(
            {
                "instance": k + 1,
                "name": spec.name,
                "object_id": spec.object_id,
                "category": spec.category,
                "camera_T_object": camera_T_object.tolist(),
                "joint": {
                    "name": spec.target_joint,
                    "type": spec.joint_type,
                    "axis_origin_camera": apply_transform(camera_T_object, axis.origin).tolist(),
                    "axis_direction_camera": (camera_T_object[:3, :3] @ axis.direction).tolist(),
                    "state": spec.joint_state,
                    "state_normalized": spec.joint_state_normalized,
                    "range": list(obj.joint_range),
                    "unit": "rad" if spec.joint_type == "revolute" else "m",
                },
                "held_states": spec.held_states,
                "visible_pixels": n_visible,
                "visible_fraction": float(min(1.0, n_visible / max(full, 1))),
                "bbox_xyxy": [int(u.min()), int(v.min()), int(u.max()), int(v.max())],
                "links": {str(i): name for i, (kk, name) in link_ids.items() if kk == k},
                "shape_code": code,
            }
        )
        masks.append(mask)
    heat, stats = heatmap_from_masks(masks)
    if not masks:
        heat = np.zeros((h, w), np.float32)
    for lab, st in zip(labels, stats, strict=True):
        lab["heatmap_gaussian"] = st
    info = {
        "scene_id": scene.scene_id,
        "view": view,
        "width": w,
        "height": h,
        "K": K.tolist(),
        "world_T_camera": world_T_camera.tolist(),
        "frames": "OpenCV camera (x right, y down, z forward); metres; object = canonical frame",
        "objects": labels,
    }
    return info, heat
