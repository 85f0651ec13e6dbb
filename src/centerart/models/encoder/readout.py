"""From encoder maps to objects: heatmap peaks, values read around each peak, instance masks.

Thresholds (documented, in code, printed by reports that use them):

- a peak is a local maximum of the heatmap at least ``PEAK_MIN_DISTANCE_FRACTION`` of the image width away
  from a higher one and above ``peak_threshold`` (default :data:`PEAK_THRESHOLD`);
- an object's values are the heatmap-weighted mean over the stride cells within ``radius_cells`` (the encoder
  config's ``read_radius_cells``; None: no limit) of its peak whose centres the object's instance region
  covers (rotations are averaged as raw matrices, then projected to SO(3));
- instance regions: watershed of the negated heatmap from the peaks, restricted to heatmap > ``MASK_THRESHOLD``.

Every quantity is in the OpenCV camera frame (m, rad), which the letterboxed input shares with the camera.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch

from centerart.models.encoder.network import (
    JOINT_TYPES,
    EncoderOutput,
    cell_centers,
    object_translation,
    rotation_from_raw,
)

PEAK_THRESHOLD = 0.5
PEAK_MIN_DISTANCE_FRACTION = 1.0 / 64.0  # the published 10 px at 960 px width is about 1/96; a little wider
MASK_THRESHOLD = 0.25
READ_RADIUS_CELLS = 1  # read_objects's default: the 3x3 cells read before EncoderConfig.read_radius_cells


@dataclass
class Detection:
    """One detected object, camera frame (OpenCV, m, rad); pixels in the encoder's input image."""

    score: float
    peak_uv: np.ndarray
    camera_T_object: np.ndarray
    shape_code: np.ndarray
    joint_code: float
    joint_type: str
    joint_type_probability: float
    axis_direction: np.ndarray
    axis_point: np.ndarray
    joint_state: float
    mask: np.ndarray | None = field(default=None, repr=False)


def find_peaks(heatmap: np.ndarray, threshold: float = PEAK_THRESHOLD) -> np.ndarray:
    """(N, 2) integer (u, v) of heatmap peaks, highest first."""
    from skimage.feature import peak_local_max

    min_distance = max(2, round(heatmap.shape[1] * PEAK_MIN_DISTANCE_FRACTION))
    rc = peak_local_max(heatmap, min_distance=min_distance, threshold_abs=threshold, exclude_border=False)
    return rc[:, ::-1].astype(np.int64)


def instance_regions(heatmap: np.ndarray, peaks_uv: np.ndarray) -> np.ndarray:
    """(H, W) int: k + 1 where peak k's watershed region lies (heatmap > MASK_THRESHOLD), else 0."""
    from skimage.segmentation import watershed

    markers = np.zeros(heatmap.shape, np.int32)
    for k, (u, v) in enumerate(peaks_uv):
        markers[v, u] = k + 1
    return watershed(-heatmap, markers=markers, mask=heatmap > MASK_THRESHOLD)


def read_objects(
    out: EncoderOutput,
    K: np.ndarray,
    index: int = 0,
    peak_threshold: float = PEAK_THRESHOLD,
    radius_cells: int | None = READ_RADIUS_CELLS,
) -> list[Detection]:
    """Detections of image ``index`` of a batch of encoder outputs; ``K`` is the input's 3x3 intrinsics; values are
    read over the region's cells within ``radius_cells`` of each peak, None: the whole region (pass the encoder
    config's ``read_radius_cells``)."""
    heat = out.heatmap[index].detach().float().cpu().numpy()
    peaks = find_peaks(heat, peak_threshold)
    if len(peaks) == 0:
        return []
    regions = instance_regions(heat, peaks)
    dense = {k: v[index].detach().float().cpu() for k, v in out.dense.items()}
    h, w = next(iter(dense.values())).shape[-2:]
    centers = cell_centers(h, w, out.stride).numpy()
    cu = np.clip(np.round(centers[..., 0]).astype(int), 0, heat.shape[1] - 1)
    cv = np.clip(np.round(centers[..., 1]).astype(int), 0, heat.shape[0] - 1)
    cell_region, cell_heat = regions[cv, cu], heat[cv, cu]
    return [
        _read_one(dense, centers, cell_region, cell_heat, k, peak, heat, K, regions == k + 1, out.stride, radius_cells)
        for k, peak in enumerate(peaks)
    ]


def _read_one(dense, centers, cell_region, cell_heat, k, peak, heat, K, mask, stride, radius) -> Detection:
    ci, cj = int(peak[1]) // stride, int(peak[0]) // stride
    ii, jj = np.mgrid[0 : cell_region.shape[0], 0 : cell_region.shape[1]]
    near = True if radius is None else (np.abs(ii - ci) <= radius) & (np.abs(jj - cj) <= radius)
    use = near & (cell_region == k + 1)
    use[min(ci, use.shape[0] - 1), min(cj, use.shape[1] - 1)] = True
    sel = torch.from_numpy(use)
    wts = torch.from_numpy(np.maximum(cell_heat[use], 1e-3)).float()
    wts = wts / wts.sum()
    vals = {name: (f[:, sel] * wts).sum(dim=1) for name, f in dense.items()}
    cells = torch.from_numpy(centers[use]).float()
    # Translation per cell first (each cell's offset points from its own centre), then averaged.
    per_cell = object_translation(
        cells, dense["center_offset"][:, sel].T, dense["center_depth"][0, sel],
        torch.as_tensor(K, dtype=torch.float32).expand(len(cells), 3, 3),
    )  # fmt: skip
    t = (per_cell * wts[:, None]).sum(0).numpy()
    rot = rotation_from_raw(vals["rotation"][None])[0].numpy()
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rot, t
    type_p = torch.softmax(vals["joint_type_logits"], 0).numpy()
    axis = vals["axis_direction"].numpy()
    return Detection(
        score=float(heat[peak[1], peak[0]]),
        peak_uv=peak.copy(),
        camera_T_object=pose,
        shape_code=vals["shape_code"].numpy(),
        joint_code=float(np.clip(vals["joint_code"][0], 0.0, 1.0)),
        joint_type=JOINT_TYPES[int(type_p.argmax())],
        joint_type_probability=float(type_p.max()),
        axis_direction=axis / max(np.linalg.norm(axis), 1e-9),
        axis_point=t + vals["axis_point_offset"].numpy(),
        joint_state=float(vals["joint_state"][0]),
        mask=mask,
    )
