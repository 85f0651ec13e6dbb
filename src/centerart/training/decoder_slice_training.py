"""SGDF decoder training in slices: the auto-decoder's whole state (weights, shape codes, Adam moments, step) in
one file, and a step loop whose draws depend on the run's seed and the global step only.

``centerart slices decoder`` (:mod:`centerart.recipe.decoder_slices`) continues this state one working period at a
time on a fixed object set. For the cut between slices to be invisible, the (object, state) items of global step
``s`` are positions ``s * B .. s * B + B - 1`` of a sequence of epochs, each epoch a permutation of the training
states drawn from (seed, epoch), and an item's points come from a generator seeded by (seed, step, slot); the
learning rates follow from the global step. A run cut anywhere and resumed from the file gives the weights an
uninterrupted run gives (tested to float tolerance on CPU).

Why not Lightning (which ``centerart train decoder`` uses): its resume does not restore the random draws of the
point sampler (the global torch RNG), so a resumed run draws other points than an uninterrupted one.

State file (``torch.load(weights_only=True)``): ``format`` ``"centerart-decoder-train-state"``, ``version`` 1,
``decoder_config``, ``object_ids`` (the order of the code rows), ``state_dict`` (decoder and codes), ``optimizer``
(Adam's state dict, groups: decoder, codes), ``step`` (global optimizer steps so far), ``meta`` (free JSON-able
dict: the ledger's bookkeeping).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from torch.utils.data import default_collate

from centerart.errors import CenterArtError
from centerart.models.checkpoint_files import check_fields, read_blob, write_blob
from centerart.models.decoder import DecoderConfig
from centerart.sdf.samples import StateData
from centerart.training.decoder_data import PointBatchDataset
from centerart.training.decoder_module import DecoderModule
from centerart.training.slice_training import SliceSchedule

FORMAT = "centerart-decoder-train-state"
VERSION = 1


@dataclass
class DecoderTrainState:
    module: DecoderModule
    """The decoder, the training objects' codes (rows in ``module.object_ids`` order) and the loss config."""
    optimizer: torch.optim.Adam
    step: int = 0
    meta: dict | None = None


def new_decoder_state(build: Callable[[], DecoderModule], seed: int) -> DecoderTrainState:
    """The module ``build()`` makes, its weights and codes drawn from ``seed``; fresh Adam; step 0."""
    torch.manual_seed(seed)
    module = build()
    return DecoderTrainState(module, module.configure_optimizers()["optimizer"], 0, {})


def save_decoder_state(path: Path, state: DecoderTrainState) -> Path:
    blob = {
        "format": FORMAT,
        "version": VERSION,
        "decoder_config": state.module.decoder.config.to_dict(),
        "object_ids": list(state.module.object_ids),
        "state_dict": {k: v.detach().cpu().clone() for k, v in state.module.state_dict().items()},
        "optimizer": state.optimizer.state_dict(),
        "step": int(state.step),
        "meta": dict(state.meta or {}),
    }
    return write_blob(path, blob)


def load_decoder_state(path: Path, module: DecoderModule) -> DecoderTrainState:
    """The state saved at ``path``, loaded into ``module``; a state of another decoder layout or object set is
    one error line naming the file."""
    kind = "decoder training state"
    blob = read_blob(path, FORMAT, VERSION, kind)
    fields = {"decoder_config": dict, "object_ids": list, "state_dict": dict, "optimizer": dict, "step": int,
              "meta": dict}  # fmt: skip
    check_fields(blob, path, kind, fields)
    if DecoderConfig.from_dict(blob["decoder_config"]) != module.decoder.config:
        raise CenterArtError(f"{path}: a {kind} of another decoder layout than the run's")
    if blob["object_ids"] != list(module.object_ids):
        raise CenterArtError(f"{path}: a {kind} of other training objects than the run's")
    optimizer = module.configure_optimizers()["optimizer"]
    try:
        module.load_state_dict(blob["state_dict"])
        optimizer.load_state_dict(blob["optimizer"])
    except (RuntimeError, ValueError, KeyError) as err:
        raise CenterArtError(f"{path}: damaged {kind} ({str(err).splitlines()[0]})") from None
    return DecoderTrainState(module, optimizer, blob["step"], blob["meta"])


class KeyedBatches:
    """The batch of each global step, drawn from the run's seed and the step alone (see the module doc)."""

    def __init__(self, dataset: PointBatchDataset, batch_items: int, seed: int):
        self.dataset, self.batch_items, self.seed = dataset, batch_items, seed
        self._orders: dict[int, np.ndarray] = {}

    def _order(self, epoch: int) -> np.ndarray:
        if epoch not in self._orders:
            self._orders = {epoch: np.random.default_rng([self.seed, epoch]).permutation(len(self.dataset.states))}
        return self._orders[epoch]

    def batch(self, step: int) -> dict[str, torch.Tensor]:
        n, items = len(self.dataset.states), []
        for slot in range(self.batch_items):
            epoch, index = divmod(step * self.batch_items + slot, n)
            key = np.random.SeedSequence([self.seed, step, slot]).generate_state(1, np.uint64)[0]
            generator = torch.Generator().manual_seed(int(key))
            items.append(self.dataset.item(int(self._order(epoch)[index]), generator))
        return default_collate(items)


def run_decoder_steps(
    state: DecoderTrainState, batches: KeyedBatches, schedule: SliceSchedule, until: int, max_seconds: float = 0.0,
    on_step: Callable[[dict], None] | None = None,
) -> int:  # fmt: skip
    """Train ``state`` in place up to global step ``until`` (or ``max_seconds``, 0: no limit); returns the global
    step reached. Each parameter group's rate is its base rate times ``schedule.factor_at(step)``."""
    module, t0 = state.module, time.perf_counter()
    base = [module.lr_decoder, module.lr_codes]
    module.train()
    while state.step < until:
        for group, lr in zip(state.optimizer.param_groups, base, strict=True):
            group["lr"] = lr * schedule.factor_at(state.step)
        terms = module.loss_terms(batches.batch(state.step))
        state.optimizer.zero_grad(set_to_none=True)
        terms["loss"].backward()
        state.optimizer.step()
        state.step += 1
        if on_step is not None:
            on_step({k: float(v.detach()) for k, v in terms.items()})
        if max_seconds > 0 and time.perf_counter() - t0 > max_seconds:
            break
    return state.step


def validate_decoder(state: DecoderTrainState, heldout_states: list[StateData], seed: int, batch_items: int,
                     points_per_item: int) -> dict:  # fmt: skip
    """Held-out states of training objects (``val_state/*``, with their trained codes) and held-out objects
    (``val_object/*``, codes fitted with the decoder frozen): SDF and grasp errors in metres (DecoderModule)."""
    from torch.utils.data import DataLoader

    module = state.module
    figures: dict[str, float] = {}
    if heldout_states:
        codes = {o: i for i, o in enumerate(module.object_ids)}
        dataset = PointBatchDataset(heldout_states, codes, points_per_item)
        torch.manual_seed(seed)  # the same held-out points at every slice
        figures.update(module.heldout_state_metrics(DataLoader(dataset, batch_size=batch_items)))
    if module.heldout_object_states:
        figures.update({f"val_object/{k}": v for k, v in module.heldout_object_metrics().items()})
    return figures


def refit_training_codes(state: DecoderTrainState, train_states: list[StateData], steps: int, seed: int,
                         points_per_step: int = 4096, progress: bool = True) -> dict:  # fmt: skip
    """Replace every training object's code by a code fitted to its training SDF samples from the zero code, the
    decoder frozen, under the run's code prior: what ``centerart eval decoder`` does for an object it never saw.
    Adam's first moments of the codes are zeroed (they belong to the old codes). With
    ``LossConfig.grasp_moves_codes = False`` afterwards, the grasp field is trained on codes a test-time fit finds.
    Returns the mean and max distance between old and new codes."""
    from tqdm import tqdm

    from centerart.models.code_fitting import CodeFitConfig, Observations, fit_code

    module = state.module
    by_obj: dict[str, list[StateData]] = {}
    for s in train_states:
        by_obj.setdefault(s.object_id, []).append(s)
    cfg = CodeFitConfig(steps=steps, points_per_step=points_per_step, code_weight=module.loss_config.code_weight,
                        seed=seed)  # fmt: skip
    weight = module.codes.weight
    moved = []
    for row, oid in enumerate(tqdm(module.object_ids, desc="refit codes", disable=not progress)):
        obs = Observations.from_states(by_obj[oid])
        code = torch.as_tensor(fit_code(module.decoder, obs, cfg)[0])
        with torch.no_grad():
            moved.append(float((weight[row] - code).norm()))
            weight[row] = code
    adam = state.optimizer.state.get(weight)
    if adam and "exp_avg" in adam:
        adam["exp_avg"].zero_()
    return {"mean_code_change": float(np.mean(moved)), "max_code_change": float(np.max(moved))}
