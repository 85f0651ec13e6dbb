import numpy as np

from centerart.viz.contact_sheet import labelled


def _caption_columns(img: np.ndarray) -> np.ndarray:
    """Columns of the caption bar (top 20 rows) that hold light text pixels."""
    return np.flatnonzero((img[:20].max(axis=2) > 200).any(axis=0))


def test_long_caption_shrinks_to_fit_the_image():
    blank = np.zeros((60, 200, 3), np.uint8)
    short = labelled(blank, "oven")
    long = labelled(blank, "scene_000028 storage_furniture true: collision_at_spawn, 117 cm from a label")
    assert _caption_columns(short).max() < 60  # a short caption keeps its size and stays short
    cols = _caption_columns(long)
    assert cols.max() <= 200 - 4  # the text ends inside the image (4 px margin) instead of being cut at its edge
    assert cols.max() > 120  # and still spans most of it (shrunk, not dropped)
