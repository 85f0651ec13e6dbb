"""Shape codes on the decoder's learned shapes: the encoder's regressed code, snapped to a training code.

The encoder regresses a shape code with an L1 loss; where it is unsure the regression lands between the
training codes, which the decoder turns into a blurred shape whose grasp positions lie off every real handle
(the scene evaluation measured 35 mm Chamfer even on training objects). Two ways back onto the learned shapes:

- ``nearest``: the training code closest to the regressed one (L2);
- ``best_fit``: of the ``BEST_FIT_CANDIDATES`` training codes closest to the regressed one, the one whose decoded
  surface best explains the object's observed depth points: lowest median |SDF| at those points mapped into the
  object frame by the predicted pose (points in the instance region that belong to a neighbour only add a
  constant to every candidate's score, and the median ignores them while they are a minority).

Frames: ``observed`` points in the camera frame (m); ``camera_T_object`` maps the object frame into it.
"""

from __future__ import annotations

import numpy as np
import torch

BEST_FIT_CANDIDATES = 8
BEST_FIT_POINTS = 1500  # observed points scored per candidate (a random subset, seeded)


def nearest_code(code: np.ndarray, codes: np.ndarray) -> int:
    """Index of the training code (K, D) closest to ``code`` (D,)."""
    return int(np.argmin(np.linalg.norm(codes - code[None], axis=1)))


def best_fit_code(
    decoder, code: np.ndarray, joint: float, codes: np.ndarray, observed: np.ndarray, camera_T_object: np.ndarray
) -> tuple[int, dict]:
    """Index of the candidate training code whose surface fits the observed points best, and the scores."""
    order = np.argsort(np.linalg.norm(codes - code[None], axis=1))[:BEST_FIT_CANDIDATES]
    pts = np.asarray(observed, np.float64).reshape(-1, 3)
    if len(pts) < 20:
        return int(order[0]), {"candidates": order.tolist(), "reason": "too few observed points"}
    if len(pts) > BEST_FIT_POINTS:
        pts = pts[np.random.default_rng(0).choice(len(pts), BEST_FIT_POINTS, replace=False)]
    object_T_camera = np.linalg.inv(camera_T_object)
    local = torch.as_tensor(pts @ object_T_camera[:3, :3].T + object_T_camera[:3, 3], dtype=torch.float32)
    n = len(local)
    z = torch.as_tensor(np.repeat(codes[order].astype(np.float32), n, axis=0))
    with torch.no_grad():
        sdf = decoder.sdf_only(z, torch.full((len(z),), float(joint)), local.repeat(len(order), 1))
    scores = np.median(np.abs(np.asarray(sdf, np.float64).reshape(len(order), n)), axis=1)
    return int(order[int(np.argmin(scores))]), {"candidates": order.tolist(), "median_abs_sdf_m": scores.tolist()}
