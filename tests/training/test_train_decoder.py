import json

import numpy as np
import pytest
import torch

from centerart.errors import CenterArtError
from centerart.models.checkpoint import load_decoder, load_shape_codes
from centerart.models.decoder import preset
from centerart.models.losses import LossConfig, decoder_loss
from centerart.sdf.samples import load_states
from centerart.training.decoder_data import PointBatchDataset, make_split
from centerart.training.decoder_module import DecoderModule
from centerart.training.synthetic import write_box_cabinet_dataset
from centerart.training.train_decoder import TrainDecoderConfig, train_decoder


@pytest.fixture(scope="module")
def box_data(tmp_path_factory):
    folder = tmp_path_factory.mktemp("box_sdf")
    write_box_cabinet_dataset(folder, n_objects=4, n_states=4, n_points=6000, seed=0)
    return folder


def test_split_is_deterministic_and_disjoint(box_data):
    states = load_states(box_data, progress=False)
    a = make_split(states, 0, 0.25, 1)
    assert a == make_split(states, 0, 0.25, 1)
    assert len(a.heldout_objects) == 1 and set(a.heldout_objects).isdisjoint(a.train_objects)
    for o, ks in a.heldout_states.items():
        assert o in a.train_objects and all(0 < k < 3 for k in ks)  # interior states only
    roles = {a.role(s.object_id, s.state_index) for s in states}
    assert roles == {"train", "heldout_state", "heldout_object"}


def test_tiny_preset_loss_falls(box_data):
    torch.manual_seed(0)
    states = load_states(box_data, progress=False)
    ids = sorted({s.object_id for s in states})
    module = DecoderModule(preset("tiny"), LossConfig(), ids, lr_decoder=2e-3, lr_codes=2e-3)
    ds = PointBatchDataset(states, {o: i for i, o in enumerate(ids)}, 512)
    opt = module.configure_optimizers()["optimizer"]
    batch = torch.utils.data.default_collate([ds[i] for i in range(len(ds))])
    losses = []
    for _ in range(60):
        f = module._flat(batch)  # the training step's computation, without Lightning's logging
        out = module.decoder(f["code"], f["joint"], f["xyz"])
        loss = decoder_loss(
            module.loss_config, out, f["xyz"], f["sdf"], f["grasp_points"], f["grasp_distance"], f["batch_codes"]
        )["loss"]
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(float(loss))
    assert np.mean(losses[-5:]) < 0.85 * np.mean(losses[:5])  # measured: about 0.34 -> 0.26


def test_train_command_writes_checkpoint_and_resumes(box_data, tmp_path):
    cfg = TrainDecoderConfig(
        data=box_data,
        out=tmp_path / "run",
        preset="tiny",
        epochs=2,
        batch_items=4,
        points_per_item=256,
        min_items_per_epoch=16,
        val_every=1,
        val_code_fit_steps=5,
        heldout_object_fraction=0.25,
        progress=False,
    )
    result = train_decoder(cfg)
    out = tmp_path / "run"
    for name in ("decoder.pt", "config.json", "split.json", "metrics.json", "lightning/last.ckpt"):
        assert (out / name).is_file(), name
    assert list((out / "logs" / "csv").rglob("metrics.csv"))
    assert list((out / "logs" / "tensorboard").rglob("events.out.tfevents.*"))
    m = result["metrics"]
    assert "val_state/sdf" in m and "val_object/sdf" in m and m["train_points_per_second"] > 0
    codes = load_shape_codes(out / "decoder.pt")
    split = json.loads((out / "split.json").read_text())
    assert sorted(codes) == split["train_objects"] and all(c.shape == (32,) for c in codes.values())
    loaded = load_decoder(out / "decoder.pt")
    assert loaded.bounds.shape == (2, 3) and loaded.meta["split"] == split
    # rerun: resumes from last.ckpt (already at max_epochs) and re-exports the same codes
    train_decoder(cfg)
    again = load_shape_codes(out / "decoder.pt")
    assert all(np.allclose(again[k], codes[k]) for k in codes)


def test_bad_inputs_raise_centerart_errors(tmp_path):
    with pytest.raises(CenterArtError):
        train_decoder(TrainDecoderConfig(data=tmp_path / "missing", out=tmp_path / "o"))
    (tmp_path / "obj").mkdir()
    (tmp_path / "obj" / "state_00.npz").write_bytes(b"not a zip")
    with pytest.raises(CenterArtError, match=r"state_00\.npz"):
        load_states(tmp_path, progress=False)
    with pytest.raises(CenterArtError, match=r"not a readable decoder checkpoint|not a centerart"):
        load_decoder(tmp_path / "obj" / "state_00.npz")
