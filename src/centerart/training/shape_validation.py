"""The regressed shape code judged where the decoder has no code to compare it with: its decoded SDF at the object's
true surface.

Why: a sliced run validates on views of the decoder's held-out objects, which have no training code, so the code
L1 (``shape_code_l1``) is never measured there, and the ledger's figures (detection, pose, joint) improved for five
slices of ``training_runs/encoder-small-102`` while closed-loop SR did not; the stage analysis's code oracle says
the regressed code costs about as many test objects as the pose (``benchmarks/results/eval_scenes_s23/``).

The figure, per matched object of a view: ``points`` points drawn near the object's true surface at the view's joint
state (surface samples plus N(0, ``sigma_m``) noise, the decoder's near-surface training band), their true signed
distances, and the mean |clamp(D(z, j*, x)) - clamp(sdf*(x))| in mm, with z the regressed code, j* the true
normalized joint state and D the frozen decoder (canonical object frame, m; clamp as in the decoder's training
loss). The true pose and joint state are used, so the figure isolates the code. The points are seeded by the
object and its state, so every slice is judged on the same points.
"""

from __future__ import annotations

import zlib
from pathlib import Path

import numpy as np
import torch

from centerart.models.losses import LossConfig

SHAPE_POINTS = 2000
"""Points per object and state: with 8,000 the medians over the 50 validation views of ``encoder-small-102`` move by
0.09 and 0.05 mm (its slices 1 and 5: 15.15 -> 15.24, 13.36 -> 13.41 mm; session 24)."""
SHAPE_SIGMA_M = 0.005


class HeldOutShapeError:
    """``judge(code, label) -> mm or None``: the decoded-SDF error of a regressed ``code`` (D,) for one labelled
    object (a view's ``labels.json`` entry: ``object_id``, ``joint.state``, ``joint.state_normalized``), or None
    when ``objects`` has no folder of that id."""

    def __init__(self, decoder, objects: Path, points: int = SHAPE_POINTS, clamp: float = LossConfig.sdf_clamp):
        decoder.eval()
        decoder.requires_grad_(False)
        self.decoder, self.objects, self.points, self.clamp = decoder, Path(objects), points, clamp
        self._samples: dict[tuple[str, float], tuple[torch.Tensor, torch.Tensor] | None] = {}

    def __call__(self, code: np.ndarray, label: dict) -> float | None:
        joint = label["joint"]
        samples = self.samples(label["object_id"], float(joint["state"]))
        if samples is None:
            return None
        points, true_sdf = samples
        z = torch.as_tensor(np.asarray(code, np.float32)).reshape(1, -1).expand(len(points), -1)
        j = torch.full((len(points),), float(joint["state_normalized"]))
        with torch.no_grad():
            pred = self.decoder.sdf_only(z, j, points).reshape(-1).clamp(-self.clamp, self.clamp)
        return 1000.0 * float((pred - true_sdf.clamp(-self.clamp, self.clamp)).abs().mean())

    def samples(self, object_id: str, state: float):
        """(points (N, 3), true SDF (N,)) near ``object_id``'s surface at joint state ``state`` (m or rad),
        canonical frame, m; cached; None when the object's folder is missing."""
        key = (object_id, round(state, 6))
        if key not in self._samples:
            self._samples[key] = self._draw(object_id, state)
        return self._samples[key]

    def _draw(self, object_id: str, state: float):
        from centerart.assets.articulated_object import ArticulatedObject
        from centerart.sdf.sampling import SamplingConfig, sample_points, signed_distance
        from centerart.sdf.surface import object_surface

        folder = self.objects / object_id
        if not folder.is_dir():
            return None
        surface = object_surface(ArticulatedObject.load(folder), state)
        rng = np.random.default_rng(zlib.crc32(f"{object_id}:{state:.6f}".encode()))
        cfg = SamplingConfig(near_fraction=1.0, far_fraction=0.0, near_sigma=SHAPE_SIGMA_M)
        signed = signed_distance(surface, sample_points(surface.mesh, self.points, cfg, rng), cfg, rng)
        return torch.as_tensor(signed.points), torch.as_tensor(signed.sdf)
