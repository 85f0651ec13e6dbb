"""Encoder training: the tiny preset overfits three rendered views; the CLI trains, resumes and exports."""

import json

import numpy as np
import pytest
import torch

from centerart.cli import main
from centerart.models.checkpoint import default_checkpoint
from centerart.models.encoder.checkpoint import load_encoder
from centerart.models.encoder.config import PRESETS
from centerart.models.encoder.inputs import Letterbox
from centerart.models.encoder.losses import EncoderLossConfig, encoder_loss
from centerart.models.encoder.network import RGBDEncoder
from centerart.models.encoder.readout import read_objects
from centerart.training.encoder_data import EncoderViewDataset, collate, collect_views
from centerart.training.encoder_targets import input_gaussians


@pytest.mark.slow
def test_tiny_encoder_overfits_three_views(kitchen_dataset):
    torch.manual_seed(0)
    cfg = PRESETS["tiny"]
    views = collect_views([kitchen_dataset])[:3]
    ds = EncoderViewDataset(views, cfg, codes={}, augment=None)
    batch = collate([ds[i] for i in range(3)])
    enc = RGBDEncoder(cfg)
    opt = torch.optim.Adam(enc.parameters(), lr=3e-3)
    loss_cfg = EncoderLossConfig()
    first_pose = None
    for _ in range(250):
        loss, terms = encoder_loss(enc(batch["rgb"], batch["depth"]), batch, loss_cfg)
        first_pose = float(terms["pose"]) if first_pose is None else first_pose
        opt.zero_grad()
        loss.backward()
        opt.step()
    assert float(terms["pose"]) < 0.3 * first_pose
    enc.eval()
    with torch.no_grad():
        out = enc(batch["rgb"], batch["depth"])
    for b, view in enumerate(views):
        labels = ds.labels_of(str(view))
        box = Letterbox.fit(labels["width"], labels["height"], cfg.input_width, cfg.input_height)
        peaks = np.array([d.peak_uv for d in read_objects(out, batch["K"][b].numpy(), index=b)]).reshape(-1, 2)
        for _, mean, cov in input_gaussians(labels, box):
            if np.sqrt(np.linalg.det(cov)) < 4.0:  # a few-pixel sliver: too small to promise a peak
                continue
            assert len(peaks) and np.linalg.norm(peaks - mean, axis=1).min() <= 4.0, (view, mean, peaks)


def test_train_encoder_cli_two_epochs_resume_and_export(kitchen_dataset, single_dataset, tmp_path):
    out = tmp_path / "enc"
    args = ["train", "encoder", "--scenes", str(kitchen_dataset), "--val-scenes", str(single_dataset),
            "--preset", "tiny", "--epochs", "1", "--batch-size", "2", "--out", str(out), "--no-progress",
            "--workers", "0", "--val-every", "5"]  # fmt: skip
    assert main(args) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["steps"] == 2 and "val/recall" in metrics and "val/loss" in metrics
    assert (out / "lightning" / "last.ckpt").is_file() and (out / "config.json").is_file()
    args[args.index("--epochs") + 1] = "2"
    assert main(args) == 0  # resumes from last.ckpt: one more epoch
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["steps"] == 4 and metrics["resumed"] is True
    loaded = load_encoder(out / "encoder.pt", decoder_path=default_checkpoint())
    assert loaded.encoder.config.input_width == PRESETS["tiny"].input_width
    assert loaded.meta["decoder"]["code_dim"] == 32
