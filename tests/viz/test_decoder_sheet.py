import numpy as np
from PIL import Image

from centerart.cli import main
from centerart.viz.object_renderer import marker_corners


def test_gripper_marker_follows_pose():
    # The reconstruction's grippers are the label sheet's markers now (stem, palm bar, two fingers) instead of a
    # wireframe; the same fact is checked on them: the right finger sits +y half the opening from the TCP.
    pose = np.eye(4)
    pose[:3, 3] = [1.0, 2.0, 3.0]
    corners = marker_corners(pose[None])
    assert corners.shape == (1, 4, 8, 3)
    right_finger = corners[0, 3]
    assert np.allclose(right_finger.mean(0)[:2], [1.0, 2.04])  # right pad centre: +y half opening from the TCP
    assert right_finger[:, 2].min() < 3.0 < right_finger[:, 2].max()  # the finger reaches past the TCP


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
