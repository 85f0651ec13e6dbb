"""The overlay's rejected-candidate toggle: on, the rejected grasps appear in their reasons' colours with a legend;
off (the default), the picture is exactly the one without any rejected candidates.

Hand-made prediction (tests/inference/test_prediction_io.py): one object 1.5 m ahead, camera 640 x 480, drawn on a
uniform dark-blue image, so the reason colours appear nowhere else."""

from __future__ import annotations

import dataclasses
import importlib.util
from pathlib import Path

import numpy as np

from centerart.viz.prediction_overlay import REASON_COLORS, draw_prediction

_spec = importlib.util.spec_from_file_location(
    "prediction_io_cases", Path(__file__).parents[1] / "inference" / "test_prediction_io.py"
)
cases = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cases)

BACKGROUND = np.zeros((480, 640, 3), np.uint8) + np.array([20, 30, 90], np.uint8)


def colour_pixels(img: np.ndarray, color, rows=slice(None)) -> int:
    return int(np.all(img[rows] == np.asarray(color, np.uint8), axis=-1).sum())


def test_rejected_drawn_by_reason_only_when_asked(tmp_path):
    pred = cases.hand_made_prediction()
    on = draw_prediction(BACKGROUND, [pred], cases.K, show_rejected=True)
    off = draw_prediction(BACKGROUND, [pred], cases.K)
    without = draw_prediction(BACKGROUND, [dataclasses.replace(pred, rejected_grasps=None, rejected_reasons=[])],
                              cases.K, show_rejected=True)  # fmt: skip
    assert np.array_equal(off, without)  # off: nothing of the rejected candidates, no legend
    below_legend = slice(80, None)  # the legend (top-left) has a swatch of each colour: count the grippers below it
    for reason, color in REASON_COLORS.items():
        assert colour_pixels(off, color) == 0, reason
        assert colour_pixels(on, color, below_legend) > 20, reason
        assert colour_pixels(on[:80, :200], color) >= 40, f"{reason}: no legend swatch"
    # The kept grasps are drawn over the rejected ones, as without them.
    kept = np.any(off != BACKGROUND, axis=-1) & ~np.any(without != BACKGROUND, axis=-1)
    assert not kept.any()
    from PIL import Image

    Image.fromarray(on).save(tmp_path / "overlay_rejected.png")


def test_max_rejected_limits_the_drawing():
    pred = cases.hand_made_prediction()
    poses = np.repeat(pred.rejected_grasps[1:2], 200, axis=0)
    poses[:, 0, 3] += np.linspace(-0.5, 0.5, 200)
    many = dataclasses.replace(pred, rejected_grasps=poses, rejected_reasons=["collides_with_observed"] * 200)
    few = draw_prediction(BACKGROUND, [many], cases.K, show_rejected=True, max_rejected=5)
    lots = draw_prediction(BACKGROUND, [many], cases.K, show_rejected=True, max_rejected=200)
    magenta = REASON_COLORS["collides_with_observed"]
    assert 0 < colour_pixels(few, magenta, slice(80, None)) < colour_pixels(lots, magenta, slice(80, None))
