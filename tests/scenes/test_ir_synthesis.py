"""IR images shaded from geometry: projector shadows where geometry puts them, inverse-square falloff, ambient
only without the projector, and stereo depth from them as good as from SAPIEN's lit render of the pair."""

import numpy as np
import pytest

from centerart.scenes.ir_synthesis import DISPLAY_GAMMA, IrLighting, projector_visibility, shade_ir

K = np.array([[615.0, 0.0, 319.5], [0.0, 615.0, 239.5], [0.0, 0.0, 1.0]])


def _wall_with_block(near=1.0, far=2.0) -> np.ndarray:
    depth = np.full((480, 640), far, np.float32)
    depth[:, 200:300] = near
    return depth


def _lighting(intensity=60.0, ambient=0.3, pattern=None) -> IrLighting:
    pattern = np.ones((960, 1280), np.float32) if pattern is None else pattern
    return IrLighting(pattern, 0.03, 90.0, intensity, ambient, [], [])


@pytest.mark.parametrize("shift", [-0.015, 0.04])
def test_projector_shadow_falls_beside_the_block_on_the_projector_s_far_side(shift):
    depth = _wall_with_block()
    visible = projector_visibility(depth, K[0, 0], shift)
    shaded_cols = np.nonzero(~visible[240])[0]
    width = K[0, 0] * abs(shift) * (1 / 1.0 - 1 / 2.0)  # px of wall behind the block (+- 0.5 px margin, 1 px rounding)
    # projector right of the camera (shift < 0): the shadow lies left of the block; left of it: right of the block
    expected = np.arange(200 - round(width), 200) if shift < 0 else np.arange(300, 300 + round(width))
    assert abs(len(shaded_cols) - width) <= 1.5 and set(shaded_cols) <= set(range(expected[0] - 1, expected[-1] + 2))
    assert (visible[:, 200:300]).all()  # the block itself is lit


def test_background_pixels_cast_no_shadow_and_stay_black():
    depth = _wall_with_block()
    depth[:, 400:] = 0.0
    img = shade_ir(np.full(depth.shape, 0.5, np.float32), depth, K, 0.015, _lighting())
    assert (img[:, 400:] == 0).all() and (img[:, :400] > 0).all()
    assert projector_visibility(depth, K[0, 0], -0.015)[:, 300:400].all()


def test_without_the_projector_only_the_ambient_light_remains():
    depth = np.full((480, 640), 2.0, np.float32)
    img = shade_ir(np.full(depth.shape, 0.5, np.float32), depth, K, 0.015, _lighting(intensity=0.0, ambient=0.4))
    np.testing.assert_allclose(img[10:-10, 10:-10], (0.5 * 0.4) ** (1 / DISPLAY_GAMMA), rtol=1e-5)


def test_projector_light_falls_off_with_the_square_of_the_distance():
    linear = []
    for z in (1.0, 2.0):
        depth = np.full((480, 640), z, np.float32)
        img = shade_ir(np.full(depth.shape, 0.2, np.float32), depth, K, 0.015, _lighting(intensity=1.0, ambient=0))
        linear.append(float(np.median(img[200:280, 280:360].astype(np.float64) ** DISPLAY_GAMMA)))
    assert linear[0] / linear[1] == pytest.approx(4.0, rel=0.05)


@pytest.mark.slow
def test_fast_ir_gives_the_lit_render_s_stereo_depth(scene_objects, tmp_path):
    """One kitchen view rendered both ways: the same valid share and median error of the stereo depth."""
    from centerart.scenes.dataset import GenerateScenesConfig, asset_index, sample_checked_scene, write_textures
    from centerart.scenes.depth_noise import stereo_depth, stereo_occlusion, to_ir_uint8
    from centerart.scenes.renderer import SceneRenderer

    cfg = GenerateScenesConfig(objects=scene_objects, out=tmp_path, layout="kitchen", views_per_scene=1, seed=3)
    scene, _, _ = sample_checked_scene(cfg, 0, asset_index(scene_objects))
    write_textures(scene, tmp_path)
    stats = []
    for shading in ("full", "fast"):
        renderer = SceneRenderer(ir_shading=shading)
        renderer.build(scene, tmp_path)
        im = renderer.render(0, ir=True)
        st, rng = scene.stereo, np.random.default_rng(0)
        occluded = stereo_occlusion(im.ir_left_depth, im.ir_right_depth, renderer.K, st.baseline_m)
        left, right = to_ir_uint8(im.ir_left, rng), to_ir_uint8(im.ir_right, rng)
        depth = stereo_depth(left, right, renderer.K, st.baseline_m, st.left_offset_m, occluded=occluded)
        true, ok = im.depth[:, 80:], depth[:, 80:] > 0
        stats.append((ok.mean(), np.median(np.abs(depth[:, 80:][ok] - true[ok]) / true[ok])))
    (valid_full, err_full), (valid_fast, err_fast) = stats
    assert valid_fast > 0.6 and abs(valid_fast - valid_full) < 0.05, stats
    assert err_fast < 0.03 and err_fast < 1.5 * err_full + 1e-3, stats
