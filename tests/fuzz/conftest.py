"""Inputs of the fuzz suite, built once per session and kept tiny: one generated microwave, a two-object box-cabinet
SDF folder, one state of synthetic grasp labels, a decoder checkpoint without shape codes, one rendered scene of the
shared ``single_dataset`` and a hand-made prediction folder. Every case copies what it damages into its own folder.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import torch

from centerart.grasps.labels import StateLabels
from centerart.models.checkpoint import default_checkpoint
from centerart.training.synthetic import write_box_cabinet_dataset


@dataclass
class FuzzInputs:
    """Pristine inputs; a case copies one (``copy``) before damaging it."""

    object_dir: Path  # one generated object folder (microwave_0000, seed 0)
    sdf_dir: Path  # SDF samples of two box cabinets, two states each
    labels_dir: Path  # grasp labels of object_dir's object, one state
    decoder_nocodes: Path  # the shipped decoder checkpoint with its "codes" removed
    scenes_dir: Path  # one rendered single-object scene (tiny intrinsics)
    prediction_dir: Path  # a prediction folder as `centerart predict` writes it (predictions.json only)

    @staticmethod
    def copy(src: Path, dst: Path) -> Path:
        shutil.copytree(src, dst, symlinks=True)
        return dst


@pytest.fixture(scope="session")
def fuzz_inputs(generated_dir, single_dataset, tmp_path_factory) -> FuzzInputs:
    root = tmp_path_factory.mktemp("fuzz_inputs")
    objects = root / "objects"
    shutil.copytree(generated_dir / "microwave_0000", objects / "microwave_0000")
    sdf = root / "sdf"
    write_box_cabinet_dataset(sdf, n_objects=2, n_states=2, n_points=600, seed=0)
    labels = root / "labels"
    StateLabels("microwave_0000", 0, 0.0, 0.0, "revolute", 1, np.tile(np.eye(4), (3, 1, 1)), np.full(3, 0.2),
                np.zeros((0, 4, 4)), np.zeros(0)).save(labels)  # fmt: skip
    blob = torch.load(default_checkpoint(), map_location="cpu", weights_only=True)
    del blob["codes"]
    nocodes = root / "decoder_nocodes.pt"
    torch.save(blob, nocodes)
    scenes = root / "scenes"
    shutil.copytree(single_dataset / "scene_000000", scenes / "scene_000000")
    prediction = root / "prediction"
    prediction.mkdir()
    (prediction / "predictions.json").write_text(json.dumps({"format": "centerart-predictions", "objects": []}))
    return FuzzInputs(objects / "microwave_0000", sdf, labels, nocodes, scenes, prediction)
