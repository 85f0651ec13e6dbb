"""Grasp-label files: one per (object, joint state).

Layout::

    LABELS/manifest.json
    LABELS/<object_id>/state_<k:02d>.npz

Each ``.npz`` holds (frames: the object's canonical frame; units: metres, radians):

==================  ==========  ====================================================================
key                 shape       meaning
==================  ==========  ====================================================================
object_id           ()          str
state_index         ()          int, k
q                   ()          target joint state (rad or m)
q_normalized        ()          (q - lower) / (upper - lower)
joint_type          ()          "revolute" | "prismatic"
direction           ()          +1: the trial opens the joint, -1: it closes it
poses               (N, 4, 4)   successful TCP poses (gripper.py convention), float32
displacement        (N,)        joint motion reached in the commanded direction (rad or m)
failed_poses        (M, 4, 4)   tried and failed TCP poses (negatives), float32
failed_displacement (M,)        their signed joint motion
==================  ==========  ====================================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from centerart.errors import CenterArtError
from centerart.utils.npz_records import load_record, save_record
from centerart.utils.npz_records import state_file as state_path

#: How the pose arrays of a label file are stored (an empty array keeps its (0, 4, 4) shape).
LABEL_SHAPES = {"poses": (-1, 4, 4), "failed_poses": (-1, 4, 4)}


@dataclass
class StateLabels:
    #: Checks of a file's arrays when it is read (utils/npz_records.py).
    SHAPES: ClassVar[dict] = {"poses": ("N", 4, 4), "displacement": ("N",), "failed_poses": ("M", 4, 4),
                              "failed_displacement": ("M",)}  # fmt: skip
    FINITE: ClassVar[tuple] = ("poses", "displacement", "failed_poses", "failed_displacement")

    object_id: str
    state_index: int
    q: float
    q_normalized: float
    joint_type: str
    direction: int
    poses: np.ndarray
    displacement: np.ndarray
    failed_poses: np.ndarray
    failed_displacement: np.ndarray

    @property
    def count(self) -> int:
        return len(self.poses)

    def save(self, folder: Path) -> Path:
        return save_record(
            state_path(folder, self.object_id, self.state_index),
            self,
            compressed=True,
            shapes=LABEL_SHAPES,
        )

    @classmethod
    def load(cls, path: Path) -> StateLabels:
        return load_record(cls, path, "grasp-label", dtype=np.float64)


def load_object_labels(folder: Path, object_id: str) -> list[StateLabels]:
    """All states of one object, sorted by state index."""
    files = sorted((Path(folder) / object_id).glob("state_*.npz"))
    if not files:
        raise CenterArtError(f"{Path(folder) / object_id}: no grasp labels (state_*.npz) found")
    return [StateLabels.load(f) for f in files]
