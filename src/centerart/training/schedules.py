"""Learning-rate multipliers of the encoder's training, shared by the one-run training (Lightning,
:mod:`~centerart.training.encoder_module`), the sliced training (:mod:`~centerart.training.slice_training`) and
the overfit check: linear warm-up from ``WARMUP_START`` x lr, then (one run) poly(0.9) decay, the published
schedule."""

from __future__ import annotations

WARMUP_START = 0.2
POLY_POWER = 0.9


def warmup_factor(step: int, warmup_steps: int) -> float:
    """Linear warm-up from WARMUP_START to 1 over ``warmup_steps`` steps, then 1."""
    return 1.0 if step >= warmup_steps else WARMUP_START + (1 - WARMUP_START) * step / warmup_steps


def lr_factor(step: int, steps_per_epoch: int, total: int) -> float:
    """The one-run multiplier at ``step``: warm-up over the first epoch, then poly decay to 0 at ``total``."""
    if step < steps_per_epoch:
        return warmup_factor(step, steps_per_epoch)
    return max(1e-3, (1 - step / total) ** POLY_POWER)
