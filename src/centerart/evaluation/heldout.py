"""Test objects must be objects no model was trained on: the check, by content fingerprint.

A checkpoint lists its training objects (``training_objects``: id -> fingerprint, written by the training
commands). Checkpoints made before fingerprints were recorded list ids only, and those made before the current
fingerprint scheme (``assets.fingerprint.is_current``) list fingerprints that change with the code version, so
such a record counts as ids only (the shipped checkpoints record current fingerprints). A checkpoint known by ids
only refuses every test object with one of those ids, because an id alone cannot prove two objects differ.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from centerart.assets.fingerprint import is_current
from centerart.errors import CenterArtError
from centerart.models.checkpoint import FORMAT as DECODER_FORMAT
from centerart.models.checkpoint import VERSION as DECODER_VERSION
from centerart.models.checkpoint_files import read_blob
from centerart.models.encoder.checkpoint import FORMAT as ENCODER_FORMAT
from centerart.models.encoder.checkpoint import VERSION as ENCODER_VERSION


@dataclass
class TrainingObjects:
    """What one checkpoint was trained on: fingerprints, and ids whose fingerprint is unknown."""

    checkpoint: Path
    fingerprints: dict[str, str]
    """fingerprint -> object id."""
    ids_only: set[str]


def checkpoint_training_objects(path: Path, kind: str) -> TrainingObjects:
    """The training objects of a ``kind`` ("decoder" or "encoder") checkpoint."""
    path = Path(path)
    fmt, version = (DECODER_FORMAT, DECODER_VERSION) if kind == "decoder" else (ENCODER_FORMAT, ENCODER_VERSION)
    blob = read_blob(path, fmt, version, kind)
    ids = list(blob["object_ids"] if kind == "decoder" else (blob.get("decoder") or {}).get("object_ids", []))
    recorded = dict(blob.get("training_objects") or {})
    if not recorded or any(fp and not is_current(fp) for fp in recorded.values()):
        recorded = {oid: None for oid in recorded}  # outdated fingerprints prove nothing
    fingerprints = {fp: oid.split("@")[0] for oid, fp in recorded.items() if fp}
    ids_only = {oid.split("@")[0] for oid, fp in recorded.items() if not fp}
    if not recorded:
        # No record of the training objects: every id the checkpoint knows may have been trained on. (With a
        # record, an encoder's other decoder ids are objects whose scenes it never saw; the decoder's own
        # checkpoint vouches for them by fingerprint.)
        ids_only |= set(ids)
    return TrainingObjects(path, fingerprints, ids_only)


def training_overlap(test_objects: dict[str, str], trained: list[TrainingObjects]) -> list[str]:
    """One line per test object (``object_id -> fingerprint``) that some checkpoint was trained on."""
    problems = []
    for oid, fp in sorted(test_objects.items()):
        for t in trained:
            if fp in t.fingerprints:
                problems.append(f"{oid} is training object {t.fingerprints[fp]!r} of {t.checkpoint.name}")
            elif oid in t.ids_only:
                problems.append(f"{oid}: {t.checkpoint.name} lists a training object of that id without a fingerprint")
    return problems


def check_held_out(test_objects: dict[str, str], trained: list[TrainingObjects], where: str) -> None:
    """Raise a clear error naming the test set ``where`` when it shares an object with a checkpoint's training."""
    problems = training_overlap(test_objects, trained)
    if problems:
        shown = "; ".join(problems[:5]) + (f"; and {len(problems) - 5} more" if len(problems) > 5 else "")
        raise CenterArtError(
            f"{where}: the test set shares objects with the models' training objects ({shown}); evaluate on objects "
            "generated with another seed, or on real objects no model saw"
        )
