"""Encoder losses: the published terms (heatmap MSE, keypoint pose loss, shape-code L1, joint code) plus the
joint heads, every per-object term masked to the cells that see an object (the published joint loss was not).

Targets come as a batch dict (see :mod:`centerart.training.encoder_targets`): ``heatmap`` (B, H, W); per cell
``cell_object`` (B, h, w) long, the index of the object the cell belongs to (-1: background) and ``cell_weight``
(B, h, w), the target heatmap at the cell centre; per object (B, M, ...) ``rotation`` (3, 3), ``translation``
(3, m), ``shape_code``, ``shape_code_valid``, ``joint_code``, ``joint_type`` (0 revolute, 1 prismatic),
``axis_direction``, ``axis_point_offset`` (m), ``joint_state`` (rad or m); and ``K`` (B, 3, 3) of the input.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import torch
import torch.nn.functional as F

from centerart.models.encoder.decoded_shape import DecodedShape
from centerart.models.encoder.network import EncoderOutput, cell_centers, object_translation, rotation_from_raw

KEYPOINT_ARM_M = 0.1  # the published pose loss: t and t + 0.1 m along each rotated axis (keypoints()'s default)


@dataclass(frozen=True)
class EncoderLossConfig:
    heatmap: float = 100.0
    pose: float = 5.0
    shape: float = 1.0
    joint_code: float = 10.0
    joint_type: float = 1.0
    axis_direction: float = 1.0
    axis_point: float = 5.0
    joint_state: float = 1.0
    min_cell_weight: float = 0.25
    """Cells whose target heatmap is at most this carry no object (the published 0.25)."""
    keypoint_arm_m: float = 0.5
    """Length (m) of the three axis keypoints of the pose loss: a rotation error of a radians moves a tip by
    about arm * a, so the arm is the rotation's weight against the translation's. Why 0.5 m, about an object's
    half size, not the published 0.1 m (:data:`KEYPOINT_ARM_M`): with 0.1 m the rotation term was a few mm
    against centimetres of translation and the rotation did not fit its own training views; on the 50-view
    overfit check (``benchmarks/results/overfit_encoder/``, 800 steps, decoupled) rotation 9.2 -> 3.6 deg."""
    pose_decoupled: bool = True
    """Pose keypoints with rotation and translation errors apart: the origin keypoint carries the translation
    error, the three axis tips the rotation error alone (tips placed about the *true* origin). Why: in the
    published form every tip also carries the translation error, and while that is centimetres the tips'
    gradient points along it, so the rotation gets little signal of its own. Same value for a perfect
    translation."""
    shape_sdf: float = 0.0
    """Weight of the decoded-shape term (:mod:`.decoded_shape`: the regressed code's SDF against the target code's,
    through the frozen decoder, m); 0 leaves it out. It needs the decoder (``encoder_loss(decoded=...)``)."""
    shape_whiten: bool = False
    """Shape-code L1 on whitened codes: each dimension's error divided by the standard deviation of that
    dimension over the decoder's codes (:func:`code_scale`), so every dimension counts by how much it varies
    between objects, not by its raw size. Only the loss changes: the head still outputs raw codes."""

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> EncoderLossConfig:
        """A saved loss config; fields added after it was saved take the values it was trained with."""
        return cls(**{**LEGACY_LOSS, **data})


LEGACY_LOSS: dict[str, object] = {"keypoint_arm_m": KEYPOINT_ARM_M, "pose_decoupled": False}
"""Values of fields that loss configs saved before them lack: the published pose loss they trained with."""


def gather_object_cells(out: EncoderOutput, batch: dict, min_weight: float) -> dict | None:
    """Predictions and targets at every object cell, flattened to (N, ...); None when no cell has an object."""
    obj, weight = batch["cell_object"], batch["cell_weight"]
    sel = (obj >= 0) & (weight > min_weight)
    if not bool(sel.any()):
        return None
    b, i, j = torch.nonzero(sel, as_tuple=True)
    k = obj[b, i, j]
    pred = {name: f[b, :, i, j] for name, f in out.dense.items()}
    h, w = obj.shape[-2:]
    cells = cell_centers(h, w, out.stride, device=obj.device)[i, j]
    target = {name: batch[name][b, k] for name in OBJECT_FIELDS}
    return {"pred": pred, "target": target, "weight": weight[b, i, j], "cells": cells, "K": batch["K"][b]}


OBJECT_FIELDS = (
    "rotation",
    "translation",
    "shape_code",
    "shape_code_valid",
    "joint_code",
    "joint_type",
    "axis_direction",
    "axis_point_offset",
    "joint_state",
)


def keypoints(rotation: torch.Tensor, translation: torch.Tensor, arm: float = KEYPOINT_ARM_M) -> torch.Tensor:
    """(N, 4, 3): the origin and the tips of the three ``arm`` (m) axes of each object frame."""
    tips = translation[:, None, :] + arm * rotation.transpose(1, 2)
    return torch.cat([translation[:, None, :], tips], dim=1)


def code_scale(codes: dict) -> torch.Tensor:
    """(code_dim,) per-dimension standard deviation of the decoder's shape codes (floored at 1e-3)."""
    stacked = torch.as_tensor(np.stack([np.asarray(c, np.float32) for c in codes.values()]))
    return stacked.std(dim=0).clamp_min(1e-3) if len(stacked) > 1 else torch.ones(stacked.shape[1])


def encoder_loss(
    out: EncoderOutput, batch: dict, cfg: EncoderLossConfig, code_std: torch.Tensor | None = None,
    decoded: DecodedShape | None = None,
) -> tuple[torch.Tensor, dict]:  # fmt: skip
    """Weighted total loss and its terms (unweighted, detached) for logging. ``code_std`` (code_dim,): the
    per-dimension scale of the shape codes, required with ``cfg.shape_whiten`` (see :func:`code_scale`);
    ``decoded``: the frozen decoder and its query points, required with ``cfg.shape_sdf``."""
    if cfg.shape_whiten and code_std is None:
        raise ValueError("EncoderLossConfig.shape_whiten needs the codes' per-dimension scale (code_std)")
    if cfg.shape_sdf > 0 and decoded is None:
        raise ValueError("EncoderLossConfig.shape_sdf needs the decoder (decoded=DecodedShape.build(...))")
    terms = {"heatmap": F.mse_loss(out.heatmap, batch["heatmap"])}
    cells = gather_object_cells(out, batch, cfg.min_cell_weight)
    if cells is not None:
        terms.update(
            object_terms(cells, code_std if cfg.shape_whiten else None, cfg.pose_decoupled, cfg.keypoint_arm_m)
        )
        if cfg.shape_sdf > 0:
            terms["shape_sdf"] = shape_sdf_term(cells, decoded)
    total = sum(getattr(cfg, name) * value for name, value in terms.items())
    return total, {name: value.detach() for name, value in terms.items()}


def shape_sdf_term(cells: dict, decoded: DecodedShape) -> torch.Tensor:
    """The decoded-shape term over the object cells with a valid target code (zero when there are none)."""
    p, t = cells["pred"], cells["target"]
    valid = t["shape_code_valid"].bool()
    if not bool(valid.any()):
        return p["shape_code"].sum() * 0.0
    return decoded.term(p["shape_code"][valid], t["shape_code"][valid], t["joint_code"][valid], cells["weight"][valid])


def _weighted_mean(values: torch.Tensor, weight: torch.Tensor) -> torch.Tensor:
    return (values * weight).sum() / weight.sum().clamp_min(1e-6)


def object_terms(
    cells: dict, code_std: torch.Tensor | None = None, pose_decoupled: bool = False, arm: float = KEYPOINT_ARM_M
) -> dict[str, torch.Tensor]:
    p, t, w = cells["pred"], cells["target"], cells["weight"]
    code_err = p["shape_code"] - t["shape_code"]
    if code_std is not None:
        code_err = code_err / code_std.to(code_err)
    rot = rotation_from_raw(p["rotation"])
    trans = object_translation(cells["cells"], p["center_offset"], p["center_depth"][:, 0], cells["K"])
    true_kp = keypoints(t["rotation"], t["translation"], arm)
    if pose_decoupled:  # the tips about the true origin measure the rotation only (see EncoderLossConfig)
        tip_err = (keypoints(rot, t["translation"], arm) - true_kp)[:, 1:].norm(dim=-1).sum(dim=1)
        kp_err = (trans - t["translation"]).norm(dim=-1) + tip_err / 4.0
    else:
        kp_err = (keypoints(rot, trans, arm) - true_kp).norm(dim=-1).mean(dim=1)
    code_w = w * t["shape_code_valid"].float()
    terms = {
        "pose": _weighted_mean(kp_err, w),
        "shape": _weighted_mean(code_err.abs().sum(dim=1), code_w),
        "joint_code": _weighted_mean((p["joint_code"][:, 0] - t["joint_code"]) ** 2, w),
        "joint_type": _weighted_mean(F.cross_entropy(p["joint_type_logits"], t["joint_type"], reduction="none"), w),
        "axis_direction": _weighted_mean(1.0 - (p["axis_direction"] * t["axis_direction"]).sum(dim=1), w),
        "axis_point": _weighted_mean((p["axis_point_offset"] - t["axis_point_offset"]).abs().sum(dim=1), w),
        "joint_state": _weighted_mean((p["joint_state"][:, 0] - t["joint_state"]).abs(), w),
    }
    return terms
