import numpy as np
from PIL import Image

from centerart.cli import main
from centerart.inference.decoder_show import gripper_segments


def test_gripper_wireframe_follows_pose():
    pose = np.eye(4)
    pose[:3, 3] = [1.0, 2.0, 3.0]
    segs = gripper_segments(pose)
    assert segs.shape == (4, 2, 3)
    assert np.allclose(segs[3, 1], [1.0, 2.04, 3.0])  # right pad centre: +y half opening from the TCP


def test_decoder_show_cli_writes_picture(tmp_path):
    out = tmp_path / "show.png"
    # shipped checkpoint, a training object: no SDF data needed (the code is in the checkpoint)
    rc = main(
        [
            "decoder",
            "show",
            "--data",
            str(tmp_path),
            "--object",
            "dishwasher_0001",
            "--out",
            str(out),
            "--states",
            "2",
            "--resolution",
            "32",
        ]
    )
    assert rc == 0 and out.is_file()
    img = np.asarray(Image.open(out))
    assert img.shape[1] > img.shape[0] and img.std() > 5  # two panels, not blank


def test_decoder_show_unknown_object_is_a_clean_error(tmp_path, capsys):
    rc = main(["decoder", "show", "--data", str(tmp_path), "--object", "nope", "--out", str(tmp_path / "x.png")])
    assert rc == 2 and "nope" in capsys.readouterr().err
