"""Inputs a user has, and every bad one named in a one-line error."""

import json

import numpy as np
import pytest
from PIL import Image

from centerart.errors import CenterArtError
from centerart.geometry.camera import Intrinsics
from centerart.inference.inputs import check_inputs, read_depth, read_intrinsics, read_rgb

CAM = Intrinsics(64, 48, 60.0, 60.0, 31.5, 23.5)


def test_depth_png_in_millimetres_and_npy_in_metres(tmp_path):
    mm = np.full((48, 64), 1500, np.uint16)
    Image.fromarray(mm).save(tmp_path / "d.png")
    assert np.allclose(read_depth(tmp_path / "d.png"), 1.5)
    assert np.allclose(read_depth(tmp_path / "d.png", depth_scale=0.0001), 0.15)
    np.save(tmp_path / "d.npy", np.full((48, 64), 2.0, np.float32))
    assert np.allclose(read_depth(tmp_path / "d.npy"), 2.0)


def test_intrinsics_json_and_ros_camera_info(tmp_path):
    (tmp_path / "k.json").write_text(json.dumps({"K": CAM.K.tolist(), "width": 64, "height": 48}))
    assert read_intrinsics(tmp_path / "k.json") == CAM
    ros = "width: 64\nheight: 48\nk: [60.0, 0.0, 31.5, 0.0, 60.0, 23.5, 0.0, 0.0, 1.0]\ndistortion_model: plumb_bob\n"
    (tmp_path / "info.yaml").write_text(ros)
    assert read_intrinsics(tmp_path / "info.yaml") == CAM
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(CenterArtError, match=r"--intrinsics .*bad\.json: not readable"):
        read_intrinsics(tmp_path / "bad.json")
    (tmp_path / "nok.json").write_text(json.dumps({"width": 64, "height": 48}))
    with pytest.raises(CenterArtError, match="no 3x3 K"):
        read_intrinsics(tmp_path / "nok.json")


def test_unreadable_files_are_named(tmp_path):
    (tmp_path / "x.png").write_bytes(b"not a png")
    with pytest.raises(CenterArtError, match=r"--rgb .*x\.png: not a readable image"):
        read_rgb(tmp_path / "x.png")
    with pytest.raises(CenterArtError, match=r"--depth .*x\.png: not a readable depth image"):
        read_depth(tmp_path / "x.png")
    with pytest.raises(CenterArtError, match="file not found"):
        read_rgb(tmp_path / "missing.png")


@pytest.mark.parametrize(
    ("rgb_shape", "depth", "camera", "message"),
    [
        ((48, 64, 3), np.ones((40, 64)), CAM, "rgb is 64x48 but depth is 64x40"),
        ((48, 64, 3), np.ones((48, 64)), Intrinsics(640, 480, 60, 60, 319.5, 239.5), "intrinsics are for a 640x480"),
        ((48, 64, 3), np.zeros((48, 64)), CAM, "no valid pixel"),
        ((48, 64, 3), np.full((48, 64), np.nan), CAM, "no valid pixel"),
        ((48, 64, 3), np.full((48, 64), 1500.0), CAM, "looks like millimetres"),
        ((48, 64, 3), np.ones((48, 64)), Intrinsics(64, 48, 60, 60, 200.0, 23.5), "principal point"),
    ],
)
def test_bad_frames_are_refused(rgb_shape, depth, camera, message):
    with pytest.raises(CenterArtError, match=message):
        check_inputs(np.zeros(rgb_shape, np.uint8), depth, camera)


def test_holes_are_normal():
    depth = np.ones((48, 64))
    depth[:10] = np.nan
    depth[10:20] = 0
    out = check_inputs(np.zeros((48, 64, 3), np.uint8), depth, CAM)
    assert (out[:20] == 0).all() and (out[20:] == 1).all()


def test_predict_cli_names_bad_inputs(tmp_path, capsys):
    from centerart.cli import main

    rgb = tmp_path / "rgb.png"
    Image.fromarray(np.zeros((48, 64, 3), np.uint8)).save(rgb)
    Image.fromarray(np.full((40, 64), 1500, np.uint16)).save(tmp_path / "depth.png")
    (tmp_path / "k.json").write_text(json.dumps({"K": CAM.K.tolist(), "width": 64, "height": 48}))
    args = ["predict", "--rgb", str(rgb), "--depth", str(tmp_path / "depth.png"), "--intrinsics",
            str(tmp_path / "k.json"), "--out", str(tmp_path / "out")]  # fmt: skip
    assert main(args) == 2
    assert "rgb is 64x48 but depth is 64x40" in capsys.readouterr().err
    assert main(["predict", "--rgb", str(rgb), "--out", str(tmp_path / "out")]) == 2
    assert "--rgb needs --depth and --intrinsics" in capsys.readouterr().err
    Image.fromarray(np.full((48, 64), 1500, np.uint16)).save(tmp_path / "depth.png")
    (tmp_path / "bad.pt").write_bytes(b"\x80\x02garbage")
    assert main([*args, "--encoder", str(tmp_path / "bad.pt")]) == 2
    err = capsys.readouterr().err
    assert "bad.pt: not a readable encoder checkpoint" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_8bit_depth_is_refused_through_the_cli(tmp_path, capsys):
    """An 8-bit depth PNG (a visualisation, 256 levels) is one clear error naming the file; nothing is written."""
    from centerart.cli import main

    rgb = tmp_path / "rgb.png"
    Image.fromarray(np.zeros((48, 64, 3), np.uint8)).save(rgb)
    Image.fromarray(np.full((48, 64), 150, np.uint8)).save(tmp_path / "depth8.png")
    (tmp_path / "k.json").write_text(json.dumps({"K": CAM.K.tolist(), "width": 64, "height": 48}))
    with pytest.raises(CenterArtError, match=r"--depth .*depth8\.png: 8-bit depth image cannot hold metric depth"):
        read_depth(tmp_path / "depth8.png")
    args = ["predict", "--rgb", str(rgb), "--depth", str(tmp_path / "depth8.png"), "--intrinsics",
            str(tmp_path / "k.json"), "--out", str(tmp_path / "out")]  # fmt: skip
    assert main(args) == 2
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("centerart: error: --depth "), lines
    assert "depth8.png" in lines[0] and "16-bit PNG in millimetres" in lines[0] and ".npy in metres" in lines[0]
    assert not (tmp_path / "out").exists()
