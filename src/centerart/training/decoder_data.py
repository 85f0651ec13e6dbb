"""Decoder training data: the validation split and per-item point draws over SDF states in memory.

The states themselves (one object at one joint state, points subsampled) are loaded by
:func:`centerart.sdf.samples.load_states`, which inference and evaluation use too.

Split (deterministic given the seed):

- held-out *objects*: a share of the objects is never trained on; at validation time their shape code is fitted
  with the decoder frozen (DeepSDF test-time optimisation), which measures generalisation to new shapes;
- held-out *states*: for every training object, some joint states are left out; the object's trained code is
  evaluated at the unseen joint codes, which measures interpolation over the joint.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import asdict, dataclass, field

import numpy as np
import torch
from torch.utils.data import Dataset

from centerart.sdf.samples import StateData
from centerart.utils.seeding import item_rng


@dataclass
class DecoderSplit:
    train_objects: list[str]
    heldout_objects: list[str]
    heldout_states: dict[str, list[int]] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> DecoderSplit:
        return cls(
            list(d["train_objects"]), list(d["heldout_objects"]), {k: list(v) for k, v in d["heldout_states"].items()}
        )

    def role(self, object_id: str, state_index: int) -> str:
        """``train``, ``heldout_state`` or ``heldout_object``."""
        if object_id in self.heldout_objects:
            return "heldout_object"
        if state_index in self.heldout_states.get(object_id, []):
            return "heldout_state"
        return "train"


def make_split(
    states: list[StateData], seed: int, heldout_object_fraction: float, heldout_states_per_object: int
) -> DecoderSplit:
    """Hold out ``round(fraction * objects)`` objects (at least one when there are 3 or more and the fraction
    is positive) and, per remaining object with more than ``heldout_states_per_object + 1`` states, that many
    interior states (never the first or last, so held-out states test interpolation, not extrapolation)."""
    by_obj: dict[str, list[int]] = defaultdict(list)
    for s in states:
        by_obj[s.object_id].append(s.state_index)
    objects = sorted(by_obj)
    n_out = round(heldout_object_fraction * len(objects))
    if heldout_object_fraction > 0 and n_out == 0 and len(objects) >= 3:
        n_out = 1
    n_out = min(n_out, len(objects) - 1)
    rng = item_rng(seed, "split")
    heldout = sorted(rng.choice(objects, n_out, replace=False).tolist()) if n_out > 0 else []
    train = [o for o in objects if o not in heldout]
    hs = {}
    for o in train:
        idx = sorted(by_obj[o])
        interior = idx[1:-1]
        if heldout_states_per_object > 0 and len(idx) > heldout_states_per_object + 1 and interior:
            k = min(heldout_states_per_object, len(interior))
            hs[o] = sorted(int(i) for i in item_rng(seed, "states", o).choice(interior, k, replace=False))
    return DecoderSplit(train, heldout, hs)


def surface_bounds(states: list[StateData], band: float = 0.01, pad: float = 0.05) -> np.ndarray:
    """(2, 3) box around all points with |sdf| < band, padded by ``pad`` metres (object frame)."""
    pts = np.concatenate([s.points[np.abs(s.sdf) < band] for s in states])
    if len(pts) == 0:
        pts = np.concatenate([s.points for s in states])
    return np.stack([pts.min(0) - pad, pts.max(0) + pad])


class PointBatchDataset(Dataset):
    """Items = (object, state); each draw returns ``points_per_item`` random points of that state.

    The draw uses the torch RNG (seeded by Lightning's ``seed_everything``), so every epoch sees new points.
    """

    def __init__(self, states: list[StateData], code_index: dict[str, int], points_per_item: int, min_length: int = 0):
        self.states = states
        # Small datasets repeat their items so that an "epoch" is long enough to amortise per-epoch overhead.
        self.length = max(len(states), min_length)
        self.code_index = code_index
        self.points_per_item = points_per_item
        self._tensors = [
            (
                torch.from_numpy(s.points),
                torch.from_numpy(s.sdf),
                torch.from_numpy(s.grasp_points),
                torch.from_numpy(s.grasp_distance),
            )
            for s in states
        ]

    def __len__(self) -> int:
        return self.length

    def __getitem__(self, i: int) -> dict[str, torch.Tensor]:
        return self.item(i)

    def item(self, i: int, generator: torch.Generator | None = None) -> dict[str, torch.Tensor]:
        """Item ``i`` with its points drawn from ``generator`` (default: the global torch RNG)."""
        i = i % len(self.states)
        s = self.states[i]
        pts, sdf, gp, gd = self._tensors[i]
        idx = torch.randint(0, len(pts), (self.points_per_item,), generator=generator)
        return {
            "code_index": torch.tensor(self.code_index[s.object_id]),
            "joint": torch.tensor(s.joint, dtype=torch.float32),
            "points": pts[idx],
            "sdf": sdf[idx],
            "grasp_points": gp[idx],
            "grasp_distance": gd[idx],
        }
