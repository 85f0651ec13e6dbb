"""Encoder training targets from a rendered view's labels (``labels.json`` of ``centerart scenes generate``).

All targets are in the letterboxed network input (pixels) and the OpenCV camera frame (m, rad):

- ``heatmap`` (H, W): per labelled object a 2-D Gaussian with the covariance of its visible mask pixels (the
  paper's), peak 1, mapped through the letterbox (mean moved, covariance scaled by s^2), pixel-wise maximum. Its
  mean is the projection of the object origin when that lies on the object's visible box, else (truncated or
  hidden centre) the mask centroid as in the paper. Why: the centroid moves with occlusion and truncation, and
  reading the origin from it takes a long offset regression that the small CPU-trained network did not learn
  (measured on training views at epoch 9: median 42 px between the predicted and true projected origin, worse
  than the 37 px of the peak itself); with the peak on the projected origin the offset is a small correction;
- ``cell_object`` (h, w): the object whose Gaussian is largest at each stride cell's centre, where that value
  exceeds ``MIN_CELL_WEIGHT`` (the published "simple bmasks"), else -1; ``cell_weight`` (h, w): that value;
- per object (padded to ``max_objects``): ``rotation``, ``translation`` (``camera_T_object``), ``shape_code``
  (from the decoder checkpoint's codes by object id; ``shape_code_valid`` false when the decoder has none),
  ``joint_code`` (normalized state), ``joint_type``, ``axis_direction``, ``axis_point_offset`` (the point of the
  joint axis nearest the object origin, minus the origin) and ``joint_state`` (metric).
"""

from __future__ import annotations

import numpy as np

from centerart.geometry.camera import Intrinsics, project
from centerart.models.encoder.inputs import Letterbox
from centerart.models.encoder.network import JOINT_TYPES, cell_centers

MIN_CELL_WEIGHT = 0.25
COV_FLOOR_PX2 = 0.25  # keeps a one-pixel object's Gaussian finite


def gaussian_image(mean_uv: np.ndarray, cov: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """exp(-d^T cov^-1 d / 2) at pixels ``uv`` (..., 2): the unnormalised Gaussian with peak 1 at ``mean_uv``."""
    inv = np.linalg.inv(cov + COV_FLOOR_PX2 * np.eye(2)).astype(np.float32)
    d = (uv - mean_uv).astype(np.float32)
    q = d[..., 0] ** 2 * inv[0, 0] + 2 * d[..., 0] * d[..., 1] * inv[0, 1] + d[..., 1] ** 2 * inv[1, 1]
    return np.exp(-0.5 * q)


def axis_point_nearest(origin: np.ndarray, direction: np.ndarray, point: np.ndarray) -> np.ndarray:
    """The point of the line (origin, unit direction) nearest ``point``."""
    d = direction / np.linalg.norm(direction)
    return origin + d * float(np.dot(point - origin, d))


def heatmap_centre(obj: dict, K: np.ndarray) -> np.ndarray:
    """Camera pixel of an object's heatmap peak: its projected origin if on its visible box, else the centroid."""
    t = np.asarray(obj["camera_T_object"], float)[:3, 3]
    uv, _ = project(t[None], K)
    x0, y0, x1, y1 = obj["bbox_xyxy"]
    if np.isfinite(uv).all() and x0 <= uv[0, 0] <= x1 and y0 <= uv[0, 1] <= y1:
        return uv[0]
    return np.asarray(obj["heatmap_gaussian"]["mean_uv"], float)


def input_gaussians(labels: dict, letterbox: Letterbox) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """(label index, mean, covariance) in input pixels of every object whose Gaussian centre lands in the input."""
    out = []
    K = np.asarray(labels["K"], float)
    for k, obj in enumerate(labels["objects"]):
        g = obj["heatmap_gaussian"]
        mean = letterbox.to_input_pixels(heatmap_centre(obj, K))
        if 0 <= mean[0] <= letterbox.width - 1 and 0 <= mean[1] <= letterbox.height - 1:
            out.append((k, mean, np.asarray(g["cov_uv"], float) * letterbox.scale**2))
    return out


def build_targets(
    labels: dict, letterbox: Letterbox, codes: dict[str, np.ndarray], code_dim: int, stride: int, max_objects: int
) -> dict[str, np.ndarray]:
    camera = Intrinsics.from_matrix(labels["K"], labels["width"], labels["height"])
    h_in, w_in = letterbox.height, letterbox.width
    gaussians = input_gaussians(labels, letterbox)[:max_objects]
    v, u = np.mgrid[0:h_in, 0:w_in]
    pix = np.stack([u, v], axis=-1).astype(np.float32)
    cells = cell_centers(-(-h_in // stride), -(-w_in // stride), stride).numpy().astype(float)
    heat = np.zeros((h_in, w_in), np.float32)
    cell_vals = np.zeros((len(gaussians), *cells.shape[:2]))
    for n, (_, mean, cov) in enumerate(gaussians):
        heat = np.maximum(heat, gaussian_image(mean, cov, pix))
        cell_vals[n] = gaussian_image(mean, cov, cells)
    targets = _object_targets([labels["objects"][k] for k, _, _ in gaussians], codes, code_dim, max_objects)
    if gaussians:
        best = cell_vals.argmax(0)
        weight = cell_vals.max(0)
        cell_object = np.where(weight > MIN_CELL_WEIGHT, best, -1)
    else:
        weight, cell_object = np.zeros(cells.shape[:2]), np.full(cells.shape[:2], -1)
    targets.update(
        heatmap=heat.astype(np.float32),
        cell_object=cell_object.astype(np.int64),
        cell_weight=weight.astype(np.float32),
        K=letterbox.intrinsics(camera).K.astype(np.float32),
    )
    return targets


def _object_targets(objects: list[dict], codes: dict, code_dim: int, max_objects: int) -> dict[str, np.ndarray]:
    m = max_objects
    t = {
        "rotation": np.tile(np.eye(3, dtype=np.float32), (m, 1, 1)),
        "translation": np.zeros((m, 3), np.float32),
        "shape_code": np.zeros((m, code_dim), np.float32),
        "shape_code_valid": np.zeros(m, bool),
        "joint_code": np.zeros(m, np.float32),
        "joint_type": np.zeros(m, np.int64),
        "axis_direction": np.tile(np.array([0, 0, 1], np.float32), (m, 1)),
        "axis_point_offset": np.zeros((m, 3), np.float32),
        "joint_state": np.zeros(m, np.float32),
        "present": np.zeros(m, bool),
    }
    for n, obj in enumerate(objects):
        pose = np.asarray(obj["camera_T_object"], float)
        joint = obj["joint"]
        direction = np.asarray(joint["axis_direction_camera"], float)
        direction /= np.linalg.norm(direction)
        on_axis = axis_point_nearest(np.asarray(joint["axis_origin_camera"], float), direction, pose[:3, 3])
        t["rotation"][n], t["translation"][n] = pose[:3, :3], pose[:3, 3]
        code = codes.get(obj["object_id"])
        if code is not None:
            t["shape_code"][n], t["shape_code_valid"][n] = code, True
        t["joint_code"][n] = joint["state_normalized"]
        t["joint_type"][n] = JOINT_TYPES.index(joint["type"])
        t["axis_direction"][n], t["axis_point_offset"][n] = direction, on_axis - pose[:3, 3]
        t["joint_state"][n], t["present"][n] = joint["state"], True
    return t
