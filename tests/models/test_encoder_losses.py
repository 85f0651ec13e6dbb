"""Encoder losses: per-object terms see object cells only; the pose term is zero for a perfect prediction."""

import numpy as np
import torch

from centerart.models.encoder.config import PRESETS
from centerart.models.encoder.losses import EncoderLossConfig, encoder_loss
from centerart.models.encoder.network import OFFSET_SCALE_PX, RGBDEncoder, cell_centers


def test_background_cells_do_not_change_object_terms(loss_batch):
    torch.manual_seed(0)
    enc = RGBDEncoder(PRESETS["tiny"])
    batch = loss_batch
    out = enc(torch.rand(1, 3, 32, 48), torch.rand(1, 1, 32, 48) + 1)
    _, terms = encoder_loss(out, batch, EncoderLossConfig())
    bg = batch["cell_object"] < 0
    for f in out.dense.values():
        f.data[:, :, bg[0]] += 100.0
    _, terms2 = encoder_loss(out, batch, EncoderLossConfig())
    for k in terms:
        assert torch.allclose(terms[k], terms2[k]), k


def test_perfect_pose_prediction_has_zero_pose_loss(loss_batch):
    enc = RGBDEncoder(PRESETS["tiny"])
    batch = loss_batch
    out = enc(torch.rand(1, 3, 32, 48), torch.rand(1, 1, 32, 48) + 1)
    t = batch["translation"][0, 0]
    K = batch["K"][0]
    uv = torch.stack([K[0, 0] * t[0] / t[2] + K[0, 2], K[1, 1] * t[1] / t[2] + K[1, 2]])
    cells = cell_centers(4, 6, 8)
    out.dense["rotation"].data[:] = torch.eye(3).reshape(9, 1, 1)
    out.dense["center_offset"].data[0] = ((uv - cells) / OFFSET_SCALE_PX).permute(2, 0, 1)
    out.dense["center_depth"].data[:] = t[2]
    _, terms = encoder_loss(out, batch, EncoderLossConfig())
    assert float(terms["pose"]) < 1e-5
    assert np.isfinite(float(terms["heatmap"]))


def _perfect_pose(out, batch):
    t, K = batch["translation"][0, 0], batch["K"][0]
    uv = torch.stack([K[0, 0] * t[0] / t[2] + K[0, 2], K[1, 1] * t[1] / t[2] + K[1, 2]])
    out.dense["rotation"].data[:] = torch.eye(3).reshape(9, 1, 1)
    out.dense["center_offset"].data[0] = ((uv - cell_centers(4, 6, 8)) / OFFSET_SCALE_PX).permute(2, 0, 1)
    out.dense["center_depth"].data[:] = t[2]


def test_decoupled_pose_loss_equals_published_when_either_error_is_zero(loss_batch):
    torch.manual_seed(0)
    enc = RGBDEncoder(PRESETS["tiny"])
    batch = loss_batch
    out = enc(torch.rand(1, 3, 32, 48), torch.rand(1, 1, 32, 48) + 1)
    _perfect_pose(out, batch)
    published, decoupled = EncoderLossConfig(pose_decoupled=False), EncoderLossConfig(pose_decoupled=True)
    out.dense["rotation"].data[:] = torch.tensor([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]).reshape(9, 1, 1)  # 90 deg
    a, b = encoder_loss(out, batch, published)[1]["pose"], encoder_loss(out, batch, decoupled)[1]["pose"]
    assert float(a) > 0.05 and torch.allclose(a, b)
    _perfect_pose(out, batch)
    out.dense["center_depth"].data[:] += 0.2  # translation error only
    a, b = encoder_loss(out, batch, published)[1]["pose"], encoder_loss(out, batch, decoupled)[1]["pose"]
    assert float(a) > 0.05 and torch.allclose(a, b)


def test_whitened_shape_loss_divides_each_dimension_by_its_code_spread(loss_batch):
    from centerart.models.encoder.losses import code_scale

    enc = RGBDEncoder(PRESETS["tiny"])
    batch = loss_batch
    out = enc(torch.rand(1, 3, 32, 48), torch.rand(1, 1, 32, 48) + 1)
    out.dense["shape_code"].data[:] = 0.1
    codes = {"a": np.full(32, -0.2, np.float32), "b": np.full(32, 0.2, np.float32)}
    std = code_scale(codes)
    raw = encoder_loss(out, batch, EncoderLossConfig())[1]["shape"]
    white = encoder_loss(out, batch, EncoderLossConfig(shape_whiten=True), std)[1]["shape"]
    assert torch.allclose(white, raw / std[0])
