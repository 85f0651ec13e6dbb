"""``centerart train encoder``: train the RGB-D encoder on rendered scenes against a decoder's shape codes.

Writes to ``--out``::

    OUT/encoder.pt            the exported checkpoint (models/encoder/checkpoint.py: weights, config, decoder link)
    OUT/config.json           this command's config with the resolved encoder config
    OUT/metrics.json          final validation metrics (held-out scenes), training time and images/s
    OUT/logs/csv/...          per-step / epoch metrics (CSV) and OUT/logs/tensorboard/... (TensorBoard)
    OUT/lightning/last.ckpt   Lightning checkpoint (rerunning the same command resumes from it)

Training runs on CPU, one GPU, or several devices / nodes with DDP (``--devices``, ``--num-nodes``,
``--strategy``), the same code.
"""

from __future__ import annotations

import json
import time
from contextlib import nullcontext
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Literal

import torch

from centerart.errors import CenterArtError
from centerart.models.encoder.config import PRESETS, EncoderConfig
from centerart.models.encoder.losses import EncoderLossConfig
from centerart.training.encoder_augment import AugmentConfig
from centerart.training.resume import resume_checkpoint
from centerart.utils.atomic import atomic_write_json
from centerart.utils.checks import at_least, positive
from centerart.utils.folders import check_output_folder, folder_lock
from centerart.utils.parallel import launcher_rank
from centerart.utils.torch_cpu import use_cpu_threads


@dataclass
class TrainEncoderConfig:
    scenes: tuple[Path, ...]
    """Training scene folders (``centerart scenes generate`` outputs; layouts may be mixed)."""
    out: Path
    """Output folder (checkpoint, config, logs)."""
    val_scenes: tuple[Path, ...] = ()
    """Validation scene folders: scenes of objects held out from training (the decoder's too)."""
    decoder: Path | None = None
    """Decoder checkpoint whose shape codes are the targets (default: the shipped decoder)."""
    preset: Literal["tiny", "small", "paper"] = "small"
    epochs: int = 30
    batch_size: int = 8
    lr: float = 6e-4
    seed: int = 0
    max_minutes: float = 0.0
    """Stop after this much training time (0: no limit), counted over resumed runs too (Lightning keeps the
    elapsed time in last.ckpt); the checkpoint is written either way."""
    val_every: int = 5
    val_depth: Literal["realistic", "true"] = "realistic"
    accelerator: Literal["auto", "cpu", "gpu"] = "auto"
    devices: int = 1
    num_nodes: int = 1
    strategy: Literal["auto", "ddp", "ddp_spawn"] = "auto"
    precision: Literal["32-true", "bf16-mixed", "16-mixed"] = "32-true"
    threads: int = 0
    """torch CPU threads (0: torch default)."""
    workers: int = 1
    """Data loader worker processes."""
    resume: bool = True
    """Resume from OUT/lightning/last.ckpt when it exists."""
    progress: bool = True
    augment: AugmentConfig = field(default_factory=AugmentConfig)
    loss: EncoderLossConfig = field(default_factory=EncoderLossConfig)
    encoder_overrides: dict[str, int | float | str] = field(default_factory=dict)
    """Override preset fields (Python API), e.g. input_width / input_height."""

    def __post_init__(self):
        for name in ("epochs", "batch_size", "val_every", "devices", "num_nodes"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 1)
        for name in ("threads", "workers", "max_minutes"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 0)
        positive("--lr", self.lr)
        if self.loss.shape_sdf > 0:
            raise CenterArtError(
                "--loss.shape-sdf: the decoded-shape term trains in sliced runs (centerart slices next --shape-sdf) "
                "and in benchmarks/overfit_encoder.py, not in centerart train encoder"
            )

    def encoder_config(self, code_dim: int) -> EncoderConfig:
        return replace(PRESETS[self.preset], **{**self.encoder_overrides, "code_dim": code_dim})


def scene_object_fingerprints(views: list[Path]) -> dict[str, str | None]:
    """Fingerprint of every object in the scenes of ``views`` (their ``scene.json`` names the asset folders)."""
    from centerart.assets.fingerprint import fingerprint_folders
    from centerart.scenes.description import SceneDescription

    folders = {}
    for scene_file in sorted({Path(v).parent.parent / "scene.json" for v in views}):
        for spec in SceneDescription.load(scene_file).objects:
            # Ids are not identities (a seed-0 and a seed-9000 cabinet_0000 differ): keep both under two keys.
            same = folders.get(spec.object_id, spec.path) == spec.path
            folders[spec.object_id if same else f"{spec.object_id}@{spec.path}"] = spec.path
    return fingerprint_folders(folders)


def _loaders(cfg: TrainEncoderConfig, enc_cfg: EncoderConfig, codes: dict):
    from torch.utils.data import DataLoader

    from centerart.training.encoder_data import EncoderViewDataset, checked_views, collate

    train_ds = EncoderViewDataset(checked_views(list(cfg.scenes)), enc_cfg, codes, cfg.augment, cfg.seed)
    if len(train_ds) < cfg.batch_size:
        raise CenterArtError(f"{len(train_ds)} training views, fewer than --batch-size {cfg.batch_size}")
    gen = torch.Generator().manual_seed(cfg.seed)
    common = {"batch_size": cfg.batch_size, "collate_fn": collate, "num_workers": cfg.workers}
    train = DataLoader(train_ds, shuffle=True, drop_last=True, generator=gen, **common)
    val = None
    if cfg.val_scenes:
        val_ds = EncoderViewDataset(checked_views(list(cfg.val_scenes)), enc_cfg, codes, None, depth=cfg.val_depth)
        val = DataLoader(val_ds, shuffle=False, **common)
    return train, val


def _trainer(cfg: TrainEncoderConfig, out: Path, has_val: bool):
    import lightning as L
    from lightning.pytorch.callbacks import ModelCheckpoint, TQDMProgressBar
    from lightning.pytorch.loggers import CSVLogger, TensorBoardLogger

    # No monitor, top 1, every epoch: the newest epoch is kept and last.ckpt (what a rerun resumes from) is refreshed
    # after every epoch, validated or not (by default Lightning saves at validation ends only).
    ckpt_cb = ModelCheckpoint(
        dirpath=out / "lightning", save_last=True, save_top_k=1, every_n_epochs=1, save_on_train_epoch_end=True
    )
    callbacks = [ckpt_cb, TQDMProgressBar(refresh_rate=5)] if cfg.progress else [ckpt_cb]
    return L.Trainer(
        max_epochs=cfg.epochs,
        max_time={"minutes": cfg.max_minutes} if cfg.max_minutes > 0 else None,
        accelerator=cfg.accelerator,
        devices=cfg.devices,
        num_nodes=cfg.num_nodes,
        strategy=cfg.strategy,
        precision=cfg.precision,
        logger=[CSVLogger(out / "logs", name="csv"), TensorBoardLogger(out / "logs", name="tensorboard")],
        callbacks=callbacks,
        enable_progress_bar=cfg.progress,
        check_val_every_n_epoch=cfg.val_every if has_val else None,
        limit_val_batches=1.0 if has_val else 0,
        num_sanity_val_steps=0,
        log_every_n_steps=5,
        enable_model_summary=False,
    )


def train_encoder(cfg: TrainEncoderConfig) -> dict:
    """Train (or resume), validate, export ``OUT/encoder.pt``; returns the checkpoint path and metrics.

    The decoder checkpoint, every view (labels and images), a resume checkpoint and --out are checked before the
    first file is written; the run holds OUT's lock, so a second run into the same OUT refuses."""
    import lightning as L

    from centerart.models.checkpoint import default_checkpoint, load_shape_codes
    from centerart.training.encoder_module import EncoderModule

    decoder_path = Path(cfg.decoder) if cfg.decoder is not None else default_checkpoint()
    codes = load_shape_codes(decoder_path)
    out = check_output_folder(cfg.out)
    use_cpu_threads(cfg.threads)
    L.seed_everything(cfg.seed, workers=True, verbose=False)
    enc_cfg = cfg.encoder_config(code_dim=len(next(iter(codes.values()))))
    train_loader, val_loader = _loaders(cfg, enc_cfg, codes)
    config_dict = json.loads(json.dumps({**asdict(cfg), "encoder": enc_cfg.to_dict()}, default=str))
    module = EncoderModule(enc_cfg, cfg.loss, cfg.lr, cfg.epochs, codes=codes)
    last = resume_checkpoint(out, cfg.resume, module)
    out.mkdir(parents=True, exist_ok=True)
    # Processes a launcher started besides rank 0 (strategy ddp) train into the same OUT without its lock.
    with folder_lock(out, blocking=False) if launcher_rank() == 0 else nullcontext():
        atomic_write_json(out / "config.json", config_dict)
        trainer = _trainer(cfg, out, val_loader is not None)
        t0 = time.perf_counter()
        trainer.fit(module, train_loader, val_loader, ckpt_path=str(last) if last else None)
        seconds = time.perf_counter() - t0
        if val_loader is not None:
            trainer.validate(module, val_loader, verbose=False)  # final numbers with the final weights
        if trainer.global_rank != 0:  # rank 0 alone exports
            return {"checkpoint": None, "metrics": {}}
        metrics = _metrics(cfg, trainer, seconds, resumed=last is not None)
        return _export(cfg, out, module, decoder_path, codes, config_dict, metrics, train_loader.dataset.views)


def _metrics(cfg: TrainEncoderConfig, trainer, seconds: float, resumed: bool) -> dict:
    metrics = {k: float(v) for k, v in trainer.callback_metrics.items()}
    images = trainer.global_step * cfg.batch_size * cfg.devices * cfg.num_nodes
    metrics.update(train_seconds_this_run=seconds, steps=trainer.global_step, epochs=trainer.current_epoch)
    metrics["resumed"] = bool(resumed)
    # A resumed run's global step counts earlier runs' steps too: no honest rate without the restored step count.
    metrics["train_images_per_second"] = None if resumed else images / max(seconds, 1e-9)
    return metrics


def _export(cfg, out: Path, module, decoder_path: Path, codes: dict, config_dict: dict, metrics: dict, views) -> dict:
    """Write ``encoder.pt`` (with the fingerprints of the training scenes' objects) and ``metrics.json``."""
    from centerart.models.encoder.checkpoint import save_encoder

    trained_on = scene_object_fingerprints(views)
    path = save_encoder(
        out / "encoder.pt", module.encoder.cpu(), decoder_path, sorted(codes), config_dict, metrics, trained_on
    )
    atomic_write_json(out / "metrics.json", metrics)
    return {"checkpoint": path, "metrics": metrics}
