"""Training in slices: a run cut anywhere (mid-slice or between slices, through the state file) gives the weights
of the uninterrupted run; the state file refuses other layouts and damage; batches and the schedule are pure
functions of the seed and the step."""

import pytest
import torch

from centerart.errors import CenterArtError
from centerart.models.encoder.config import PRESETS
from centerart.models.encoder.losses import EncoderLossConfig
from centerart.training.encoder_augment import AugmentConfig
from centerart.training.encoder_data import EncoderViewDataset, collect_views
from centerart.training.slice_training import (
    SliceSchedule,
    StepLoop,
    load_state,
    new_state,
    run_steps,
    save_state,
    slice_batches,
)

# Measured: 0 on this machine (the same ops in the same order); room for other BLAS builds.
ATOL = 1e-6


def _weights(state) -> list[torch.Tensor]:
    return [v.detach().clone() for v in state.encoder.state_dict().values()]


def _loop(batches) -> StepLoop:
    return StepLoop(batches, SliceSchedule(lr=2e-3, warmup_steps=2), EncoderLossConfig(), workers=0)


@pytest.fixture(scope="module")
def datasets(kitchen_dataset):
    views = collect_views([kitchen_dataset])
    cfg = PRESETS["tiny"]
    return [EncoderViewDataset(views, cfg, {}, AugmentConfig(), seed=s) for s in (11, 12)]


def test_mid_slice_stop_and_resume_through_the_state_file_equals_one_run(datasets, tmp_path):
    ds = datasets[0]
    batches = slice_batches(len(ds), 2, 4, seed=0, slice_index=1)
    whole = new_state(PRESETS["tiny"], seed=3)
    assert run_steps(whole, ds, _loop(batches)) == 4 and whole.step == 4

    cut = new_state(PRESETS["tiny"], seed=3)
    assert run_steps(cut, ds, _loop(batches[:2])) == 2
    save_state(tmp_path / "progress.pt", cut)
    resumed = load_state(tmp_path / "progress.pt", PRESETS["tiny"])
    assert resumed.step == 2
    assert run_steps(resumed, ds, _loop(batches), start=2) == 4
    for a, b in zip(_weights(whole), _weights(resumed), strict=True):
        torch.testing.assert_close(a, b, atol=ATOL, rtol=0)


def test_two_slices_through_the_state_file_equal_two_slices_in_memory(datasets, tmp_path):
    plans = [(ds, slice_batches(len(ds), 2, 2, seed=0, slice_index=k)) for k, ds in enumerate(datasets, 1)]
    memory = new_state(PRESETS["tiny"], seed=4)
    for ds, batches in plans:
        run_steps(memory, ds, _loop(batches))
    saved = new_state(PRESETS["tiny"], seed=4)
    for ds, batches in plans:
        run_steps(saved, ds, _loop(batches))
        save_state(tmp_path / "state.pt", saved)
        saved = load_state(tmp_path / "state.pt")
    assert saved.step == memory.step == 4
    for a, b in zip(_weights(memory), _weights(saved), strict=True):
        torch.testing.assert_close(a, b, atol=ATOL, rtol=0)
    # The weights moved: the comparison above is not between two untouched initialisations.
    fresh = _weights(new_state(PRESETS["tiny"], seed=4))
    assert any(float((a - b).abs().max()) > 1e-4 for a, b in zip(fresh, _weights(saved), strict=True))


def test_state_file_refuses_another_layout_and_damage(tmp_path):
    path = save_state(tmp_path / "state.pt", new_state(PRESETS["tiny"], seed=0))
    with pytest.raises(CenterArtError, match=r"another encoder layout.*input_height"):
        load_state(path, PRESETS["small"])
    path.write_bytes(path.read_bytes()[:1000])
    with pytest.raises(CenterArtError, match=r"state\.pt") as err:
        load_state(path, PRESETS["tiny"])
    assert "\n" not in str(err.value)


def test_batches_are_a_function_of_seed_and_slice():
    a = slice_batches(10, 3, 7, seed=0, slice_index=1)
    assert a == slice_batches(10, 3, 7, seed=0, slice_index=1)
    assert a != slice_batches(10, 3, 7, seed=0, slice_index=2)
    assert len(a) == 7 and all(len(b) == 3 for b in a)
    # 3 full batches an epoch; the keys of step 4 onwards belong to epoch 1 (key // 10), each view once an epoch.
    epoch0 = [k for b in a[:3] for k in b]
    assert len(set(epoch0)) == 9 and all(k < 10 for k in epoch0)
    assert all(10 <= k < 20 for b in a[3:6] for k in b)
    with pytest.raises(CenterArtError, match="smaller than one batch"):
        slice_batches(2, 3, 1, seed=0, slice_index=1)


def test_schedule_warms_up_then_holds_the_slice_scale():
    s = SliceSchedule(lr=1e-3, warmup_steps=10, scale=0.5)
    assert s.lr_at(0) == pytest.approx(0.2 * 0.5e-3)
    assert s.lr_at(5) == pytest.approx(0.6 * 0.5e-3)
    assert s.lr_at(10) == s.lr_at(10_000) == pytest.approx(0.5e-3)
