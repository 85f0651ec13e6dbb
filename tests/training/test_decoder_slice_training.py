"""Decoder training in slices (issue 29): a run cut into pieces and resumed through the state file equals one
uninterrupted run; the batch of a step depends on the seed and the step only; a state of another layout or object
set is one error line."""

from __future__ import annotations

import pytest
import torch

from centerart.errors import CenterArtError
from centerart.models.code_fitting import CodeFitConfig
from centerart.models.decoder import preset
from centerart.models.losses import LossConfig
from centerart.sdf.samples import load_states
from centerart.training.decoder_data import PointBatchDataset, make_split
from centerart.training.decoder_module import DecoderModule
from centerart.training.decoder_slice_training import (
    KeyedBatches,
    load_decoder_state,
    new_decoder_state,
    run_decoder_steps,
    save_decoder_state,
    validate_decoder,
)
from centerart.training.slice_training import SliceSchedule
from centerart.training.synthetic import write_box_cabinet_dataset


@pytest.fixture(scope="module")
def box_states(tmp_path_factory):
    folder = tmp_path_factory.mktemp("box_sdf")
    write_box_cabinet_dataset(folder, n_objects=4, n_states=4, n_points=3000, seed=0)
    states = load_states(folder, progress=False)
    split = make_split(states, 0, 0.25, 1)
    roles = {r: [s for s in states if split.role(s.object_id, s.state_index) == r] for r in
             ("train", "heldout_state", "heldout_object")}  # fmt: skip
    return split, roles


def _builder(split, roles, ids=None):
    def build():
        fit = CodeFitConfig(steps=3)
        objects = ids or split.train_objects
        return DecoderModule(
            preset("tiny"), LossConfig(), objects, heldout_object_states=roles["heldout_object"], code_fit=fit
        )

    return build


def _batches(split, roles) -> KeyedBatches:
    codes = {o: i for i, o in enumerate(split.train_objects)}
    return KeyedBatches(PointBatchDataset(roles["train"], codes, 128), 3, seed=5)


def test_a_step_batch_depends_on_seed_and_step_only(box_states):
    split, roles = box_states
    a, b = _batches(*box_states), _batches(*box_states)
    first = a.batch(7)
    b.batch(0), b.batch(30)  # other draws in between change nothing
    again = b.batch(7)
    assert all(torch.equal(first[k], again[k]) for k in first)
    assert not torch.equal(a.batch(8)["points"], first["points"])
    # The first epoch's positions draw every training state once.
    n = len(roles["train"])
    keys = [(int(c), round(float(j), 6)) for s in range(-(-n // 3)) for c, j in
            zip(a.batch(s)["code_index"], a.batch(s)["joint"], strict=True)][:n]  # fmt: skip
    codes = {o: i for i, o in enumerate(split.train_objects)}
    assert sorted(keys) == sorted((codes[s.object_id], round(s.joint, 6)) for s in roles["train"])


def test_slices_resumed_through_the_file_equal_one_run(box_states, tmp_path):
    split, roles = box_states
    build, schedule = _builder(split, roles), SliceSchedule(1.0, 2, 1.0)
    whole = new_decoder_state(build, seed=3)
    run_decoder_steps(whole, _batches(split, roles), schedule, until=7)

    cut = new_decoder_state(build, seed=3)
    run_decoder_steps(cut, _batches(split, roles), schedule, until=2)
    save_decoder_state(tmp_path / "a.pt", cut)
    cut = load_decoder_state(tmp_path / "a.pt", build())
    run_decoder_steps(cut, _batches(split, roles), schedule, until=5)
    save_decoder_state(tmp_path / "b.pt", cut)
    cut = load_decoder_state(tmp_path / "b.pt", build())
    assert cut.step == 5
    run_decoder_steps(cut, _batches(split, roles), schedule, until=7)

    assert cut.step == whole.step == 7
    for (name, a), b in zip(whole.module.state_dict().items(), cut.module.state_dict().values(), strict=True):
        assert torch.allclose(a, b, atol=1e-6), name
    # Training moved the weights, and the fixed validation set gives the same figures for equal weights.
    fresh = new_decoder_state(build, seed=3)
    assert not torch.allclose(fresh.module.codes.weight, whole.module.codes.weight)
    figures = validate_decoder(whole, roles["heldout_state"], 0, 3, 128)
    assert figures == validate_decoder(cut, roles["heldout_state"], 0, 3, 128)
    assert {"val_state/sdf", "val_object/sdf", "val_object/sdf_near"} <= set(figures)


def test_a_state_of_other_objects_or_a_damaged_file_is_one_error(box_states, tmp_path):
    split, roles = box_states
    state = new_decoder_state(_builder(split, roles), seed=0)
    save_decoder_state(tmp_path / "s.pt", state)
    other = _builder(split, roles, ids=list(reversed(split.train_objects)))()
    with pytest.raises(CenterArtError, match="other training objects"):
        load_decoder_state(tmp_path / "s.pt", other)
    (tmp_path / "bad.pt").write_bytes(b"not a torch file")
    with pytest.raises(CenterArtError, match=r"bad\.pt"):
        load_decoder_state(tmp_path / "bad.pt", other)


def test_grasp_term_kept_off_the_codes_gives_them_the_sdf_gradient_only(box_states):
    split, roles = box_states
    batch = _batches(split, roles).batch(0)

    def grads(loss_config, loss_key):
        torch.manual_seed(0)
        module = _builder(split, roles)()
        module.loss_config = loss_config
        terms = module.loss_terms(batch)
        loss = terms["loss"] if loss_key == "loss" else loss_config.sdf_weight * terms["sdf"]
        loss = loss + (loss_config.code_weight * terms["code"] if loss_key != "loss" else 0)
        loss.backward()
        return module.codes.weight.grad.clone(), module.decoder.head.weight.grad.clone()

    codes_off, head_off = grads(LossConfig(grasp_moves_codes=False), "loss")
    codes_sdf, _ = grads(LossConfig(), "sdf")
    codes_on, head_on = grads(LossConfig(), "loss")
    torch.testing.assert_close(codes_off, codes_sdf)  # the codes see the SDF and the prior only
    torch.testing.assert_close(head_off, head_on)  # the weights still see the grasp term
    assert not torch.allclose(codes_on, codes_sdf)  # and the grasp term does reach the codes by default


def test_refit_replaces_each_training_code_by_a_code_fitted_to_its_sdf(box_states):
    from centerart.models.code_fitting import CodeFitConfig, Observations, fit_code
    from centerart.training.decoder_slice_training import refit_training_codes

    split, roles = box_states
    state = new_decoder_state(_builder(split, roles), seed=3)
    run_decoder_steps(state, _batches(split, roles), SliceSchedule(1.0, 0, 1.0), 2)
    before = state.module.codes.weight.detach().clone()
    moved = refit_training_codes(state, roles["train"], steps=4, seed=0, points_per_step=256, progress=False)
    oid = state.module.object_ids[1]
    obs = Observations.from_samples([(s.joint, s.points, s.sdf) for s in roles["train"] if s.object_id == oid])
    cfg = CodeFitConfig(steps=4, points_per_step=256, code_weight=state.module.loss_config.code_weight, seed=0)
    expected = torch.as_tensor(fit_code(state.module.decoder, obs, cfg)[0])
    torch.testing.assert_close(state.module.codes.weight[1].detach(), expected)
    assert moved["max_code_change"] > 0 and not torch.equal(before, state.module.codes.weight.detach())
    assert float(state.optimizer.state[state.module.codes.weight]["exp_avg"].abs().sum()) == 0.0
