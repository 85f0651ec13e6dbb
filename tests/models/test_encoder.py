"""The RGB-D encoder network, read-out and checkpoints (tiny preset, CPU)."""

import numpy as np
import pytest
import torch

from centerart.errors import CenterArtError
from centerart.models.checkpoint import default_checkpoint
from centerart.models.encoder.checkpoint import load_encoder, save_encoder
from centerart.models.encoder.config import PRESETS, EncoderConfig
from centerart.models.encoder.network import RGBDEncoder, dense_layout, rotation_from_raw
from centerart.models.encoder.readout import find_peaks, read_objects


@pytest.mark.parametrize("size", [(120, 160), (97, 131), (64, 33)])
def test_every_head_has_its_shape_for_odd_sizes(size):
    h, w = size
    cfg = PRESETS["tiny"]
    out = RGBDEncoder(cfg)(torch.rand(2, 3, h, w), torch.rand(2, 1, h, w) * 3)
    assert out.heatmap.shape == (2, h, w) and float(out.heatmap.min()) >= 0 and float(out.heatmap.max()) <= 1
    for name, channels in dense_layout(cfg.code_dim).items():
        assert out.dense[name].shape == (2, channels, -(-h // 8), -(-w // 8)), name
    assert torch.allclose(out.dense["axis_direction"].norm(dim=1), torch.ones(1))


def test_depth_holes_do_not_read_as_near_surfaces():
    enc = RGBDEncoder(PRESETS["tiny"]).eval()
    depth = torch.full((1, 1, 40, 40), 2.0)
    depth[..., :10, :] = 0.0
    nan_depth = depth.clone()
    nan_depth[..., :10, :] = float("nan")
    with torch.no_grad():
        a, b = enc(torch.rand(1, 3, 40, 40), depth), None
        b = enc(torch.zeros(1, 3, 40, 40) + 0.5, nan_depth)
    assert torch.isfinite(b.heatmap).all() and torch.isfinite(a.dense["rotation"]).all()


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_every_preset_takes_a_training_step(name):
    """Each named layout builds, runs forward and backward (on a small image: the layout, not the input size)."""
    torch.manual_seed(0)
    enc = RGBDEncoder(PRESETS[name])
    out = enc(torch.rand(2, 3, 96, 128), torch.rand(2, 1, 96, 128) + 0.5)
    loss = out.heatmap.mean() + sum(f.float().pow(2).mean() for f in out.dense.values())
    loss.backward()
    assert all(p.grad is not None for p in enc.parameters() if p.requires_grad)


def test_rotation_projection_gives_rotations():
    rots = rotation_from_raw(torch.randn(50, 9))
    assert torch.allclose(rots @ rots.transpose(1, 2), torch.eye(3).expand(50, 3, 3), atol=1e-5)
    assert torch.allclose(torch.det(rots), torch.ones(50), atol=1e-5)


def test_peaks_and_readout_on_a_hand_made_heatmap():
    heat = np.zeros((60, 80), np.float32)
    heat[20, 30], heat[40, 70] = 0.9, 0.8
    assert find_peaks(heat).tolist() == [[30, 20], [70, 40]]
    enc = RGBDEncoder(PRESETS["tiny"]).eval()
    with torch.no_grad():
        out = enc(torch.rand(1, 3, 60, 80), torch.rand(1, 1, 60, 80) + 1)
    out.heatmap = torch.from_numpy(heat)[None]
    K = np.array([[100.0, 0, 39.5], [0, 100.0, 29.5], [0, 0, 1]])
    dets = read_objects(out, K)
    assert len(dets) == 2 and dets[0].score == pytest.approx(0.9)
    for d in dets:
        assert np.allclose(d.camera_T_object[:3, :3] @ d.camera_T_object[:3, :3].T, np.eye(3), atol=1e-5)
        assert d.joint_type in ("revolute", "prismatic") and 0 <= d.joint_code <= 1


def test_checkpoint_round_trip_and_errors(tmp_path):
    torch.manual_seed(0)
    enc = RGBDEncoder(PRESETS["tiny"]).eval()
    path = save_encoder(tmp_path / "enc.pt", enc, default_checkpoint(), ["a"], {"preset": "tiny"})
    loaded = load_encoder(path, decoder_path=default_checkpoint())
    x, d = torch.rand(1, 3, 48, 64), torch.rand(1, 1, 48, 64)
    with torch.no_grad():
        assert torch.equal(loaded.encoder(x, d).heatmap, enc(x, d).heatmap)
    assert loaded.encoder.config == PRESETS["tiny"]
    other = tmp_path / "other_decoder.pt"
    other.write_bytes(default_checkpoint().read_bytes() + b"x")
    with pytest.raises(CenterArtError, match="trained against the shape codes"):
        load_encoder(path, decoder_path=other)
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(path.read_bytes()[:1000])
    with pytest.raises(CenterArtError, match=r"truncated\.pt: not a readable encoder checkpoint"):
        load_encoder(truncated)
    with pytest.raises(CenterArtError, match="not a centerart encoder checkpoint"):
        load_encoder(default_checkpoint())
    with pytest.raises(CenterArtError, match="not found"):
        load_encoder(tmp_path / "missing.pt")


def test_config_dict_round_trip():
    cfg = PRESETS["paper"]
    assert EncoderConfig.from_dict(cfg.to_dict()) == cfg
    with pytest.raises(ValueError, match="unknown"):
        EncoderConfig.from_dict({"widthz": 3})


def test_config_of_an_older_checkpoint_reads_as_it_was_measured():
    old = {k: v for k, v in PRESETS["small"].to_dict().items() if k != "read_radius_cells"}
    assert EncoderConfig.from_dict(old).read_radius_cells == 1


def test_readout_radius_zero_reads_the_peak_cell_alone():
    v, u = np.mgrid[0:64, 0:80]
    heat = (0.9 * np.exp(-((u - 32) ** 2 + (v - 32) ** 2) / (2 * 10.0**2))).astype(np.float32)  # one wide object
    enc = RGBDEncoder(PRESETS["tiny"]).eval()
    with torch.no_grad():
        out = enc(torch.rand(1, 3, 64, 80), torch.rand(1, 1, 64, 80) + 1)
    out.heatmap = torch.from_numpy(heat)[None]
    K = np.array([[100.0, 0, 39.5], [0, 100.0, 31.5], [0, 0, 1]])
    peak_code = out.dense["shape_code"][0, :, 32 // 8, 32 // 8].numpy()
    assert np.allclose(read_objects(out, K, radius_cells=0)[0].shape_code, peak_code, atol=1e-6)
    assert not np.allclose(read_objects(out, K, radius_cells=3)[0].shape_code, peak_code, atol=1e-6)
