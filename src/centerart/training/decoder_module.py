"""Lightning module for auto-decoder training: the SGDF decoder plus one learnable shape code per object.

Validation reports, separately:

- ``val_state/*``: training objects at held-out joint states, with their trained codes;
- ``val_object/*``: held-out objects, whose codes are fitted at validation time with the decoder frozen
  (:func:`centerart.models.code_fitting.fit_code`, fewer steps than at test time to keep epochs short).

Metrics: ``sdf`` = clamped L1 (m), ``grasp`` = weighted symmetric control-point error (m), ``sdf_near`` =
unclamped L1 at points with |sdf| < 1 cm (the part that shapes the mesh), ``grasp_near`` = control-point error at
points within 2 cm of a label TCP.
"""

from __future__ import annotations

import math
from dataclasses import asdict

import lightning as L
import numpy as np
import torch
from torch import nn

from centerart.models.code_fitting import CodeFitConfig, Observations, fit_code
from centerart.models.decoder import DecoderConfig, SGDFDecoder
from centerart.models.losses import (
    LossConfig,
    control_points_torch,
    decoder_loss,
    symmetric_control_point_error,
)
from centerart.sdf.samples import StateData


def keep_sdf_gradient_only(code_per_point: torch.Tensor, sdf_loss: torch.Tensor) -> None:
    """Make the backward pass of the total loss give ``code_per_point`` (the codes fed to the decoder, (N, D)) the
    gradient of ``sdf_loss`` alone (``LossConfig.grasp_moves_codes = False``); the decoder's weights still get
    the whole loss's. Why a hook and not a second forward pass with detached codes: the gradient with respect to
    the input costs one extra backward through the activations, a second forward would cost a whole step. The
    code prior acts on the codes directly, not through this tensor, and keeps its gradient."""
    (grad,) = torch.autograd.grad(sdf_loss, code_per_point, retain_graph=True)
    code_per_point.register_hook(lambda _: grad)


class DecoderModule(L.LightningModule):
    def __init__(
        self,
        decoder_config: DecoderConfig,
        loss_config: LossConfig,
        object_ids: list[str],
        lr_decoder: float = 5e-4,
        lr_codes: float = 1e-3,
        epochs: int = 100,
        heldout_object_states: list[StateData] | None = None,
        code_fit: CodeFitConfig | None = None,
    ):
        super().__init__()
        self.decoder = SGDFDecoder(decoder_config)
        self.loss_config = loss_config
        self.object_ids = list(object_ids)
        self.codes = nn.Embedding(len(object_ids), decoder_config.code_dim)
        nn.init.normal_(self.codes.weight, 0.0, 0.01)
        self.lr_decoder = lr_decoder
        self.lr_codes = lr_codes
        self.epochs = epochs
        self.heldout_object_states = heldout_object_states or []
        self.code_fit = code_fit or CodeFitConfig(steps=100)
        self.save_hyperparameters(
            {
                "decoder_config": decoder_config.to_dict(),
                "loss_config": asdict(loss_config),
                "object_ids": self.object_ids,
                "lr_decoder": lr_decoder,
                "lr_codes": lr_codes,
                "epochs": epochs,
            }
        )

    # ------------------------------------------------------------------ helpers
    def _flat(self, batch):
        b, p = batch["points"].shape[:2]
        code_idx = batch["code_index"]
        codes = self.codes(code_idx)  # (B, D)
        return {
            "code": codes[:, None, :].expand(b, p, -1).reshape(b * p, -1),
            "joint": batch["joint"][:, None].expand(b, p).reshape(-1),
            "xyz": batch["points"].reshape(-1, 3),
            "sdf": batch["sdf"].reshape(-1),
            "grasp_points": batch["grasp_points"].reshape(-1, 5, 3),
            "grasp_distance": batch["grasp_distance"].reshape(-1),
            "batch_codes": codes,
        }

    def _metrics(self, out, f) -> dict[str, torch.Tensor]:
        terms = decoder_loss(
            self.loss_config, out, f["xyz"], f["sdf"], f["grasp_points"], f["grasp_distance"], f["batch_codes"]
        )
        near = f["sdf"].abs() < 0.01
        terms["sdf_near"] = (out.sdf[near] - f["sdf"][near]).abs().mean() if near.any() else out.sdf.sum() * 0
        gnear = f["grasp_distance"] < 0.02
        if gnear.any():
            cp = control_points_torch(out.rotation[gnear], f["xyz"][gnear] + out.offset[gnear])
            terms["grasp_near"] = symmetric_control_point_error(cp, f["grasp_points"][gnear]).mean()
        return terms

    # ------------------------------------------------------------------ training
    def loss_terms(self, batch) -> dict[str, torch.Tensor]:
        """The training loss and its terms on one batch (``decoder_loss``; ``loss`` is what is minimised)."""
        f = self._flat(batch)
        out = self.decoder(f["code"], f["joint"], f["xyz"])
        terms = decoder_loss(
            self.loss_config, out, f["xyz"], f["sdf"], f["grasp_points"], f["grasp_distance"], f["batch_codes"]
        )
        if not self.loss_config.grasp_moves_codes and f["code"].requires_grad:
            keep_sdf_gradient_only(f["code"], self.loss_config.sdf_weight * terms["sdf"])
        return terms

    def training_step(self, batch, batch_idx):
        terms = self.loss_terms(batch)
        bs = len(batch["points"])
        self.log("train/loss", terms["loss"], prog_bar=True, batch_size=bs)
        self.log("train/sdf", terms["sdf"], prog_bar=True, batch_size=bs)
        self.log("train/grasp", terms["grasp"], prog_bar=True, batch_size=bs)
        self.log("train/code", terms["code"], batch_size=bs)
        return terms["loss"]

    def validation_step(self, batch, batch_idx):
        f = self._flat(batch)
        out = self.decoder(f["code"], f["joint"], f["xyz"])
        terms = self._metrics(out, f)
        bs = len(batch["points"])
        for k in ("sdf", "grasp", "sdf_near", "grasp_near"):
            if k in terms:
                # sync_dist: under DDP each process validates a share of the batches; the logged value is the mean
                self.log(f"val_state/{k}", terms[k], prog_bar=k == "sdf", batch_size=bs, sync_dist=True)

    def on_validation_epoch_end(self):
        if not self.heldout_object_states or self.trainer.sanity_checking:
            return
        # Every process fits the same codes (same seed, same data): the values agree; sync_dist only averages them.
        self.log_dict({f"val_object/{k}": v for k, v in self.heldout_object_metrics().items()}, sync_dist=True)

    def heldout_state_metrics(self, loader) -> dict[str, float]:
        """``val_state/*`` over a whole loader, in this process (no trainer): the means over points that
        :meth:`validation_step` logs, each batch weighted by its item count as Lightning weights them."""
        sums: dict[str, float] = {}
        counts: dict[str, int] = {}
        was_training = self.training
        self.eval()
        with torch.no_grad():
            for batch in loader:
                batch = {k: v.to(self.device) for k, v in batch.items()}
                f = self._flat(batch)
                terms = self._metrics(self.decoder(f["code"], f["joint"], f["xyz"]), f)
                bs = len(batch["points"])
                for k in ("sdf", "grasp", "sdf_near", "grasp_near"):
                    if k in terms:
                        sums[k] = sums.get(k, 0.0) + float(terms[k]) * bs
                        counts[k] = counts.get(k, 0) + bs
        self.train(was_training)
        return {f"val_state/{k}": sums[k] / counts[k] for k in sums}

    def heldout_object_metrics(self, max_points: int = 8192) -> dict[str, float]:
        """Fit each held-out object's code on even-indexed points of its states, score the odd ones."""
        device = self.device
        by_obj: dict[str, list[StateData]] = {}
        for s in self.heldout_object_states:
            by_obj.setdefault(s.object_id, []).append(s)
        sums: dict[str, list[float]] = {"sdf": [], "sdf_near": [], "grasp_near": []}
        for states in by_obj.values():
            fit_states = [(s.joint, s.points[0::2][:max_points], s.sdf[0::2][:max_points]) for s in states]
            code, _, _ = fit_code(self.decoder, Observations.from_samples(fit_states), self.code_fit)
            code_t = torch.as_tensor(code, device=device)
            for s in states:
                sl = slice(1, None, 2)
                xyz = torch.as_tensor(s.points[sl][:max_points], device=device)
                n = len(xyz)
                with torch.no_grad():
                    self.decoder.eval()
                    out = self.decoder(code_t.expand(n, -1), torch.full((n,), s.joint, device=device), xyz)
                    self.decoder.train()
                sdf = torch.as_tensor(s.sdf[sl][:n], device=device)
                c = self.loss_config.sdf_clamp
                sums["sdf"].append(float((out.sdf.clamp(-c, c) - sdf.clamp(-c, c)).abs().mean()))
                near = sdf.abs() < 0.01
                if near.any():
                    sums["sdf_near"].append(float((out.sdf[near] - sdf[near]).abs().mean()))
                gd = torch.as_tensor(s.grasp_distance[sl][:n], device=device)
                gnear = gd < 0.02
                if gnear.any():
                    gp = torch.as_tensor(s.grasp_points[sl][:n], device=device)
                    cp = control_points_torch(out.rotation[gnear], xyz[gnear] + out.offset[gnear])
                    sums["grasp_near"].append(float(symmetric_control_point_error(cp, gp[gnear]).mean()))
        return {k: float(np.mean(v)) for k, v in sums.items() if v}

    def configure_optimizers(self):
        opt = torch.optim.Adam(
            [
                {"params": self.decoder.parameters(), "lr": self.lr_decoder},
                {"params": self.codes.parameters(), "lr": self.lr_codes},
            ]
        )
        # Cosine decay to 5% over the run: stable late epochs without a hand-tuned step schedule.
        total = max(1, self.epochs)
        sched = torch.optim.lr_scheduler.LambdaLR(
            opt, lambda e: 0.05 + 0.95 * 0.5 * (1.0 + math.cos(math.pi * min(e, total) / total))
        )
        return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "interval": "epoch"}}

    def code_array(self) -> np.ndarray:
        return self.codes.weight.detach().cpu().numpy().astype(np.float32)
