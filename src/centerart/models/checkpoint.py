"""Decoder checkpoints: one self-contained ``.pt`` file with everything later stages need.

Contents (a plain dict, loadable with ``torch.load(weights_only=True)``):

- ``format``: ``"centerart-sgdf-decoder"``, ``version``: 1;
- ``decoder_config``: :class:`~centerart.models.decoder.DecoderConfig` as a dict;
- ``state_dict``: the decoder weights;
- ``object_ids`` (list of str) and ``codes`` (K, code_dim) float32: the trained shape code of every training
  object (one code per object, shared by all its joint states);
- ``bounds`` (2, 3): the axis-aligned box (object canonical frame, m) of the training samples' surface points,
  padded; reconstruction evaluates the network inside it;
- ``split``: which objects/states were held out for validation; ``train_config``: the training config;
  ``metrics``: final validation numbers; ``code_version``;
- ``training_objects``: content fingerprint (:mod:`centerart.assets.fingerprint`) of every object whose data
  trained it, by object id (None where the folder was not found); the scene evaluation refuses test objects
  that share one.

A grasp critic fitted to the checkpoint's grasps may sit beside it as ``<checkpoint>.critic.json``
(:mod:`~centerart.models.grasp_critic`); :func:`load_decoder` loads it too.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from centerart.errors import CenterArtError
from centerart.models.checkpoint_files import check_fields, read_blob, write_blob
from centerart.models.decoder import DecoderConfig, SGDFDecoder
from centerart.models.grasp_critic import GraspCritic, load_critic

FORMAT = "centerart-sgdf-decoder"
VERSION = 1
WEIGHTS_DIR = Path(__file__).resolve().parent.parent / "weights"
DEFAULT_CHECKPOINT_NAME = "sgdf_small.pt"


@dataclass
class LoadedDecoder:
    decoder: SGDFDecoder
    codes: dict[str, np.ndarray]
    bounds: np.ndarray
    path: Path
    meta: dict = field(default_factory=dict, repr=False)
    critic: GraspCritic | None = field(default=None, repr=False)
    """The grasp critic stored beside the checkpoint (:mod:`~centerart.models.grasp_critic`), if any."""
    anchor_critic: GraspCritic | None = field(default=None, repr=False)
    """The ranker of grasps anchored in the observed depth stored beside it (``<checkpoint>.anchor_critic.json``,
    features ``grasp_critic.ANCHOR_FEATURES``), if any."""

    @property
    def code_weight(self) -> float:
        """The weight of the code prior the decoder was trained with (its ``train_config``; the default where it
        recorded none): new shape codes are fitted under the same prior."""
        from centerart.models.losses import LossConfig

        loss = (self.meta.get("train_config") or {}).get("loss") or {}
        return float(loss.get("code_weight", LossConfig.code_weight))

    def code(self, object_id: str) -> np.ndarray:
        if object_id not in self.codes:
            raise CenterArtError(
                f"{self.path}: object {object_id!r} has no trained shape code "
                f"(known: {', '.join(sorted(self.codes)[:8])}{', ...' if len(self.codes) > 8 else ''}); "
                "fit one with centerart.models.code_fitting"
            )
        return self.codes[object_id]


def save_checkpoint(
    path: Path,
    decoder: SGDFDecoder,
    object_ids: list[str],
    codes: torch.Tensor | np.ndarray,
    bounds: np.ndarray,
    split: dict,
    train_config: dict,
    metrics: dict | None = None,
    training_objects: dict[str, str | None] | None = None,
) -> Path:
    from centerart.utils.manifest import code_version

    blob = {
        "format": FORMAT,
        "version": VERSION,
        "decoder_config": decoder.config.to_dict(),
        "state_dict": {k: v.detach().cpu().clone() for k, v in decoder.state_dict().items()},
        "object_ids": list(object_ids),
        "codes": torch.as_tensor(np.asarray(codes, np.float32)),
        "bounds": torch.as_tensor(np.asarray(bounds, np.float32)),
        "split": split,
        "train_config": train_config,
        "metrics": metrics or {},
        "code_version": code_version(),
        "training_objects": dict(training_objects or {}),
    }
    return write_blob(path, blob)


#: Fields every decoder checkpoint must have, with their types (after ``torch.load``).
FIELDS = {"decoder_config": dict, "state_dict": dict, "object_ids": list, "codes": torch.Tensor, "bounds": torch.Tensor}


def _read(path: Path) -> dict:
    """The checkpoint dict, its fields checked: shape codes (K, code_dim) finite for K string object ids, bounds a
    finite (2, 3) box."""
    blob = read_blob(path, FORMAT, VERSION, "decoder")
    check_fields(blob, path, "decoder", FIELDS)
    codes, ids, bounds = blob["codes"], blob["object_ids"], blob["bounds"]
    problem = None
    if codes.ndim != 2 or codes.shape[0] != len(ids) or not codes.is_floating_point():
        problem = f"codes of shape {tuple(codes.shape)} for {len(ids)} object ids"
    elif not all(isinstance(i, str) for i in ids):
        problem = "object_ids are not all strings"
    elif not torch.isfinite(codes).all():
        problem = "non-finite shape codes"
    elif tuple(bounds.shape) != (2, 3) or not bounds.is_floating_point() or not torch.isfinite(bounds).all():
        problem = f"bounds of shape {tuple(bounds.shape)}, expected a finite (2, 3) box"
    if problem:
        raise CenterArtError(f"{path}: not a valid centerart decoder checkpoint ({problem})")
    return blob


def load_shape_codes(path: Path) -> dict[str, np.ndarray]:
    """The trained shape code (code_dim,) float32 of every training object, by object id."""
    blob = _read(path)
    codes = blob["codes"].numpy()
    return {oid: codes[i].copy() for i, oid in enumerate(blob["object_ids"])}


def load_decoder(path: Path | None = None, device: str | torch.device = "cpu") -> LoadedDecoder:
    """The decoder (eval mode), its shape codes and bounds. ``path=None``: :func:`default_checkpoint`."""
    path = Path(path) if path is not None else default_checkpoint()
    blob = _read(path)
    try:
        decoder = SGDFDecoder(DecoderConfig.from_dict(blob["decoder_config"]))
        decoder.load_state_dict(blob["state_dict"])
    except (TypeError, ValueError, RuntimeError, KeyError) as err:
        raise CenterArtError(f"{path}: decoder weights do not match its config ({err})") from None
    decoder.eval().to(device)
    meta = {k: blob.get(k) for k in ("split", "train_config", "metrics", "code_version")}
    codes = blob["codes"].numpy()
    return LoadedDecoder(
        decoder=decoder,
        codes={oid: codes[i].copy() for i, oid in enumerate(blob["object_ids"])},
        bounds=blob["bounds"].numpy().astype(np.float64),
        path=path,
        meta=meta,
        critic=load_critic(path),
        anchor_critic=load_critic(path, "anchor_critic"),
    )


def default_checkpoint() -> Path:
    """The shipped ``small`` decoder checkpoint (package data, ``centerart/weights/sgdf_small.pt``)."""
    path = WEIGHTS_DIR / DEFAULT_CHECKPOINT_NAME
    if not path.is_file():
        raise CenterArtError(f"{path}: the shipped decoder checkpoint is missing (reinstall the package)")
    return path
