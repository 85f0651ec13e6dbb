"""``centerart encoder show`` with the shipped encoder on a rendered kitchen: a picture per view with peaks drawn."""

import numpy as np
from PIL import Image

from centerart.cli import main


def test_encoder_show_draws_every_view(kitchen_dataset, tmp_path):
    out = tmp_path / "enc.png"
    assert main(["encoder", "show", "--scenes", str(kitchen_dataset), "--out", str(out), "--max-views", "2"]) == 0
    img = np.asarray(Image.open(out))
    assert img.shape[0] > 2 * 150 and img.shape[1] > 5 * 300 and img[..., :3].std() > 20  # 2 rows x 5 tiles
