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

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from centerart.errors import CenterArtError
from centerart.utils.atomic import atomic_write_bytes


@dataclass
class StateLabels:
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
        path = state_path(folder, self.object_id, self.state_index)
        buf = io.BytesIO()
        np.savez_compressed(
            buf,
            object_id=np.array(self.object_id),
            state_index=np.array(self.state_index),
            q=np.array(self.q),
            q_normalized=np.array(self.q_normalized),
            joint_type=np.array(self.joint_type),
            direction=np.array(self.direction),
            poses=np.asarray(self.poses, np.float32).reshape(-1, 4, 4),
            displacement=np.asarray(self.displacement, np.float32),
            failed_poses=np.asarray(self.failed_poses, np.float32).reshape(-1, 4, 4),
            failed_displacement=np.asarray(self.failed_displacement, np.float32),
        )
        atomic_write_bytes(path, buf.getvalue())
        return path

    @classmethod
    def load(cls, path: Path) -> StateLabels:
        path = Path(path)
        try:
            with np.load(path) as d:
                return cls(
                    object_id=str(d["object_id"]),
                    state_index=int(d["state_index"]),
                    q=float(d["q"]),
                    q_normalized=float(d["q_normalized"]),
                    joint_type=str(d["joint_type"]),
                    direction=int(d["direction"]),
                    poses=d["poses"].astype(np.float64),
                    displacement=d["displacement"].astype(np.float64),
                    failed_poses=d["failed_poses"].astype(np.float64),
                    failed_displacement=d["failed_displacement"].astype(np.float64),
                )
        except (OSError, KeyError, ValueError) as err:
            raise CenterArtError(f"{path}: not a readable grasp-label file ({err})") from None


def state_path(folder: Path, object_id: str, state_index: int) -> Path:
    return Path(folder) / object_id / f"state_{state_index:02d}.npz"


def load_object_labels(folder: Path, object_id: str) -> list[StateLabels]:
    """All states of one object, sorted by state index."""
    files = sorted((Path(folder) / object_id).glob("state_*.npz"))
    if not files:
        raise CenterArtError(f"{Path(folder) / object_id}: no grasp labels (state_*.npz) found")
    return [StateLabels.load(f) for f in files]
