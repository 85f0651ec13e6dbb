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

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from centerart.errors import CenterArtError
from centerart.utils.atomic import atomic_write_bytes


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
        path = sample_path(folder, self.object_id, self.state_index)
        buf = io.BytesIO()
        np.savez(
            buf,
            object_id=np.array(self.object_id),
            state_index=np.array(self.state_index),
            q=np.array(self.q),
            q_normalized=np.array(self.q_normalized),
            joint_type=np.array(self.joint_type),
            points=np.asarray(self.points, np.float32),
            sdf=np.asarray(self.sdf, np.float32),
            grasp_points=np.asarray(self.grasp_points, np.float32),
            grasp_distance=np.asarray(self.grasp_distance, np.float32),
        )
        atomic_write_bytes(path, buf.getvalue())
        return path

    @classmethod
    def load(cls, path: Path) -> SdfSamples:
        path = Path(path)
        try:
            with np.load(path) as d:
                return cls(
                    object_id=str(d["object_id"]),
                    state_index=int(d["state_index"]),
                    q=float(d["q"]),
                    q_normalized=float(d["q_normalized"]),
                    joint_type=str(d["joint_type"]),
                    points=d["points"],
                    sdf=d["sdf"],
                    grasp_points=d["grasp_points"],
                    grasp_distance=d["grasp_distance"],
                )
        except (OSError, KeyError, ValueError) as err:
            raise CenterArtError(f"{path}: not a readable SDF sample file ({err})") from None


def sample_path(folder: Path, object_id: str, state_index: int) -> Path:
    return Path(folder) / object_id / f"state_{state_index:02d}.npz"


def list_sample_files(folder: Path) -> list[Path]:
    """Every ``<object_id>/state_*.npz`` under ``folder``, sorted."""
    files = sorted(Path(folder).glob("*/state_*.npz"))
    if not files:
        raise CenterArtError(f"{folder}: no SDF sample files (<object_id>/state_*.npz) found")
    return files
