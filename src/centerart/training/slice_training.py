"""Encoder training in slices: a deterministic step loop whose state (weights, Adam moments, step) is one file.

A long run is cut into slices that each fit one working period (``centerart slices next``,
:mod:`centerart.recipe.slices`). Every slice continues the state the last one saved, on new data. For the cut to
be invisible, everything a step draws is a function of the run's seed and the step's place, never of process
state: the batch order of a slice comes from (seed, slice, epoch within the slice), an item's augmentation from
(seed, slice, epoch, index) (:meth:`~centerart.training.encoder_data.EncoderViewDataset.item`), and the learning
rate from the global step. So a slice that stops and resumes, or a run saved and reloaded between slices, gives
the weights an uninterrupted run gives (tested to float tolerance on CPU).

Why not Lightning (which ``centerart train encoder`` uses): its resume restores a loop position inside one
dataloader; here the data changes at every slice and a slice may stop mid-way, so the loop keeps its own
position, and the state file holds exactly what the next slice needs.

State file (``torch.load(weights_only=True)``): ``format`` ``"centerart-encoder-train-state"``, ``version`` 1,
``encoder_config``, ``state_dict``, ``optimizer`` (Adam's state dict), ``step`` (global optimizer steps so far),
``meta`` (free JSON-able dict: the slice ledger's bookkeeping).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
from torch.utils.data import DataLoader, Dataset

from centerart.errors import CenterArtError
from centerart.models.checkpoint_files import check_fields, read_blob, write_blob
from centerart.models.encoder.config import EncoderConfig, same_weights_layout
from centerart.models.encoder.decoded_shape import DecodedShape
from centerart.models.encoder.losses import EncoderLossConfig, encoder_loss
from centerart.models.encoder.network import RGBDEncoder
from centerart.training.encoder_data import EncoderViewDataset, collate
from centerart.training.encoder_metrics import batch_view_metrics, summarize
from centerart.training.schedules import warmup_factor

FORMAT = "centerart-encoder-train-state"
VERSION = 1


@dataclass(frozen=True)
class SliceSchedule:
    """Learning rate by global step: linear warm-up over ``warmup_steps`` from 0.2 x ``lr``, then ``lr`` times
    ``scale`` (a slice's own factor, recorded in its ledger line: an open-ended run decays by lowering it)."""

    lr: float = 1e-3
    warmup_steps: int = 500
    scale: float = 1.0

    def factor_at(self, step: int) -> float:
        """The multiplier of the base rate at global ``step`` (warm-up times the slice's scale)."""
        return self.scale * warmup_factor(step, self.warmup_steps)

    def lr_at(self, step: int) -> float:
        return self.lr * self.factor_at(step)


@dataclass
class TrainState:
    encoder: RGBDEncoder
    optimizer: torch.optim.Adam
    step: int = 0
    meta: dict | None = None


def new_state(config: EncoderConfig, seed: int, init: Path | None = None, decoder: Path | None = None) -> TrainState:
    """Weights drawn from ``seed`` (or copied from the encoder checkpoint ``init``, which must have been trained
    against ``decoder`` when given), fresh Adam, step 0."""
    torch.manual_seed(seed)
    encoder = RGBDEncoder(config)
    if init is not None:
        from centerart.models.encoder.checkpoint import load_encoder

        loaded = load_encoder(init, decoder)
        if not same_weights_layout(loaded.encoder.config, config):  # the run's read-out may differ from init's
            raise CenterArtError(f"{init}: its encoder layout differs from the run's; start the run from scratch")
        encoder.load_state_dict(loaded.encoder.state_dict())
    return TrainState(encoder, torch.optim.Adam(encoder.parameters(), lr=1e-3), 0, {})


def save_state(path: Path, state: TrainState) -> Path:
    blob = {
        "format": FORMAT,
        "version": VERSION,
        "encoder_config": state.encoder.config.to_dict(),
        "state_dict": {k: v.detach().cpu().clone() for k, v in state.encoder.state_dict().items()},
        "optimizer": state.optimizer.state_dict(),
        "step": int(state.step),
        "meta": dict(state.meta or {}),
    }
    return write_blob(path, blob)


def load_state(path: Path, config: EncoderConfig | None = None) -> TrainState:
    """The state saved at ``path``; with ``config``, refuses a state of another encoder layout (one line)."""
    blob = read_blob(path, FORMAT, VERSION, "encoder training state")
    fields = {"encoder_config": dict, "state_dict": dict, "optimizer": dict, "step": int, "meta": dict}
    check_fields(blob, path, "encoder training state", fields)
    saved = EncoderConfig.from_dict(blob["encoder_config"])
    if config is not None and saved != config:
        diff = sorted(k for k, v in asdict(config).items() if asdict(saved)[k] != v)
        raise CenterArtError(f"{path}: a training state of another encoder layout (differs in {', '.join(diff)})")
    encoder = RGBDEncoder(saved)
    try:
        encoder.load_state_dict(blob["state_dict"])
        optimizer = torch.optim.Adam(encoder.parameters(), lr=1e-3)
        optimizer.load_state_dict(blob["optimizer"])
    except (RuntimeError, ValueError, KeyError) as err:
        raise CenterArtError(f"{path}: damaged encoder training state ({str(err).splitlines()[0]})") from None
    return TrainState(encoder, optimizer, blob["step"], blob["meta"])


def slice_batches(n_views: int, batch_size: int, steps: int, seed: int, slice_index: int) -> list[list[int]]:
    """The item keys of each step of a slice: epochs over its ``n_views`` views, each in the order drawn from
    (seed, slice, epoch), last short batch dropped. A key is ``epoch * n_views + view``."""
    if n_views < batch_size:
        raise CenterArtError(f"a slice of {n_views} views is smaller than one batch ({batch_size})")
    per_epoch = n_views // batch_size
    batches: list[list[int]] = []
    for epoch in range(math.ceil(steps / per_epoch)):
        order = np.random.default_rng([seed, slice_index, epoch]).permutation(n_views)
        for b in range(per_epoch):
            batches.append([int(epoch * n_views + i) for i in order[b * batch_size : (b + 1) * batch_size]])
    return batches[:steps]


class EpochKeyed(Dataset):
    """Items addressed by ``epoch * len(views) + view`` (see :func:`slice_batches`): the augmentation of an item
    depends on its key only, whatever loader worker draws it."""

    def __init__(self, dataset: EncoderViewDataset):
        self.dataset = dataset

    def __len__(self) -> int:
        return len(self.dataset)

    def __getitem__(self, key: int) -> dict:
        epoch, index = divmod(int(key), len(self.dataset))
        return self.dataset.item(index, epoch)


@dataclass(frozen=True)
class StepLoop:
    """One slice's steps ``start`` .. ``len(batches)`` with the loss weights, schedule and loader settings."""

    batches: list[list[int]]
    schedule: SliceSchedule
    loss: EncoderLossConfig
    code_std: torch.Tensor | None = None
    """Per-dimension scale of the shape codes (``losses.code_scale``), for ``loss.shape_whiten``."""
    workers: int = 1
    max_seconds: float = 0.0
    """Stop after this much time (0: no limit); the caller saves the state and a rerun resumes."""
    decoded: DecodedShape | None = None
    """The frozen decoder and query points of ``loss.shape_sdf`` (``decoded_shape.DecodedShape``)."""


def run_steps(
    state: TrainState, dataset: EncoderViewDataset, loop: StepLoop, start: int = 0,
    on_step: Callable[[int, dict], None] | None = None,
) -> int:  # fmt: skip
    """Train ``state`` in place over ``loop.batches[start:]``; returns the slice step reached (stops early on
    ``loop.max_seconds``). ``on_step(slice_step, terms)`` runs after each step (progress, periodic saves)."""
    state.encoder.train()
    loader = DataLoader(
        EpochKeyed(dataset), batch_sampler=loop.batches[start:], collate_fn=collate, num_workers=loop.workers
    )
    t0, done = time.perf_counter(), start
    for batch in loader:
        for group in state.optimizer.param_groups:
            group["lr"] = loop.schedule.lr_at(state.step)
        out = state.encoder(batch["rgb"], batch["depth"])
        loss, terms = encoder_loss(out, batch, loop.loss, loop.code_std, loop.decoded)
        state.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        state.optimizer.step()
        state.step, done = state.step + 1, done + 1
        if on_step is not None:
            on_step(done, {k: float(v.detach()) for k, v in terms.items()} | {"loss": float(loss.detach())})
        if loop.max_seconds > 0 and time.perf_counter() - t0 > loop.max_seconds:
            break
    return done


def validate(encoder: RGBDEncoder, dataset: EncoderViewDataset, codes: dict, batch_size: int = 8,
             shape_error=None) -> dict:  # fmt: skip
    """Detection and pose/joint/shape-code figures on un-augmented views (the one-run training's ``val/``), and the
    decoded-SDF error of the regressed codes when ``shape_error`` judges them (:mod:`.shape_validation`)."""
    summary = summarize(validation_results(encoder, dataset, codes, batch_size, shape_error))
    return {k: float(v) for k, v in summary.items() if isinstance(v, (int, float))}


@torch.no_grad()
def validation_results(encoder: RGBDEncoder, dataset: EncoderViewDataset, codes: dict, batch_size: int = 8,
                       shape_error=None) -> list[dict]:  # fmt: skip
    """Every view's :func:`~centerart.training.encoder_metrics.view_metrics` (in the dataset's order), the encoder
    in eval mode meanwhile."""
    encoder.eval()
    loader = DataLoader(dataset, batch_size=batch_size, shuffle=False, collate_fn=collate, num_workers=0)
    results: list[dict] = []
    for batch in loader:
        out = encoder(batch["rgb"], batch["depth"])
        results += batch_view_metrics(out, batch, encoder.config, codes, shape_error)
    encoder.train()
    return results
