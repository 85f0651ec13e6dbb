"""Grasps from the decoder: candidates near the predicted surface of the moving part, scored, NMS'd and ranked.

All poses are TCP poses (``grasps/gripper.py``) in the object's canonical frame, metres.

1. Candidates: query points of the final reconstruction level (a thin shell around the predicted surface) with
   |sdf| < ``surface_band`` whose predicted grasp position is close to them (|offset| < ``max_offset``). Far
   from any label, the training target is the nearest label, so a large predicted offset means "the grasp is
   elsewhere": such points vote for a grasp but are not used as candidates.
2. Moving part: the candidate's grasp position must be on the part that moves with the joint. The decoder is
   queried there at the joint code +-``moving_delta``; if the SDF there does not change by ``moving_sdf_change``
   metres, the point is on a static part and is dropped (``require_moving``).
3. Consistency: the grasp predicted at a candidate is supported by the other candidates whose predicted grasp
   lies within ``agree_distance`` and ``agree_angle_deg`` of it (rotation counted with the finger-swapped
   gripper as equal). Confidence = support / (support + ``support_half``) * exp(-|offset| / ``offset_scale``),
   in [0, 1): many neighbours that agree and a small offset mean a grasp the network is sure about.
4. Non-maximum suppression (greedy by confidence; suppress within ``nms_distance`` and ``nms_angle_deg``), then
   the ``top_k`` best, ranked by confidence.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from scipy.spatial import cKDTree

from centerart.grasps.gripper import FLIP_Z
from centerart.inference.reconstruction import Reconstruction
from centerart.models.decoder import SGDFDecoder, decode_outputs


@dataclass(frozen=True)
class GraspExtractionConfig:
    surface_band: float = 0.02
    max_offset: float = 0.02
    agree_distance: float = 0.015
    agree_angle_deg: float = 20.0
    support_half: float = 5.0
    offset_scale: float = 0.01
    require_moving: bool = True
    moving_delta: float = 0.05
    moving_sdf_change: float = 0.002
    nms_distance: float = 0.02
    nms_angle_deg: float = 30.0
    top_k: int = 20
    max_candidates: int = 4000


@dataclass
class DecoderGrasps:
    poses: np.ndarray  # (K, 4, 4) TCP poses, object frame, ranked best first
    scores: np.ndarray  # (K,) confidence in [0, 1)
    support: np.ndarray  # (K,) number of agreeing candidates

    def __len__(self) -> int:
        return len(self.poses)


def rotation_angle_symmetric(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Angle (rad) between rotations (..., 3, 3), counting a 180-degree turn about the approach axis as equal."""

    def angle(A, B):
        tr = np.einsum("...ij,...ij->...", A, B)  # trace(A^T B)
        return np.arccos(np.clip((tr - 1.0) / 2.0, -1.0, 1.0))

    return np.minimum(angle(Ra, Rb), angle(Ra, Rb @ FLIP_Z[:3, :3]))


def _empty() -> DecoderGrasps:
    return DecoderGrasps(np.zeros((0, 4, 4)), np.zeros(0), np.zeros(0, int))


def extract_grasps(
    decoder: SGDFDecoder,
    code: np.ndarray,
    joint: float,
    recon: Reconstruction,
    cfg: GraspExtractionConfig = GraspExtractionConfig(),
    device: str | torch.device = "cpu",
) -> DecoderGrasps:
    """Ranked grasps on the moving part at normalized joint code ``joint`` (see module doc)."""
    if recon.raw is None or len(recon.points) == 0:
        return _empty()
    out = decode_outputs(recon.raw)
    offset = out.offset.numpy()
    off_norm = np.linalg.norm(offset, axis=1)
    keep = (np.abs(recon.sdf) < cfg.surface_band) & (off_norm < cfg.max_offset)
    if not keep.any():
        return _empty()
    idx = np.flatnonzero(keep)
    if len(idx) > cfg.max_candidates:  # the best-offset candidates; deterministic
        idx = idx[np.argsort(off_norm[idx], kind="stable")[: cfg.max_candidates]]
    pos = recon.points[idx] + offset[idx]
    rot = out.rotation.numpy()[idx]
    off = off_norm[idx]
    if cfg.require_moving:
        moving = _on_moving_part(decoder, code, joint, pos, cfg, device)
        pos, rot, off = pos[moving], rot[moving], off[moving]
        if len(pos) == 0:
            return _empty()
    # Consistency: neighbours (by predicted grasp position) whose predicted rotation agrees.
    tree = cKDTree(pos)
    support = np.zeros(len(pos), int)
    max_angle = np.deg2rad(cfg.agree_angle_deg)
    for i, nb in enumerate(tree.query_ball_point(pos, cfg.agree_distance)):
        nb = np.asarray(nb)
        nb = nb[nb != i]
        if len(nb):
            support[i] = int((rotation_angle_symmetric(rot[i][None], rot[nb]) < max_angle).sum())
    score = support / (support + cfg.support_half) * np.exp(-off / cfg.offset_scale)
    order = np.argsort(-score, kind="stable")
    chosen: list[int] = []
    nms_angle = np.deg2rad(cfg.nms_angle_deg)
    for i in order:
        if len(chosen) >= cfg.top_k:
            break
        if chosen:
            c = np.asarray(chosen)
            close = np.linalg.norm(pos[c] - pos[i], axis=1) < cfg.nms_distance
            if close.any() and (rotation_angle_symmetric(rot[i][None], rot[c[close]]) < nms_angle).any():
                continue
        chosen.append(int(i))
    c = np.asarray(chosen, int)
    poses = np.tile(np.eye(4), (len(c), 1, 1))
    poses[:, :3, :3] = rot[c]
    poses[:, :3, 3] = pos[c]
    return DecoderGrasps(poses, score[c], support[c])


def _on_moving_part(decoder, code, joint, pos, cfg, device) -> np.ndarray:
    """True where the predicted SDF at the grasp position changes when the joint moves by +-moving_delta."""
    x = torch.as_tensor(pos, dtype=torch.float32, device=device)
    z = torch.as_tensor(np.asarray(code, np.float32), device=device).expand(len(x), -1)
    change = np.zeros(len(pos))
    with torch.no_grad():
        base = decoder.sdf_only(z, torch.full((len(x),), float(joint), device=device), x)
        for j in (joint - cfg.moving_delta, joint + cfg.moving_delta):
            if 0.0 <= j <= 1.0:
                other = decoder.sdf_only(z, torch.full((len(x),), float(j), device=device), x)
                change = np.maximum(change, (other - base).abs().cpu().numpy())
    return change > cfg.moving_sdf_change


def predict_shape_and_grasps(
    decoder: SGDFDecoder,
    code: np.ndarray,
    joint: float,
    bounds: np.ndarray,
    mesh_cfg=None,
    grasp_cfg: GraspExtractionConfig = GraspExtractionConfig(),
    device: str | torch.device = "cpu",
) -> tuple[Reconstruction, DecoderGrasps]:
    """Mesh (coarse-to-fine) and ranked grasps of one object at normalized joint code ``joint`` (object frame)."""
    from centerart.inference.reconstruction import MeshConfig, reconstruct_object

    recon = reconstruct_object(decoder, code, joint, bounds, mesh_cfg or MeshConfig(), device)
    return recon, extract_grasps(decoder, code, joint, recon, grasp_cfg, device)
