"""The held-out check: test objects are compared to checkpoints' training objects by content fingerprint."""

from __future__ import annotations

from pathlib import Path

import pytest

from centerart.errors import CenterArtError
from centerart.evaluation.heldout import TrainingObjects, check_held_out, checkpoint_training_objects, training_overlap
from centerart.models.checkpoint import default_checkpoint
from centerart.models.encoder.checkpoint import default_encoder


def test_shipped_checkpoints_know_every_training_object_by_fingerprint():
    for path, kind in ((default_checkpoint(), "decoder"), (default_encoder(), "encoder")):
        t = checkpoint_training_objects(path, kind)
        assert len(t.fingerprints) == 34, kind
        assert not t.ids_only, kind


def test_overlap_by_fingerprint_and_by_id_without_fingerprint():
    trained = [TrainingObjects(Path("dec.pt"), {"f" * 64: "oven_0000"}, {"microwave_0003"})]
    assert training_overlap({"oven_0007": "f" * 64}, trained) == ["oven_0007 is training object 'oven_0000' of dec.pt"]
    assert training_overlap({"oven_0000": "e" * 64}, trained) == []  # same id, other content: a different object
    assert len(training_overlap({"microwave_0003": "e" * 64}, trained)) == 1  # id only: cannot prove it differs
    with pytest.raises(CenterArtError, match="tests/x: the test set shares objects"):
        check_held_out({"oven_0007": "f" * 64}, trained, "tests/x")
