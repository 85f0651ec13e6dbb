"""Decoder losses: clamped L1 on the SDF, a 5-control-point grasp loss with finger-swap symmetry, and a code prior.

All distances in metres, all points in the object's canonical frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import torch

from centerart.grasps.gripper import CONTROL_POINTS_TCP, FINGER_SWAP
from centerart.models.decoder import DecoderOutput

GraspWeighting = Literal["none", "label", "surface"]


@dataclass(frozen=True)
class LossConfig:
    sdf_clamp: float = 0.1
    """m; SDF prediction and target are clamped to +-this before the L1 (DeepSDF), in the loss only."""
    sdf_weight: float = 10.0
    grasp_weight: float = 1.0
    code_weight: float = 1e-4
    """Weight of the Gaussian code prior mean(|z|^2) (DeepSDF's 1/sigma^2 term)."""
    grasp_weighting: GraspWeighting = "label"
    """How each point's grasp term is weighted: ``none`` (every point equally, as published), ``label``
    (exp(-d/scale), d = distance from the point to the TCP of its nearest label) or ``surface`` (same with
    d = |sdf|). Far points have a discontinuous nearest-label target, so down-weighting them is expected to help."""
    grasp_weight_scale: float = 0.05
    """m; the decay length of the ``label``/``surface`` weighting."""
    grasp_moves_codes: bool = True
    """Whether the grasp term's gradient reaches the shape codes (as published). ``False``: the codes learn from
    the SDF and the code prior alone, the objective a code is fitted under at test time (``models/code_fitting``),
    so a code fitted to an object's surface is the code the grasp field was trained with; the decoder's weights
    still learn from both terms. Why: with it on, the top grasp opened 10 of 15 closed training objects with their
    trained codes and 2 of 15 with codes fitted to their SDF (``benchmarks/fitted_code_grasps.py``). Not the default:
    a slice trained with it off (``decoder-small-102-paper-reg`` slice 6) left the fitted codes at 2 of 15 and the
    closed loop level (``benchmarks/results/decoder_closed_loop/``, slice 6)."""


def control_points_torch(rotation: torch.Tensor, position: torch.Tensor) -> torch.Tensor:
    """(..., 5, 3) control points of TCP poses given as rotation (..., 3, 3) and position (..., 3)."""
    cp = torch.as_tensor(CONTROL_POINTS_TCP, dtype=rotation.dtype, device=rotation.device)
    return torch.einsum("...ij,kj->...ki", rotation, cp) + position[..., None, :]


def symmetric_control_point_error(pred_cp: torch.Tensor, gt_cp: torch.Tensor) -> torch.Tensor:
    """Mean per-control-point Euclidean distance (m), the smaller of the two finger assignments. Shape (...)."""
    swap = torch.as_tensor(FINGER_SWAP, device=pred_cp.device)
    direct = (pred_cp - gt_cp).norm(dim=-1).mean(-1)
    swapped = (pred_cp[..., swap, :] - gt_cp).norm(dim=-1).mean(-1)
    return torch.minimum(direct, swapped)


def grasp_point_weights(cfg: LossConfig, sdf_gt: torch.Tensor, grasp_distance: torch.Tensor) -> torch.Tensor:
    """Per-point weights of the grasp term; zero where the state has no labels (distance inf)."""
    valid = torch.isfinite(grasp_distance)
    if cfg.grasp_weighting == "none":
        w = torch.ones_like(sdf_gt)
    elif cfg.grasp_weighting == "label":
        w = torch.exp(-torch.where(valid, grasp_distance, torch.zeros_like(grasp_distance)) / cfg.grasp_weight_scale)
    elif cfg.grasp_weighting == "surface":
        w = torch.exp(-sdf_gt.abs() / cfg.grasp_weight_scale)
    else:
        raise ValueError(f"unknown grasp weighting {cfg.grasp_weighting!r}")
    return torch.where(valid, w, torch.zeros_like(w))


def decoder_loss(
    cfg: LossConfig,
    out: DecoderOutput,
    xyz: torch.Tensor,
    sdf_gt: torch.Tensor,
    grasp_points_gt: torch.Tensor,
    grasp_distance: torch.Tensor,
    codes: torch.Tensor | None = None,
) -> dict[str, torch.Tensor]:
    """Loss terms for a flat batch of N points. ``codes``: the distinct shape codes used in the batch (K, D).

    Returns ``loss`` (the weighted sum) and the unweighted terms ``sdf`` (m), ``grasp`` (m, weighted mean of
    the symmetric control-point error) and ``code``.
    """
    c = cfg.sdf_clamp
    sdf_l1 = (out.sdf.clamp(-c, c) - sdf_gt.clamp(-c, c)).abs().mean()
    w = grasp_point_weights(cfg, sdf_gt, grasp_distance)
    pred_cp = control_points_torch(out.rotation, xyz + out.offset)
    err = symmetric_control_point_error(pred_cp, grasp_points_gt)
    # With no labelled point in the batch the term is exactly zero (and still part of the graph).
    grasp = (w * err).sum() / w.sum().clamp_min(1e-6)
    code = (codes**2).sum(-1).mean() if codes is not None else sdf_l1 * 0.0
    loss = cfg.sdf_weight * sdf_l1 + cfg.grasp_weight * grasp + cfg.code_weight * code
    return {"loss": loss, "sdf": sdf_l1, "grasp": grasp, "code": code}
