"""The scene dataset on disk: files, manifest, resume, determinism of rendering, CLI, errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from centerart.cli import main
from centerart.errors import CenterArtError
from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes, list_views, load_view
from centerart.scenes.textures import TEXTURE_KINDS, make_texture


def test_dataset_files_and_manifest(kitchen_dataset):
    manifest = json.loads((kitchen_dataset / "manifest.json").read_text())
    assert manifest["stage"] == "scenes"
    assert manifest["counts"]["scenes"] == 2 and manifest["counts"]["images"] == 4
    for view_dir in list_views(kitchen_dataset):
        for name in (
            "rgb.png",
            "depth_true.png",
            "depth_realistic.png",
            "instances.png",
            "links.png",
            "heatmap.png",
            "ir_left.png",
            "ir_right.png",
        ):
            assert (view_dir / name).is_file(), name
        view = load_view(view_dir)
        assert view.rgb.shape == (240, 320, 3) and view.rgb.std() > 10
        assert view.labels["objects"], "every kitchen view should see an object"
        for lab in view.labels["objects"]:
            assert lab["shape_code"] is None
            ids = {int(i) for i in lab["links"]}
            seen = set(np.unique(view.links[view.instances == lab["instance"]]).tolist())
            assert seen <= ids  # link segmentation refines the instance mask
    scene_dir = list_views(kitchen_dataset)[0].parent.parent
    scene = json.loads((scene_dir / "scene.json").read_text())
    for box in scene["boxes"]:
        tex = box["material"]["texture"]
        assert tex is None or (scene_dir / tex).is_file()


def test_resume_skips_finished_scenes(kitchen_dataset, kitchen_config):
    rgb = list_views(kitchen_dataset)[0] / "rgb.png"
    before = rgb.stat().st_mtime_ns
    cfg = kitchen_config(kitchen_dataset, count=2)
    result = generate_scenes(cfg)
    assert all(r["resumed"] for r in result["scenes"])
    assert rgb.stat().st_mtime_ns == before


def test_rendering_is_deterministic(kitchen_dataset, kitchen_config, tmp_path):
    """Re-rendering scene 0 from scratch gives the same images and labels (same process, same seed)."""
    cfg = kitchen_config(tmp_path, count=1)
    generate_scenes(cfg)
    for name in ("rgb.png", "depth_true.png", "depth_realistic.png", "instances.png"):
        a = np.asarray(Image.open(kitchen_dataset / "scene_000000/views/00" / name))
        b = np.asarray(Image.open(tmp_path / "scene_000000/views/00" / name))
        np.testing.assert_array_equal(a, b, err_msg=name)
    la = json.loads((kitchen_dataset / "scene_000000/views/00/labels.json").read_text())
    lb = json.loads((tmp_path / "scene_000000/views/00/labels.json").read_text())
    assert la == lb


def test_missing_decoder_checkpoint_is_a_clear_error(scene_objects, tmp_path):
    cfg = GenerateScenesConfig(objects=scene_objects, out=tmp_path, count=1, decoder_checkpoint=tmp_path / "no.ckpt")
    with pytest.raises(CenterArtError, match="decoder-checkpoint"):
        generate_scenes(cfg)


def test_cli_show_and_errors(kitchen_dataset, tmp_path, capsys):
    out = tmp_path / "sheet.png"
    assert main(["scenes", "show", str(kitchen_dataset), "--out", str(out)]) == 0
    sheet = np.asarray(Image.open(out))
    assert sheet.shape[0] > 100 and sheet.shape[1] > 1000
    assert main(["scenes", "show", str(tmp_path / "nothing"), "--out", str(out)]) == 2
    assert "no such folder" in capsys.readouterr().err
    assert main(["scenes", "generate", "--objects", str(tmp_path / "none"), "--out", str(tmp_path / "o")]) == 2


@pytest.mark.parametrize("kind", TEXTURE_KINDS)
def test_textures_are_deterministic_and_tile(kind):
    a = make_texture(kind, (0.6, 0.5, 0.4), 3, size=128)
    np.testing.assert_array_equal(a, make_texture(kind, (0.6, 0.5, 0.4), 3, size=128))
    assert a.shape == (128, 128, 3) and a.dtype == np.uint8
    # Seamless: the jump across the wrap-around border is like the jump between the two middle columns (the same
    # phase of any tile grid), not a visible seam.
    middle = np.abs(a[:, 63].astype(int) - a[:, 64].astype(int)).mean()
    wrap = np.abs(a[:, 0].astype(int) - a[:, -1].astype(int)).mean()
    assert wrap <= 3 * middle + 3


def test_shape_codes_from_decoder_checkpoint(scene_objects, tmp_path, monkeypatch):
    """With --decoder-checkpoint, each label carries the object's code from load_shape_codes (here a stand-in)."""
    import sys
    import types

    ckpt = tmp_path / "decoder.ckpt"
    ckpt.write_bytes(b"stand-in")
    codes = {p.name: np.arange(4, dtype=float) + i for i, p in enumerate(sorted(scene_objects.iterdir())) if p.is_dir()}
    module = types.ModuleType("centerart.models.checkpoint")
    module.load_shape_codes = lambda path: codes if path == ckpt else {}
    monkeypatch.setitem(sys.modules, "centerart.models.checkpoint", module)
    out = tmp_path / "out"
    cfg = GenerateScenesConfig(
        objects=scene_objects,
        out=out,
        layout="single",
        count=1,
        views_per_scene=1,
        seed=2,
        depth="true",
        intrinsics="tiny",
        radius_m=(1.2, 2.0),
        workers=1,
        decoder_checkpoint=ckpt,
    )
    generate_scenes(cfg)
    view = load_view(list_views(out)[0])
    assert view.depth_realistic is None
    assert view.labels["objects"]
    for lab in view.labels["objects"]:
        assert lab["shape_code"] == codes[lab["object_id"]].tolist()
