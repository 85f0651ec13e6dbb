"""The held-out shape figure of a sliced run's validation (``training.shape_validation``): a decoder's own code of an
object scores a few mm, another object's code or the mean code tens of mm; the points are the same on every call;
a missing object folder is no figure, and the validation summary carries the figure only where it was judged."""

from __future__ import annotations

import numpy as np
import pytest

from centerart.assets.articulated_object import ArticulatedObject
from centerart.models.checkpoint import load_decoder
from centerart.training.encoder_metrics import summarize_rows
from centerart.training.shape_validation import HeldOutShapeError


@pytest.fixture(scope="module")
def judge(generated_dir) -> tuple[HeldOutShapeError, dict]:
    """The shipped decoder (its training objects: 24 per category at seed 0, whose first ones ``generated_dir``
    regenerates) and its codes."""
    loaded = load_decoder(None)
    return HeldOutShapeError(loaded.decoder, generated_dir), loaded.codes


def _label(folder, object_id: str, fraction: float) -> dict:
    state = ArticulatedObject.load(folder / object_id).denormalize(fraction)
    return {"object_id": object_id, "joint": {"state": state, "state_normalized": fraction}}


@pytest.mark.parametrize("object_id", ["dishwasher_0000", "oven_0000", "storage_furniture_0000"])
def test_an_objects_own_code_scores_far_better_than_another_or_the_mean_code(judge, generated_dir, object_id):
    shapes, codes = judge
    mean = np.mean(np.stack(list(codes.values())), axis=0)
    for fraction in (0.0, 0.5):
        label = _label(generated_dir, object_id, fraction)
        own = shapes(codes[object_id], label)
        assert own < 5.0  # mm: the decoder reproduces its training objects (1.4-3.7 mm measured)
        assert shapes(mean, label) > 3 * own and shapes(codes["microwave_0001"], label) > 3 * own


def test_the_same_object_and_state_is_judged_on_the_same_points(judge, generated_dir):
    shapes, codes = judge
    label = _label(generated_dir, "dishwasher_0000", 0.3)
    fresh = HeldOutShapeError(load_decoder(None).decoder, generated_dir)
    assert fresh(codes["dishwasher_0001"], label) == shapes(codes["dishwasher_0001"], label)
    assert shapes(codes["dishwasher_0000"], {**label, "object_id": "no_such_object"}) is None


def test_the_summary_has_the_shape_figure_only_where_rows_were_judged():
    row = {"translation_cm": 1.0, "rotation_deg": 2.0, "joint_type_correct": True, "axis_deg": 1.0,
           "joint_state_error": 0.1, "joint_type": "revolute"}  # fmt: skip
    assert "shape_sdf_mm_median" not in summarize_rows([row])
    summary = summarize_rows([{**row, "shape_sdf_mm": 10.0}, {**row, "shape_sdf_mm": 20.0}, row])
    assert summary["shape_sdf_mm_median"] == 15.0 and summary["shape_sdf_mm_mean"] == 15.0
