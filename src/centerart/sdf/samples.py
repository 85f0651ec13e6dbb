"""SDF sample files: one per (object, joint state), the decoder's training data.

Layout::

    SDF/manifest.json
    SDF/<object_id>/state_<k:02d>.npz

Each ``.npz`` holds (frame: the object's canonical frame; units: metres, radians):

==============  ==========  ==========================================================================
key             shape       meaning
==============  ==========  ==========================================================================
object_id       ()          str
state_index     ()          int, k (matches the grasp-label file of the same state)
q               ()          target joint state (rad or m)
q_normalized    ()          (q - lower) / (upper - lower)
joint_type      ()          "revolute" | "prismatic"
points          (N, 3)      query points, float32
sdf             (N,)        signed distance to the true surface at state q, positive outside, float32
                            (real triangle soups: to the soup thickened by ``sampling.soup_shell``, see
                            :mod:`centerart.sdf.sampling`)
grasp_points    (N, 5, 3)   control points (gripper.CONTROL_POINTS_TCP) of the labelled grasp whose TCP is
                            nearest to the point, float32; zeros when the state has no labels
grasp_distance  (N,)        distance from the point to that grasp's TCP position, float32 (inf if none)
==============  ==========  ==========================================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from centerart.errors import CenterArtError
from centerart.utils.npz_records import load_record, save_record
from centerart.utils.npz_records import state_file as sample_path


@dataclass
class SdfSamples:
    object_id: str
    state_index: int
    q: float
    q_normalized: float
    joint_type: str
    points: np.ndarray
    sdf: np.ndarray
    grasp_points: np.ndarray
    grasp_distance: np.ndarray

    @property
    def has_grasps(self) -> bool:
        return bool(np.isfinite(self.grasp_distance).any())

    def save(self, folder: Path) -> Path:
        return save_record(sample_path(folder, self.object_id, self.state_index), self)

    @classmethod
    def load(cls, path: Path) -> SdfSamples:
        return load_record(cls, path, "SDF sample")


def list_sample_files(folder: Path) -> list[Path]:
    """Every ``<object_id>/state_*.npz`` under ``folder``, sorted."""
    files = sorted(Path(folder).glob("*/state_*.npz"))
    if not files:
        raise CenterArtError(f"{folder}: no SDF sample files (<object_id>/state_*.npz) found")
    return files
