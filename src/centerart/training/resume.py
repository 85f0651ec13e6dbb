"""Resuming a training run from Lightning's ``OUT/lightning/last.ckpt``, checked before the run writes anything.

Lightning reads the file deep inside ``Trainer.fit``, after the run has written its config and logs, and a damaged
or foreign file then fails with a library traceback (``KeyError: 'pytorch-lightning_version'``, a zip error, a
state-dict mismatch). Here the file is loaded safely (``weights_only=True``), its Lightning fields are checked and
its weights are compared with the model's names and shapes, so a bad file is one clear error and nothing is left
behind.
"""

from __future__ import annotations

from pathlib import Path

import torch

from centerart.errors import CenterArtError
from centerart.models.checkpoint_files import check_fields, load_torch_file

#: The fields of a Lightning training checkpoint that resuming uses, with their types.
LIGHTNING_FIELDS = {
    "pytorch-lightning_version": str,
    "epoch": int,
    "global_step": int,
    "state_dict": dict,
    "optimizer_states": list,
    "loops": dict,
}


def resume_checkpoint(out: Path, resume: bool, module: torch.nn.Module) -> Path | None:
    """``OUT/lightning/last.ckpt`` when resuming and it exists and fits ``module``; None when not resuming.

    Raises:
        CenterArtError: naming the file, when it is damaged, not a Lightning checkpoint, or holds another model.
    """
    last = Path(out) / "lightning" / "last.ckpt"
    if not resume or not last.is_file():
        return None
    kind = "training (Lightning last.ckpt)"
    blob = load_torch_file(last, kind)
    if not isinstance(blob, dict):
        raise CenterArtError(f"{last}: not a valid centerart {kind} checkpoint (holds a {type(blob).__name__})")
    check_fields(blob, last, kind, LIGHTNING_FIELDS)
    mismatch = _state_mismatch(blob["state_dict"], module.state_dict())
    if mismatch:
        raise CenterArtError(
            f"{last}: not a valid centerart {kind} checkpoint for this model ({mismatch}); "
            "use another --out, or --no-resume to start over"
        )
    return last


def _state_mismatch(saved: dict, expected: dict) -> str | None:
    """What differs between a saved state dict and the model's (names, then shapes), or None."""
    missing, extra = sorted(set(expected) - set(saved)), sorted(set(saved) - set(expected))
    if missing or extra:
        return f"{len(missing)} weights missing, {len(extra)} unexpected, e.g. {(missing or extra)[0]!r}"
    for name, tensor in expected.items():
        value = saved[name]
        if not isinstance(value, torch.Tensor) or tuple(value.shape) != tuple(tensor.shape):
            shape = tuple(value.shape) if isinstance(value, torch.Tensor) else type(value).__name__
            return f"weight {name!r} is {shape}, the model's is {tuple(tensor.shape)}"
    return None
