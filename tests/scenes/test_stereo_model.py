"""The stereo sensor's error model at the encoder's size against full-size stereo shrunk by the loader, and the
cheap scenes (``--intrinsics d415-half --depth stereo-model``, masks and textures not written) in the encoder's
dataset."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from centerart.models.encoder.config import PRESETS
from centerart.models.encoder.inputs import Letterbox
from centerart.scenes.dataset import GenerateScenesConfig, asset_index, generate_scenes, sample_checked_scene
from centerart.scenes.depth_noise import stereo_depth, stereo_occlusion, to_ir_uint8
from centerart.scenes.renderer import SceneRenderer
from centerart.scenes.stereo_model import error_bands, modelled_stereo_depth
from centerart.training.encoder_data import EncoderViewDataset, checked_views
from centerart.training.encoder_targets import input_gaussians
from centerart.utils.seeding import item_rng

MIN_BAND_PIXELS = 3000  # bands with fewer pixels in either set are not compared (too few for a percentile)


def _views(objects: Path, scenes: int, seed: int) -> tuple[list, list]:
    """(reference, model) (true, realistic) pairs at 320x240 of the same kitchens: 640x480 stereo letterboxed as
    the encoder's loader does, and the error model on the 320x240 true depth."""
    entries = asset_index(objects)
    renderer = SceneRenderer()
    box = Letterbox.fit(640, 480, 320, 240)
    reference, model = [], []
    for i in range(scenes):
        for intrinsics in ("d415", "d415-half"):
            cfg = GenerateScenesConfig(objects=objects, out=Path("."), seed=seed, intrinsics=intrinsics)
            scene, _, _ = sample_checked_scene(cfg, i, entries)
            renderer.build(scene, None)
            st = scene.stereo
            for v in range(len(scene.cameras)):
                rng = item_rng(seed, "scene", i, "view", v, "sensor")
                im = renderer.render(v, ir=intrinsics == "d415")
                if intrinsics == "d415-half":
                    offsets = (st.left_offset_m, st.baseline_m, st.projector_offset_m)
                    real = modelled_stereo_depth(im.depth, renderer.K, rng, *offsets)
                    model.append((im.depth, real))
                    continue
                left, right = to_ir_uint8(im.ir_left, rng), to_ir_uint8(im.ir_right, rng)
                occluded = stereo_occlusion(im.ir_left_depth, im.ir_right_depth, renderer.K, st.baseline_m)
                real = stereo_depth(left, right, renderer.K, st.baseline_m, st.left_offset_m, occluded=occluded)
                reference.append((box.warp(im.rgb, im.depth)[1], box.warp(im.rgb, real)[1]))
        renderer.close()
    return reference, model


def test_stereo_model_matches_full_size_stereo_error_bands(scene_objects):
    """Per band of true depth with enough pixels: median and 90th-percentile errors within a factor 1.5 of the
    full-size stereo's once shrunk; holes on depth edges within a factor 2, elsewhere within 2 points; the blind
    band on the left in both."""
    ref_views, model_views = _views(scene_objects, scenes=2, seed=5)
    ref, model = error_bands(ref_views, 42), error_bands(model_views, 42)
    compared = 0
    for band, r in ref.items():
        if not isinstance(r, dict) or min(r["pixels"], model[band]["pixels"]) < MIN_BAND_PIXELS:
            continue
        compared += 1
        for stat in ("median_mm", "p90_mm"):
            assert 1 / 1.5 < model[band][stat] / r[stat] < 1.5, (band, stat, model[band], r)
    assert compared >= 2, (ref, model)
    assert 0.5 < model["edge_holes"] / ref["edge_holes"] < 2.0, (model["edge_holes"], ref["edge_holes"])
    assert abs(model["flat_holes"] - ref["flat_holes"]) < 0.02, (model["flat_holes"], ref["flat_holes"])
    assert ref["left_holes"] > 0.95 and model["left_holes"] > 0.95


@pytest.fixture(scope="module")
def cheap_and_full(tmp_path_factory, kitchen_config) -> tuple[Path, Path]:
    """One kitchen (2 views) written the cheap way at 320x240 and the usual way at 640x480, same seed."""
    out = tmp_path_factory.mktemp("cheap")
    base = kitchen_config(out / "cheap", count=1)
    settings = dict(objects=base.objects, layout="kitchen", count=1, views_per_scene=2, seed=base.seed, workers=1)
    generate_scenes(GenerateScenesConfig(out=out / "cheap", intrinsics="d415-half", depth="stereo-model",
                                         save_ir=False, save_masks=False, save_textures=False, **settings))  # fmt: skip
    generate_scenes(GenerateScenesConfig(out=out / "full", intrinsics="d415", depth="true", **settings))
    return out / "cheap", out / "full"


def test_cheap_scenes_write_what_the_encoder_reads(cheap_and_full):
    cheap, _ = cheap_and_full
    for view in checked_views([cheap]):
        assert sorted(p.name for p in view.iterdir()) == [
            "depth_realistic.png", "depth_true.png", "labels.json", "rgb.png"
        ]  # fmt: skip
    assert not any(cheap.glob("scene_*/textures"))


def test_cheap_scenes_load_with_targets_at_the_input_scale(cheap_and_full):
    """Through EncoderViewDataset at the small encoder's 320x240: no rescaling (scale 1), the input's K is the
    camera's and equals the letterboxed 640x480 camera's, and each object's heatmap Gaussian lands within 1 px of
    where the same view rendered at 640x480 and letterboxed puts it (objects under 50 pixels at 320x240, 200 at
    640x480, are not labelled)."""
    cheap, full = cheap_and_full
    cfg = PRESETS["small"]
    ds_cheap = EncoderViewDataset(checked_views([cheap]), cfg, codes={})
    ds_full = EncoderViewDataset(checked_views([full]), cfg, codes={}, depth="true")
    assert len(ds_cheap) == len(ds_full) == 2
    for i in range(len(ds_cheap)):
        a, b = ds_cheap[i], ds_full[i]
        assert a["rgb"].shape == (3, 240, 320) and a["depth"].shape == (1, 240, 320)
        assert a["meta"]["scale"] == 1.0 and a["meta"]["depth_kind"] == "realistic"
        assert (a["depth"] > 0).float().mean() > 0.6  # realistic depth, mostly measured
        assert np.allclose(a["K"].numpy(), a["meta"]["labels"]["K"], atol=1e-4)
        assert np.allclose(a["K"].numpy(), b["K"].numpy(), atol=1e-3)
        la, lb = a["meta"]["labels"], b["meta"]["labels"]
        ga = {la["objects"][k]["name"]: mean for k, mean, _ in input_gaussians(la, Letterbox.fit(320, 240, 320, 240))}
        gb = {lb["objects"][k]["name"]: mean for k, mean, _ in input_gaussians(lb, Letterbox.fit(640, 480, 320, 240))}
        assert ga, la
        for name in ga:
            assert np.abs(ga[name] - gb[name]).max() <= 1.0, (name, ga[name], gb[name])
        small = {o["name"] for o in lb["objects"] if o["visible_pixels"] < 200}
        assert set(gb) - set(ga) <= small
