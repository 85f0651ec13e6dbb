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

In memory, :func:`load_states` reads a folder's files as :class:`StateData` (each state's points a seeded random
subset); training, code fitting for display and evaluation all load their samples through it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
from tqdm import tqdm

from centerart.errors import CenterArtError
from centerart.utils.npz_records import load_record, save_record
from centerart.utils.npz_records import state_file as sample_path
from centerart.utils.seeding import item_rng


@dataclass
class SdfSamples:
    #: Checks of a file's arrays when it is read (utils/npz_records.py); grasp_distance is inf without labels.
    SHAPES: ClassVar[dict] = {"points": ("N", 3), "sdf": ("N",), "grasp_points": ("N", 5, 3), "grasp_distance": ("N",)}
    FINITE: ClassVar[tuple] = ("points", "sdf", "grasp_points")
    NO_NAN: ClassVar[tuple] = ("grasp_distance",)

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


@dataclass
class StateData:
    """One (object, joint state) with its points subsampled to at most ``max_points`` (object frame, m)."""

    object_id: str
    state_index: int
    joint: float  # normalized joint state in [0, 1]
    points: np.ndarray  # (N, 3) float32
    sdf: np.ndarray  # (N,)
    grasp_points: np.ndarray  # (N, 5, 3)
    grasp_distance: np.ndarray  # (N,)


def load_states(folder: Path, max_points: int | None = None, seed: int = 0, progress: bool = True) -> list[StateData]:
    """Every SDF sample file under ``folder``; each keeps a seeded random subset of ``max_points`` points."""
    states = []
    for path in tqdm(list_sample_files(folder), desc="load sdf samples", disable=not progress):
        s = SdfSamples.load(path)  # shapes and finiteness checked on reading
        n = len(s.points)
        idx = np.arange(n)
        if max_points is not None and n > max_points:
            idx = np.sort(item_rng(seed, "subsample", s.object_id, s.state_index).choice(n, max_points, replace=False))
        states.append(
            StateData(
                object_id=s.object_id,
                state_index=s.state_index,
                joint=float(s.q_normalized),
                points=np.ascontiguousarray(s.points[idx], np.float32),
                sdf=np.ascontiguousarray(s.sdf[idx], np.float32),
                grasp_points=np.ascontiguousarray(s.grasp_points[idx], np.float32),
                grasp_distance=np.ascontiguousarray(s.grasp_distance[idx], np.float32),
            )
        )
    return states
