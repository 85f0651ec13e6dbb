"""Lightning module for the RGB-D encoder: one shared interface (forward -> loss and a dict of terms).

Validation logs the loss terms and, from the read-out objects (heatmap peaks), detection precision / recall and
median pose and joint errors (:mod:`centerart.training.encoder_metrics`), under ``val/``.
"""

from __future__ import annotations

import lightning as L
import torch

from centerart.models.encoder.config import EncoderConfig
from centerart.models.encoder.losses import EncoderLossConfig, code_scale, encoder_loss
from centerart.models.encoder.network import RGBDEncoder
from centerart.training.encoder_metrics import batch_view_metrics, summarize
from centerart.training.schedules import lr_factor


class EncoderModule(L.LightningModule):
    def __init__(self, config: EncoderConfig, loss: EncoderLossConfig, lr: float, epochs: int, codes=None):
        super().__init__()
        self.encoder = RGBDEncoder(config)
        self.loss_config = loss
        self.lr, self.epochs = lr, epochs
        self.codes = codes
        # The codes' per-dimension scale, for the whitened shape loss (a buffer: it moves with the module's device).
        self.register_buffer("code_std", code_scale(codes) if codes else torch.ones(config.code_dim), persistent=False)
        self._val_results: list[dict] = []
        self.save_hyperparameters({"encoder": config.to_dict(), "loss": loss.to_dict(), "lr": lr, "epochs": epochs})

    def forward(self, batch: dict):
        out = self.encoder(batch["rgb"], batch["depth"])
        loss, terms = encoder_loss(out, batch, self.loss_config, self.code_std)
        return loss, terms, out

    def training_step(self, batch, batch_idx):
        loss, terms, _ = self(batch)
        bs = batch["rgb"].shape[0]
        self.log("train/loss", loss, prog_bar=True, batch_size=bs)
        self.log_dict({f"train/{k}": v for k, v in terms.items()}, batch_size=bs)
        return loss

    def on_train_epoch_start(self):
        loader = self.trainer.train_dataloader
        dataset = getattr(loader, "dataset", None)
        if hasattr(dataset, "set_epoch"):
            dataset.set_epoch(self.current_epoch)

    def validation_step(self, batch, batch_idx):
        loss, terms, out = self(batch)
        bs = batch["rgb"].shape[0]
        self.log("val/loss", loss, batch_size=bs)
        self.log_dict({f"val/{k}": v for k, v in terms.items()}, batch_size=bs)
        self._val_results += batch_view_metrics(out, batch, self.encoder.config, self.codes)

    def on_validation_epoch_end(self):
        if self._val_results:
            summary = summarize(self._val_results)
            logged = {f"val/{k}": float(v) for k, v in summary.items() if isinstance(v, (int, float))}
            self.log_dict(logged)
        self._val_results = []

    def configure_optimizers(self):
        opt = torch.optim.Adam(self.encoder.parameters(), lr=self.lr)
        steps_per_epoch = max(1, self.trainer.estimated_stepping_batches // max(self.epochs, 1))
        total = max(1, self.trainer.estimated_stepping_batches)

        sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda step: lr_factor(step, steps_per_epoch, total))
        return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "interval": "step"}}
