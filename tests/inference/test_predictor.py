"""The predictor with the shipped weights: the bundled example end to end through the CLI, and a rendered
kitchen of training objects seen from two cameras (detections, poses, joints, grasps, frame consistency)."""

import json

import numpy as np
import pytest
from PIL import Image

from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
from centerart.cli import main
from centerart.geometry.matching import match_points
from centerart.geometry.transforms import rotation_angle_between
from centerart.inference.prediction_io import read_predictions
from centerart.inference.predictor import Predictor
from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes, list_views, load_view

# Tolerances from the shipped small encoder's measured errors (src/centerart/weights/README.md: on training-object
# views recall 0.81, median rotation error 24 deg; on held-out objects recall 0.59, 20 deg): they guard the pipeline
# and its frames, not the model's quality, which the benchmark reports.
MATCH_M = 0.10
TRANSLATION_M = 0.35  # a frame or camera-convention error would be metres off; the model is 0.2-0.4 m off here
ROTATION_DEG = 35.0
MIN_FOUND_FRACTION = 0.6  # found in the image (a peak on the object's box): measured 100% on training-object views


@pytest.fixture(scope="module")
def predictor():
    return Predictor.from_pretrained()


@pytest.fixture(scope="module")
def training_kitchen(tmp_path_factory, predictor):
    """One kitchen of the shipped decoder's training objects (seed 0, the first training object of each category
    by index: the split holds some out), two D415 views: the folder (objects/, scenes/)."""
    import shutil

    root = tmp_path_factory.mktemp("train_kitchen")
    generate_objects(GenerateObjectsConfig(out=root / "candidates", category="all", count=3, seed=0, workers=1))
    trained = set(predictor.decoder.codes)
    for category in sorted({f.name.rsplit("_", 1)[0] for f in (root / "candidates").iterdir() if f.is_dir()}):
        first = next(f for f in sorted((root / "candidates").glob(f"{category}_*")) if f.name in trained)
        shutil.copytree(first, root / "objects" / first.name)
    generate_scenes(
        GenerateScenesConfig(
            objects=root / "objects", out=root / "scenes", layout="kitchen", count=1, views_per_scene=2, seed=21,
            depth="stereo", intrinsics="d415", workers=1, save_ir=False,
        )
    )  # fmt: skip
    return root


@pytest.fixture(scope="module")
def training_object_views(training_kitchen):
    return [load_view(v) for v in list_views(training_kitchen / "scenes")]


@pytest.mark.slow
def test_predict_cli_on_the_bundled_example(tmp_path):
    out = tmp_path / "pred"
    assert main(["predict", "--out", str(out)]) == 0
    record = read_predictions(out)
    assert record["objects"], "no object found in the bundled example"
    for obj in record["objects"]:
        pose = np.asarray(obj["camera_T_object"])
        assert np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-5) and pose[2, 3] > 0
        assert obj["joint"]["type"] in ("revolute", "prismatic") and obj["joint"]["unit"] in ("rad", "m")
        assert (out / obj["mesh"]).is_file()
        scores = [g["score"] for g in obj["grasps"]]
        assert scores == sorted(scores, reverse=True)
    assert json.loads((out / "predictions.json").read_text()) == record  # plain JSON, round trip
    overlay = np.asarray(Image.open(out / "overlay.png"))
    assert overlay.shape[:2] == (480, 640) and (out / "scene.glb").stat().st_size > 10_000


def found_in_image(preds, obj):
    """The prediction whose peak lies in the object's box and whose centre is nearest to it, or None."""
    x0, y0, x1, y1 = obj["bbox_xyxy"]
    t = np.asarray(obj["camera_T_object"])[:3, 3]
    inside = [p for p in preds if x0 <= p.peak_uv[0] <= x1 and y0 <= p.peak_uv[1] <= y1]
    return min(inside, key=lambda p: np.linalg.norm(p.camera_T_object[:3, 3] - t)) if inside else None


@pytest.mark.slow
def test_training_objects_are_found_from_two_cameras(predictor, training_object_views):
    world_centres = []
    for view in training_object_views:
        preds = predictor.predict(view.rgb, view.depth_realistic, np.asarray(view.labels["K"]))
        visible = [o for o in view.labels["objects"] if o["visible_fraction"] >= 0.5]
        # Keyed by instance: a kitchen may hold the same object twice (this one shows two fridges, two dishwashers).
        found = {o["instance"]: (o, p) for o in visible if (p := found_in_image(preds, o)) is not None}
        assert len(found) >= max(1, np.ceil(MIN_FOUND_FRACTION * len(visible))), f"{len(found)} of {len(visible)}"
        t_err = [
            np.linalg.norm(p.camera_T_object[:3, 3] - np.asarray(o["camera_T_object"])[:3, 3])
            for o, p in found.values()
        ]
        r_err = [np.degrees(rotation_angle_between(p.camera_T_object[:3, :3], np.asarray(o["camera_T_object"])[:3, :3]))
                 for o, p in found.values()]  # fmt: skip
        assert np.median(t_err) < TRANSLATION_M and np.median(r_err) < ROTATION_DEG, (t_err, r_err)
        # Anchoring keeps only grasps the observation supports: some objects may keep none, each says what it did.
        assert any(len(p.grasp_poses) > 0 for _, p in found.values())
        assert all(p.refinement["anchoring"]["kept"] == len(p.grasp_poses) for _, p in found.values())
        world_T_camera = np.asarray(view.labels["world_T_camera"])
        world_centres.append({k: (world_T_camera @ p.camera_T_object)[:3, 3] for k, (_, p) in found.items()})
    # Frames: an object predicted from two cameras lands at the same world position (within twice the error bound).
    common = set(world_centres[0]) & set(world_centres[1])
    assert common
    gaps = [np.linalg.norm(world_centres[0][k] - world_centres[1][k]) for k in common]
    assert np.median(gaps) < 2 * TRANSLATION_M, gaps


@pytest.mark.slow
def test_another_camera_focal_length_and_resolution(predictor, tmp_path):
    """A 960x512 camera with f = 530 px (the paper's; training used 640x480, f = 615): poses still come out."""
    generate_objects(GenerateObjectsConfig(out=tmp_path / "objects", category="oven", count=1, seed=0, workers=1))
    generate_scenes(
        GenerateScenesConfig(
            objects=tmp_path / "objects", out=tmp_path / "scenes", layout="single", count=1, views_per_scene=1,
            seed=4, depth="analytic", intrinsics="paper", radius_m=(1.3, 1.8), workers=1, save_ir=False,
        )
    )  # fmt: skip
    view = load_view(list_views(tmp_path / "scenes")[0])
    assert view.rgb.shape[:2] == (512, 960)
    preds = predictor.predict(view.rgb, view.depth_realistic, np.asarray(view.labels["K"]))
    truth = np.asarray(view.labels["objects"][0]["camera_T_object"])
    pairs = match_points(np.array([p.camera_T_object[:3, 3] for p in preds]), truth[None, :3, 3], TRANSLATION_M)
    assert len(pairs) == 1, [p.camera_T_object[:3, 3] for p in preds]
    pred = preds[pairs[0][0]]
    assert np.degrees(rotation_angle_between(pred.camera_T_object[:3, :3], truth[:3, :3])) < ROTATION_DEG


def test_onnxruntime_and_torch_decoders_give_the_same_grasps(predictor, training_object_views):
    from scipy.spatial.distance import cdist

    from centerart.inference.grasp_anchoring import AnchoringConfig
    from centerart.inference.predictor import PredictorConfig
    from centerart.models.decoder_onnx import onnxruntime_available

    if not onnxruntime_available():
        pytest.skip("onnx / onnxruntime not installed")
    assert type(predictor.fast_decoder).__name__ == "OnnxDecoder"  # the default on a CPU
    v = training_object_views[0]
    K = np.asarray(v.labels["K"])
    # The decoder's own grasps (anchoring off): anchoring may keep none of them on an object, and this compares
    # the two runtimes, not the anchoring.
    off = AnchoringConfig(enabled=False)
    fast = Predictor(config=PredictorConfig(anchoring=off)).predict(v.rgb, v.depth_realistic, K)
    slow = Predictor(config=PredictorConfig(runtime="torch", anchoring=off)).predict(v.rgb, v.depth_realistic, K)
    assert len(fast) == len(slow) > 0
    for a, b in zip(fast, slow, strict=True):
        np.testing.assert_allclose(a.camera_T_object, b.camera_T_object)
        assert len(a.grasp_poses) > 0 and len(b.grasp_poses) > 0
        # Outputs agree to 5e-4; near-ties in the ranking may swap, so compare positions as sets.
        d = cdist(a.grasp_poses[:, :3, 3], b.grasp_poses[:, :3, 3]).min(axis=1)
        assert np.mean(d < 0.005) >= 0.8, d


def test_top_grasp_lies_on_the_moving_part_given_the_true_pose(predictor, training_kitchen):
    """With the true pose and joint state and the object's trained shape code swapped in (the encoder's pose error,
    0.2-0.4 m on these objects, is the encoder's to fix), the decoder's top grasp, through the predictor's
    extraction, filter and frames, would close its fingers on the true moving part: some of the part's surface
    lies between the open pads (a handle grasp's TCP can be 2 cm from the part's nearest surface; what matters is
    that the part is in the closing region). Measured: the top grasp on 8 of 9 object views, one of the top 3 on
    every one (the predictor's 48-cell lattice; at 128 cells the top grasp on every one). This checks the decoder's
    own ranking (``grasp_critic=False``): with the shipped grasp critic, the training fridge ajar at 0.70 gets
    three grasps 1-2 cm off the field's target (offset, which the critic learned to ignore on new objects) that
    miss its door, in both views (benchmarks/results/grasp_critic/README.md)."""
    import trimesh

    from centerart.errors import CenterArtError
    from centerart.evaluation.code_oracle import true_detection
    from centerart.grasps.gripper import FINGER_PAD_LENGTH, FINGER_WIDTH, FINGERTIP_BEYOND_TCP, MAX_OPENING
    from centerart.inference.grasp_anchoring import AnchoringConfig
    from centerart.inference.predictor import PredictorConfig
    from centerart.scenes.description import SceneDescription, load_scene_object

    top_closes = []
    # The decoder's proposal (anchoring off: it re-ranks by the observation, tests/inference/test_grasp_anchoring),
    # decoded with no encoder: the detection is given.
    own_ranking = Predictor.without_encoder(
        config=PredictorConfig(grasp_critic=False, anchoring=AnchoringConfig(enabled=False))
    )
    for view_dir in list_views(training_kitchen / "scenes"):
        v = load_view(view_dir)
        with pytest.raises(CenterArtError, match="no encoder"):
            own_ranking.predict(v.rgb, v.depth_realistic, np.asarray(v.labels["K"]))
        scene = SceneDescription.load(view_dir.parent.parent / "scene.json")
        for o in (o for o in v.labels["objects"] if o["visible_fraction"] >= 0.3):
            k, joint, pose = o["instance"] - 1, o["joint"], np.asarray(o["camera_T_object"])
            det = true_detection(o, v.instances, predictor.decoder.codes[o["object_id"]])
            pred = own_ranking.predict_detection(det, v.rgb, v.depth_realistic, np.asarray(v.labels["K"]))
            assert len(pred.grasp_poses) > 0, o["object_id"]
            moving = load_scene_object(scene.objects[k]).moving_mesh(joint["state"])
            surface, _ = trimesh.sample.sample_surface(moving, 200_000, seed=0)
            closes_on_part = []
            for grasp in pred.grasp_poses[:3]:
                tcp_in_object = np.linalg.inv(pose) @ grasp
                local = (surface - tcp_in_object[:3, 3]) @ tcp_in_object[:3, :3]  # TCP frame
                between_pads = (
                    (np.abs(local[:, 0]) <= FINGER_WIDTH / 2)
                    & (np.abs(local[:, 1]) <= MAX_OPENING / 2)
                    & (local[:, 2] >= -FINGER_PAD_LENGTH / 2)
                    & (local[:, 2] <= FINGERTIP_BEYOND_TCP)
                )
                closes_on_part.append(bool(between_pads.any()))
            assert any(closes_on_part), o["object_id"]
            top_closes.append(closes_on_part[0])
    assert len(top_closes) >= 6 and np.mean(top_closes) >= 0.8, top_closes
