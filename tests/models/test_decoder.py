import numpy as np
import pytest
import torch

from centerart.models.decoder import PRESETS, DecoderConfig, SGDFDecoder, gram_schmidt, preset


def test_gram_schmidt_orthonormal_right_handed():
    g = torch.Generator().manual_seed(0)
    a, b = torch.randn(100, 3, generator=g), torch.randn(100, 3, generator=g)
    R = gram_schmidt(a, b)
    eye = torch.eye(3).expand(100, 3, 3)
    assert torch.allclose(R.transpose(-1, -2) @ R, eye, atol=1e-5)
    assert torch.allclose(torch.linalg.det(R), torch.ones(100), atol=1e-5)
    # first column is a's direction; b only fixes the second column up to its component along a
    assert torch.allclose(R[..., 0], a / a.norm(dim=-1, keepdim=True), atol=1e-6)
    assert torch.allclose(gram_schmidt(3 * a, b + 2 * a), R, atol=1e-5)


def test_gram_schmidt_recovers_rotation_from_its_columns():
    from scipy.spatial.transform import Rotation

    Rt = torch.as_tensor(Rotation.random(20, random_state=1).as_matrix(), dtype=torch.float32)
    assert torch.allclose(gram_schmidt(Rt[..., 0], Rt[..., 1]), Rt, atol=1e-5)


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_presets_forward_shapes(name):
    dec = SGDFDecoder(preset(name)).eval()
    n = 7
    out = dec(torch.zeros(n, 32), torch.rand(n), torch.randn(n, 3) * 0.2)
    assert out.sdf.shape == (n,) and out.offset.shape == (n, 3) and out.rotation.shape == (n, 3, 3)
    poses = out.grasp_poses(torch.zeros(n, 3))
    assert poses.shape == (n, 4, 4) and torch.allclose(poses[:, 3, 3], torch.ones(n))


def test_paper_preset_matches_published_layout():
    c = PRESETS["paper"]
    assert (c.width, c.depth, c.skip_layers, c.joint_layer, c.weight_norm, c.dropout) == (512, 8, (4,), 1, True, 0.2)


def test_joint_code_changes_output_and_no_output_squashing():
    torch.manual_seed(0)
    dec = SGDFDecoder(preset("tiny")).eval()
    with torch.no_grad():
        for p in dec.head.parameters():
            p.mul_(100.0)  # large head weights: a tanh would saturate at 1
        x = torch.randn(64, 3)
        a = dec(torch.zeros(64, 32), torch.zeros(64), x)
        b = dec(torch.zeros(64, 32), torch.ones(64), x)
    assert not torch.allclose(a.sdf, b.sdf)
    assert a.raw.abs().max() > 1.5  # unbounded outputs


def test_bad_config_rejected():
    with pytest.raises(ValueError):
        DecoderConfig(depth=4, joint_layer=4)
    with pytest.raises(ValueError):
        DecoderConfig(depth=4, skip_layers=(0,))
    with pytest.raises(ValueError):
        preset("huge")


def test_config_roundtrip():
    c = preset("small", width=128)
    assert DecoderConfig.from_dict(c.to_dict()) == c
    assert np.isfinite(SGDFDecoder(c).num_parameters())
