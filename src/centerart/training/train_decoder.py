"""``centerart train decoder``: auto-decoder training of the SGDF decoder on SDF sample files.

Writes to ``--out``::

    OUT/decoder.pt        the exported checkpoint (models/checkpoint.py format: weights, config, shape codes)
    OUT/config.json       this command's config (preset resolved into the decoder config)
    OUT/split.json        held-out objects and states
    OUT/metrics.json      final validation metrics
    OUT/logs/csv/...      per-step/epoch metrics (CSV) and OUT/logs/tensorboard/... (TensorBoard)
    OUT/lightning/last.ckpt   Lightning checkpoint (rerunning the same command resumes from it)

Training runs on CPU, one GPU, or several devices / nodes with DDP (``--devices``, ``--num-nodes``,
``--strategy``), the same code. Every process holds every shape code (one ``nn.Embedding``); DDP averages the
gradients of all parameters, codes included: an object's code gets the gradient of whichever processes drew it in
a step (zero from the others), and since each process's loss is a mean over its batch, the average is exactly the
gradient of one process holding the combined batch. Only global rank 0 holds OUT's lock and writes the exports.
"""

from __future__ import annotations

import json
import time
from contextlib import nullcontext
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np
import torch

from centerart.errors import CenterArtError
from centerart.models.code_fitting import CodeFitConfig
from centerart.models.decoder import PRESETS, DecoderConfig
from centerart.models.losses import GraspWeighting, LossConfig
from centerart.training.resume import resume_checkpoint
from centerart.utils.atomic import atomic_write_json
from centerart.utils.checks import at_least, between, positive
from centerart.utils.folders import check_output_folder, folder_lock
from centerart.utils.parallel import launcher_rank
from centerart.utils.torch_cpu import use_cpu_threads

if TYPE_CHECKING:
    from centerart.sdf.samples import StateData
    from centerart.training.decoder_data import DecoderSplit


@dataclass
class TrainDecoderConfig:
    data: Path
    """Folder of SDF sample files (``centerart sdf generate`` output)."""
    out: Path
    """Output folder (checkpoint, config, logs)."""
    preset: Literal["tiny", "small", "paper"] = "small"
    """Decoder size: tiny (tests), small (CPU), paper (8x512, weight norm, dropout 0.2)."""
    epochs: int = 30
    seed: int = 0
    batch_items: int = 8
    """(object, state) items per step."""
    points_per_item: int = 2048
    """Points drawn per item and step."""
    min_items_per_epoch: int = 256
    """An epoch draws at least this many items (small datasets repeat their items)."""
    max_points_per_state: int = 40000
    """Points of each state kept in memory (a seeded random subset)."""
    lr_decoder: float = 5e-4
    lr_codes: float = 1e-3
    grasp_weighting: GraspWeighting = "label"
    """Weighting of the grasp term: none | label (distance to nearest label) | surface (|sdf|)."""
    sdf_weight: float = 10.0
    code_weight: float = 1e-2
    """Weight of the Gaussian code prior (DeepSDF's 1/sigma^2 term), in training and in the validation code fits.
    1e-2 since session 10 (benchmarks/results/code_prior/: new objects' shapes generalize better than at 1e-4, the
    weight of every checkpoint made before); the shipped checkpoint is trained at 1e-2 since session 13."""
    heldout_object_fraction: float = 0.15
    heldout_states_per_object: int = 1
    val_every: int = 10
    """Validate every N epochs (held-out objects need a code fit, which costs time)."""
    val_code_fit_steps: int = 100
    accelerator: Literal["auto", "cpu", "gpu"] = "auto"
    devices: int = 1
    """Devices per node (GPUs, or CPU processes with ``--accelerator cpu``); more than one trains with DDP."""
    num_nodes: int = 1
    """Machines; more than one needs a cluster launcher (SLURM, torchrun) starting this command on each."""
    strategy: Literal["auto", "ddp", "ddp_spawn"] = "auto"
    """auto: Lightning's choice (DDP for several devices); ddp: one process per device, launched by Lightning or
    the cluster; ddp_spawn: processes spawned by this one (works from any caller, e.g. a test or the recipe)."""
    threads: int = 0
    """torch CPU threads (0: torch default)."""
    resume: bool = True
    """Resume from OUT/lightning/last.ckpt when it exists."""
    progress: bool = True
    decoder_overrides: dict[str, int | float | bool] = field(default_factory=dict)
    """Override preset fields, e.g. width/depth (Python API; the CLI takes the presets)."""

    def __post_init__(self):
        for name in ("epochs", "batch_items", "points_per_item", "min_items_per_epoch", "max_points_per_state"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 1)
        at_least("--val-every", self.val_every, 1)
        at_least("--val-code-fit-steps", self.val_code_fit_steps, 0)
        at_least("--heldout-states-per-object", self.heldout_states_per_object, 0)
        at_least("--threads", self.threads, 0)
        at_least("--devices", self.devices, 1)
        at_least("--num-nodes", self.num_nodes, 1)
        for name in ("lr_decoder", "lr_codes", "sdf_weight"):
            positive(f"--{name.replace('_', '-')}", getattr(self, name))
        at_least("--code-weight", self.code_weight, 0.0)
        between("--heldout-object-fraction", self.heldout_object_fraction, 0.0, 0.9)

    def decoder_config(self) -> DecoderConfig:
        from dataclasses import replace

        return replace(PRESETS[self.preset], **self.decoder_overrides)

    def loss_config(self) -> LossConfig:
        return LossConfig(
            grasp_weighting=self.grasp_weighting, sdf_weight=self.sdf_weight, code_weight=self.code_weight
        )


@dataclass
class _Data:
    """The loaded SDF states by role in the split, and what the checkpoint needs to know about them."""

    split: DecoderSplit
    train: list[StateData]
    heldout_states: list[StateData]
    heldout_objects: list[StateData]
    code_index: dict[str, int]
    bounds: np.ndarray  # (2, 3) box around every state's surface, object frame, m


def train_decoder(cfg: TrainDecoderConfig) -> dict:
    """Train on ``cfg.data``, export ``decoder.pt`` and return {checkpoint, metrics, split} (see the module doc).

    Everything that can be wrong with the inputs (data, a resume checkpoint, --out) is checked before the first
    file is written, and the run holds OUT's lock, so a second run into the same OUT refuses instead of mixing in.
    """
    import lightning as L

    if not Path(cfg.data).is_dir():
        raise CenterArtError(f"{cfg.data}: SDF data folder not found")
    out = check_output_folder(cfg.out)
    use_cpu_threads(cfg.threads)
    L.seed_everything(cfg.seed, workers=True, verbose=False)
    data = load_split_data(cfg)
    dcfg, lcfg = cfg.decoder_config(), cfg.loss_config()
    module = build_module(cfg, data)
    last = resume_checkpoint(out, cfg.resume, module)
    out.mkdir(parents=True, exist_ok=True)
    # Processes a launcher started besides rank 0 (strategy ddp) train into the same OUT without its lock.
    with folder_lock(out, blocking=False) if launcher_rank() == 0 else nullcontext():
        atomic_write_json(out / "config.json", {**asdict(cfg), "decoder": dcfg.to_dict(), "loss": asdict(lcfg)})
        atomic_write_json(out / "split.json", data.split.to_dict())
        train_loader, val_loader = _loaders(cfg, data)
        trainer = _trainer(cfg, out)
        t0 = time.perf_counter()
        trainer.fit(module, train_loader, val_loader, ckpt_path=str(last) if last else None)
        seconds = time.perf_counter() - t0
        if trainer.global_rank != 0:  # rank 0 alone validates and exports
            return {"checkpoint": None, "metrics": {}, "split": data.split}
        metrics = _final_metrics(cfg, trainer, module, val_loader, data, seconds)
        return _export(cfg, out, module, data, lcfg, metrics)


def build_module(cfg: TrainDecoderConfig, data: _Data):
    """The Lightning module of ``cfg`` over ``data``'s training objects (weights drawn from the torch RNG)."""
    from centerart.training.decoder_module import DecoderModule

    return DecoderModule(
        cfg.decoder_config(), cfg.loss_config(), data.split.train_objects, cfg.lr_decoder, cfg.lr_codes, cfg.epochs,
        heldout_object_states=data.heldout_objects,
        code_fit=CodeFitConfig(steps=cfg.val_code_fit_steps, code_weight=cfg.code_weight, seed=cfg.seed),
    )  # fmt: skip


def load_split_data(cfg: TrainDecoderConfig) -> _Data:
    """Load every state (points subsampled) and split them into training, held-out states and held-out objects."""
    from centerart.sdf.samples import load_states
    from centerart.training.decoder_data import make_split, surface_bounds

    states = load_states(cfg.data, cfg.max_points_per_state, cfg.seed, progress=cfg.progress)
    split = make_split(states, cfg.seed, cfg.heldout_object_fraction, cfg.heldout_states_per_object)
    roles = {(s.object_id, s.state_index): split.role(s.object_id, s.state_index) for s in states}
    by_role = {r: [s for s in states if roles[(s.object_id, s.state_index)] == r] for r in set(roles.values())}
    if not by_role.get("train"):
        raise CenterArtError(f"{cfg.data}: no training states left after the validation split")
    return _Data(
        split,
        by_role["train"],
        by_role.get("heldout_state", []),
        by_role.get("heldout_object", []),
        {o: i for i, o in enumerate(split.train_objects)},
        surface_bounds(states),
    )


def _loaders(cfg: TrainDecoderConfig, data: _Data):
    """(training loader: shuffled with a seeded generator, validation loader over held-out states or None)."""
    from torch.utils.data import DataLoader

    from centerart.training.decoder_data import PointBatchDataset

    # Several processes: Lightning shuffles with a DistributedSampler seeded by --seed, and a torch.Generator would
    # not survive the trip to spawned processes (its state tensor fails to unpickle from shared memory there).
    distributed = cfg.devices * cfg.num_nodes > 1
    gen = None if distributed else torch.Generator().manual_seed(cfg.seed)
    train_loader = DataLoader(
        PointBatchDataset(data.train, data.code_index, cfg.points_per_item, cfg.min_items_per_epoch),
        batch_size=cfg.batch_items,
        shuffle=True,
        generator=gen,
        drop_last=True,
    )
    val_loader = (
        DataLoader(
            PointBatchDataset(data.heldout_states, data.code_index, cfg.points_per_item), batch_size=cfg.batch_items
        )
        if data.heldout_states
        else None
    )
    return train_loader, val_loader


def _trainer(cfg: TrainDecoderConfig, out: Path):
    import lightning as L
    from lightning.pytorch.callbacks import ModelCheckpoint, TQDMProgressBar
    from lightning.pytorch.loggers import CSVLogger, TensorBoardLogger

    loggers = [CSVLogger(out / "logs", name="csv"), TensorBoardLogger(out / "logs", name="tensorboard")]
    ckpt_cb = ModelCheckpoint(
        dirpath=out / "lightning", save_last=True, save_top_k=1, every_n_epochs=cfg.val_every
    )  # no monitor: keeps the newest epoch checkpoint; last.ckpt is what a rerun resumes from
    return L.Trainer(
        max_epochs=cfg.epochs,
        accelerator=cfg.accelerator,
        devices=cfg.devices,
        num_nodes=cfg.num_nodes,
        strategy=cfg.strategy,
        logger=loggers,
        callbacks=[ckpt_cb, TQDMProgressBar(refresh_rate=10)] if cfg.progress else [ckpt_cb],
        enable_progress_bar=cfg.progress,
        check_val_every_n_epoch=cfg.val_every,
        num_sanity_val_steps=0,
        inference_mode=False,  # held-out-object code fitting needs autograd during validation
        log_every_n_steps=10,
        enable_model_summary=False,
        deterministic=False,
    )


def _final_metrics(cfg: TrainDecoderConfig, trainer, module, val_loader, data: _Data, seconds: float) -> dict:
    """The trainer's last metrics, validation redone with the final weights, and training time and throughput.

    The final validation runs in this process on the module directly (not through the trainer), so that it is the
    same single-process computation after one-device and after multi-process (DDP) training."""
    metrics = {k: float(v) for k, v in trainer.callback_metrics.items()}
    if data.heldout_states:
        # Final numbers with the final weights (the last in-loop validation may be up to val_every epochs old).
        metrics.update(module.heldout_state_metrics(val_loader))
    if data.heldout_objects:
        metrics.update({f"val_object/{k}": v for k, v in module.heldout_object_metrics().items()})
    world = cfg.devices * cfg.num_nodes
    points_seen = _global_step(trainer, Path(cfg.out)) * cfg.batch_items * cfg.points_per_item * world
    metrics["train_seconds"] = seconds
    metrics["train_points_per_second"] = points_seen / max(seconds, 1e-9)
    metrics["world_size"] = world
    return metrics


def _global_step(trainer, out: Path) -> int:
    """Optimizer steps of the run: the trainer's count, or after spawned DDP processes (whose counters do not come
    back to this process) the count saved in ``last.ckpt``."""
    last = out / "lightning" / "last.ckpt"
    if trainer.global_step or not last.is_file():
        return trainer.global_step
    return int(torch.load(last, map_location="cpu", weights_only=False).get("global_step", 0))


def training_object_fingerprints(data: Path, object_ids: list[str]) -> dict[str, str | None]:
    """Fingerprints of the training objects, found through the SDF data's manifest (its ``objects`` folder)."""
    from centerart.assets.fingerprint import fingerprint_folders

    try:
        objects = Path(json.loads((data / "manifest.json").read_text())["config"]["objects"])
    except (OSError, ValueError, KeyError, TypeError):
        return dict.fromkeys(object_ids)
    if (objects / "mobility.urdf").is_file():  # one object folder
        return fingerprint_folders({oid: objects for oid in object_ids if oid == objects.name})
    return fingerprint_folders({oid: objects / oid for oid in object_ids})


def _export(cfg: TrainDecoderConfig, out: Path, module, data: _Data, lcfg: LossConfig, metrics: dict) -> dict:
    """Write ``decoder.pt`` (CPU weights, codes, bounds, split, config, metrics) and ``metrics.json``."""
    path = export_decoder(out / "decoder.pt", cfg, module, data, {**asdict(cfg), "loss": asdict(lcfg)}, metrics)
    atomic_write_json(out / "metrics.json", metrics)
    return {"checkpoint": path, "metrics": metrics, "split": data.split}


def export_decoder(path: Path, cfg: TrainDecoderConfig, module, data: _Data, train_config: dict, metrics: dict):
    """The decoder checkpoint (models/checkpoint.py format) of ``module`` at ``path``, naming its training objects
    by fingerprint (found through ``cfg.data``'s manifest)."""
    from centerart.models.checkpoint import save_checkpoint

    module.decoder.cpu()
    return save_checkpoint(
        path,
        module.decoder,
        data.split.train_objects,
        module.code_array(),
        data.bounds,
        data.split.to_dict(),
        json.loads(json.dumps(train_config, default=str)),
        metrics,
        training_objects=training_object_fingerprints(Path(cfg.data), data.split.train_objects),
    )
