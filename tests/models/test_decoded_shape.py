"""The decoded-shape term of the encoder loss: query points on the decoded target surface, a zero term for the target
code that grows with the code's error, gradients into the code only, and a clear error without the decoder."""

import numpy as np
import pytest
import torch

from centerart.models.checkpoint import default_checkpoint, load_decoder
from centerart.models.encoder.config import PRESETS
from centerart.models.encoder.decoded_shape import DecodedShape, code_index
from centerart.models.encoder.losses import EncoderLossConfig, encoder_loss
from centerart.models.encoder.network import RGBDEncoder


@pytest.fixture(scope="module")
def decoded():
    loaded = load_decoder(default_checkpoint())
    codes = dict(list(loaded.codes.items())[:4])
    return DecodedShape.build(loaded.decoder, codes, loaded.bounds, points=128, pool=8192, band_m=0.04)


def test_query_points_lie_near_the_decoded_target_surface(decoded):
    for z, pts in zip(decoded.codes, decoded.points, strict=True):
        with torch.no_grad():
            near = torch.stack(
                [
                    decoded.decoder.sdf_only(z.expand(len(pts), -1), torch.full((len(pts),), j), pts).abs()
                    for j in (0.0, 0.5, 1.0)
                ]
            ).amin(dim=0)
        assert float(near.max()) < 0.04


def test_the_term_is_zero_at_the_target_code_grows_with_its_error_and_trains_the_code_only(decoded):
    target = decoded.codes[[0, 1, 2, 3, 0, 1]]
    joint, weight = torch.linspace(0, 1, 6), torch.linspace(0.3, 1.0, 6)
    assert float(decoded.term(target.clone(), target, joint, weight)) == 0.0
    torch.manual_seed(0)
    noise = torch.randn_like(target)
    small = float(decoded.term(target + 0.01 * noise, target, joint, weight))
    pred = (target + 0.05 * noise).requires_grad_(True)
    large = decoded.term(pred, target, joint, weight)
    assert 0.0 < small < float(large)
    large.backward()
    assert pred.grad is not None and float(pred.grad.abs().sum()) > 0
    assert all(p.grad is None for p in decoded.decoder.parameters())  # the decoder stays frozen
    np.testing.assert_array_equal(code_index(target, decoded.codes).numpy(), [0, 1, 2, 3, 0, 1])


def test_encoder_loss_adds_the_term_only_with_its_decoder(decoded, loss_batch):
    torch.manual_seed(0)
    enc = RGBDEncoder(PRESETS["tiny"])
    batch = loss_batch
    batch["shape_code"] = decoded.codes[2].expand(1, batch["shape_code"].shape[1], -1).clone()
    out = enc(torch.rand(1, 3, 32, 48), torch.rand(1, 1, 32, 48) + 1)
    cfg = EncoderLossConfig(shape_sdf=10.0)
    with pytest.raises(ValueError, match="shape_sdf needs the decoder"):
        encoder_loss(out, batch, cfg)
    loss, terms = encoder_loss(out, batch, cfg, decoded=decoded)
    base, base_terms = encoder_loss(out, batch, EncoderLossConfig())
    assert "shape_sdf" in terms and "shape_sdf" not in base_terms and float(terms["shape_sdf"]) > 0
    assert torch.isclose(loss - base, 10.0 * terms["shape_sdf"])
    loss.backward()
    assert float(next(enc.object_head.parameters()).grad.abs().sum()) > 0
