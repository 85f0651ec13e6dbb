"""One-to-one matching of predicted to true objects by 3-D centre distance (Hungarian assignment)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment


def match_points(pred: np.ndarray, true: np.ndarray, max_distance: float) -> list[tuple[int, int]]:
    """Pairs (pred index, true index) minimising the summed distance, keeping pairs closer than ``max_distance``.

    ``pred`` (N, 3) and ``true`` (M, 3) in one frame and unit (m). Unmatched entries are misses / false positives.
    """
    pred, true = np.asarray(pred, float).reshape(-1, 3), np.asarray(true, float).reshape(-1, 3)
    if len(pred) == 0 or len(true) == 0:
        return []
    dist = np.linalg.norm(pred[:, None, :] - true[None, :, :], axis=-1)
    rows, cols = linear_sum_assignment(dist)
    return [(int(r), int(c)) for r, c in zip(rows, cols, strict=True) if dist[r, c] < max_distance]
