"""Encoder checkpoints: one ``.pt`` file that loads without executing code (``torch.load(weights_only=True)``).

Contents (a plain dict): ``format`` ``"centerart-rgbd-encoder"``, ``version`` 1, ``encoder_config`` (JSON-able
dict), ``state_dict``, ``decoder`` (``sha256`` of the decoder checkpoint whose shape codes were the targets,
its ``object_ids`` and ``code_dim``), ``train_config``, ``metrics``, ``code_version``, ``training_objects``
(content fingerprint of every object in the training scenes, by id). Training also writes the
config as JSON beside it. The decoder link matters: shape codes only mean something to the decoder they came from,
so :func:`load_encoder` refuses a different decoder with a clear error.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from centerart.errors import CenterArtError
from centerart.models.checkpoint_files import check_fields, file_sha256, read_blob, write_blob
from centerart.models.encoder.config import EncoderConfig
from centerart.models.encoder.network import RGBDEncoder

FORMAT = "centerart-rgbd-encoder"
VERSION = 1
WEIGHTS_DIR = Path(__file__).resolve().parent.parent.parent / "weights"
DEFAULT_ENCODER_NAME = "encoder_small.pt"


@dataclass
class LoadedEncoder:
    encoder: RGBDEncoder
    path: Path
    decoder_sha256: str
    meta: dict = field(default_factory=dict, repr=False)


def save_encoder(
    path: Path, encoder: RGBDEncoder, decoder_path: Path, decoder_object_ids: list[str], train_config: dict,
    metrics: dict | None = None, training_objects: dict[str, str | None] | None = None,
) -> Path:  # fmt: skip
    from centerart.utils.manifest import code_version

    blob = {
        "format": FORMAT,
        "version": VERSION,
        "encoder_config": encoder.config.to_dict(),
        "state_dict": {k: v.detach().cpu().clone() for k, v in encoder.state_dict().items()},
        "decoder": {
            "sha256": file_sha256(decoder_path),
            "file": Path(decoder_path).name,
            "object_ids": list(decoder_object_ids),
            "code_dim": encoder.config.code_dim,
        },
        "train_config": train_config,
        "metrics": metrics or {},
        "code_version": code_version(),
        "training_objects": dict(training_objects or {}),
    }
    return write_blob(path, blob)


def _read(path: Path) -> dict:
    blob = read_blob(path, FORMAT, VERSION, "encoder")
    check_fields(blob, path, "encoder", {"encoder_config": dict, "state_dict": dict, "decoder": dict})
    return blob


def load_encoder(path: Path | None = None, decoder_path: Path | None = None, device="cpu") -> LoadedEncoder:
    """The encoder (eval mode). With ``decoder_path``, refuse it unless it is the decoder the encoder was trained
    against (same file hash). ``path=None``: the shipped encoder (:func:`default_encoder`)."""
    path = Path(path) if path is not None else default_encoder()
    blob = _read(path)
    try:
        encoder = RGBDEncoder(EncoderConfig.from_dict(blob["encoder_config"]))
        encoder.load_state_dict(blob["state_dict"])
    except (TypeError, ValueError, RuntimeError, KeyError) as err:
        raise CenterArtError(f"{path}: encoder weights do not match its config ({str(err).splitlines()[0]})") from None
    link = blob.get("decoder") or {}
    if decoder_path is not None and link.get("sha256") != file_sha256(decoder_path):
        raise CenterArtError(
            f"{path}: this encoder was trained against the shape codes of decoder {link.get('file')!r} "
            f"(sha256 {str(link.get('sha256'))[:12]}...), not {decoder_path}; use that decoder or retrain the encoder"
        )
    meta = {k: blob.get(k) for k in ("decoder", "train_config", "metrics", "code_version")}
    return LoadedEncoder(encoder.eval().to(device), path, str(link.get("sha256")), meta)


def default_encoder() -> Path:
    """The shipped ``small`` encoder (package data, ``centerart/weights/encoder_small.pt``)."""
    path = WEIGHTS_DIR / DEFAULT_ENCODER_NAME
    if not path.is_file():
        raise CenterArtError(f"{path}: the shipped encoder checkpoint is missing (reinstall the package)")
    return path
