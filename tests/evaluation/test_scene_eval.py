"""Closed-loop scene evaluation (issue 13) on the tiny single-object scenes of the shared fixtures.

The fixture objects (seed 3) are not the shipped checkpoints' training objects (seed 0), which the held-out
check verifies by content fingerprint."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from centerart.cli import main
from centerart.evaluation.scene_eval import EvalScenesConfig, evaluate_scenes, job_config, scene_context
from centerart.evaluation.scene_summary import group_summary, stage_losses
from centerart.evaluation.trials import execute_grasp, oracle_trial
from centerart.models.checkpoint import default_checkpoint
from centerart.models.checkpoint_files import file_sha256
from centerart.models.grasp_critic import critic_path
from centerart.scenes.description import SceneDescription


@pytest.fixture(scope="module")
def ctx(single_dataset, tmp_path_factory):
    cfg = job_config(EvalScenesConfig(scenes=(single_dataset,), out=tmp_path_factory.mktemp("eval")))
    scene, context = scene_context(single_dataset / "scene_000000", tmp_path_factory.mktemp("labels"), cfg)
    yield scene, context
    context.phys.close()


def test_physics_rebuild_holds_the_room_and_the_object_at_its_state(ctx):
    scene, c = ctx
    assert len(c.phys.boxes) == len(scene.boxes) > 0
    assert abs(c.phys.targets[0].joint_state() - scene.objects[0].joint_state) < 1e-6
    assert len(c.labels_world[0]) > 0, "the label generator found no grasp at the test state"


def test_oracle_label_moves_the_joint(ctx):
    _, c = ctx
    trial = oracle_trial(c.phys, 0, c.labels_world[0])
    assert trial["success"], trial
    assert trial["displacement"] > 0


def test_a_grasp_in_free_air_fails(ctx):
    _, c = ctx
    air = np.asarray(c.labels_world[0][0]).copy()
    air[:3, 3] += [0.0, 0.0, 3.0]  # 3 m above the label: nothing between the fingers
    trial = execute_grasp(c.phys, 0, air)
    assert not trial["success"]
    assert trial["abort"] == "no_contact"


def _row(**kw) -> dict:
    row = {"scene": "s", "view": 0, "instance": 0, "category": "oven", "matched": True, "sr": False,
           "sr_abort": "", "sr_axis": False, "top5_any": False, "rsr": False, "nearest_label_m": None}  # fmt: skip
    return {**row, **kw}


def test_a_missed_object_counts_as_a_failure():
    rows = [_row(sr=True, sr_axis=True, rsr=True, nearest_label_m=0.01), _row(matched=False, sr_abort="missed")]
    g = group_summary(rows)
    assert g["objects"] == 2
    assert g["sr"] == 0.5 and g["sr_axis"] == 0.5 and g["rsr"] == 0.5
    assert g["aborts"] == {"missed": 1, "success": 1}
    assert g["nearest_label"]["count"] == 2 and g["nearest_label"]["finite"] == 1


def test_stage_losses_attribute_each_failure_once():
    rows = [
        _row(matched=False, instance=0),  # detection
        _row(instance=1, sr_gt_pose=True),  # pose and joint
        _row(instance=2, sr_gt_pose=False),  # shape / grasp decoding (the oracle succeeds)
        _row(instance=3, sr_gt_pose=False),  # execution (the oracle fails too)
        _row(instance=4, sr=True, sr_gt_pose=True),
    ]
    oracle = [_row(instance=i, sr=i != 3) for i in range(5)]
    s = stage_losses(rows, oracle)
    assert s["failures_by_stage"] == dict.fromkeys(
        ("detection", "pose_and_joint", "shape_and_grasp_decoding", "execution"), 1
    )
    assert s["sr"] == 0.2 and s["sr_with_true_pose_and_joint"] == 0.4


def test_a_fitted_shape_code_splits_the_encoders_code_from_the_decoders_grasps():
    rows = [
        _row(instance=0, sr_gt_pose=True, sr_gt_pose_code=None),  # pose and joint (no code swap needed)
        _row(instance=1, sr_gt_pose=False, sr_gt_pose_code=True),  # the encoder's shape code
        _row(instance=2, sr_gt_pose=False, sr_gt_pose_code=False),  # the decoder's grasps
        _row(instance=3, sr=True, sr_gt_pose=False, sr_gt_pose_code=None),
        _row(instance=4, matched=False),  # a miss holds no swap
    ]
    s = stage_losses(rows, [_row(instance=i, sr=True) for i in range(5)])
    assert s["failures_by_stage"] == {"detection": 1, "pose_and_joint": 1, "shape_code": 1,
                                      "shape_and_grasp_decoding": 1, "execution": 0}  # fmt: skip
    assert s["sr"] == 0.2 and s["sr_with_true_pose_and_joint"] == 0.4
    assert s["sr_with_true_pose_joint_and_code"] == 0.6


def test_the_oracle_code_fits_the_objects_surface_better_than_the_mean_code(ctx):
    """The code fitted to the object's true surface (the shape-code stage) must describe that surface: its SDF error
    on fresh samples of it is below the zero code's (the mean of the code prior), and the fit is deterministic."""
    import torch

    from centerart.evaluation.code_oracle import oracle_code
    from centerart.models.checkpoint import load_decoder
    from centerart.sdf.sampling import SamplingConfig, sample_points, signed_distance
    from centerart.sdf.surface import object_surface

    _, c = ctx
    loaded, obj, q = load_decoder(default_checkpoint()), c.phys.objects[0], c.phys.states[0]
    code = oracle_code(loaded, obj, q, seed=0)
    np.testing.assert_array_equal(code, oracle_code(loaded, obj, q, seed=0))
    rng = np.random.default_rng(123)  # other samples than the fit's
    surface = object_surface(obj, q)
    signed = signed_distance(surface, sample_points(surface.mesh, 4000, SamplingConfig(), rng), SamplingConfig(), rng)
    near = np.abs(signed.sdf) < 0.02

    def error_mm(z: np.ndarray) -> float:
        with torch.no_grad():
            pred = loaded.decoder.sdf_only(
                torch.as_tensor(z, dtype=torch.float32).expand(int(near.sum()), -1),
                torch.full((int(near.sum()),), float(obj.normalize(q))),
                torch.as_tensor(signed.points[near]),
            ).numpy()
        return float(np.mean(np.abs(pred - signed.sdf[near]))) * 1000

    assert error_mm(code) < 0.8 * error_mm(np.zeros_like(code)), (error_mm(code), error_mm(np.zeros_like(code)))


def test_a_test_set_with_a_training_object_is_refused(single_dataset, tmp_path, capsys):
    import torch

    from centerart.assets.fingerprint import object_fingerprint
    from centerart.models.checkpoint import default_checkpoint
    from centerart.models.checkpoint_files import write_blob

    spec = SceneDescription.load(single_dataset / "scene_000000" / "scene.json").objects[0]
    blob = torch.load(default_checkpoint(), weights_only=True)
    blob["training_objects"] = {"renamed_in_training": object_fingerprint(spec.path)}
    fake = write_blob(tmp_path / "decoder_trained_on_it.pt", blob)
    out = tmp_path / "out"
    code = main(["eval", "scenes", "--scenes", str(single_dataset), "--out", str(out), "--decoder", str(fake)])
    err = capsys.readouterr().err
    assert code == 2
    assert "shares objects with the models' training objects" in err and "renamed_in_training" in err
    assert not (tmp_path / "out" / "report.json").exists()


def _strip_latency(obj):
    if isinstance(obj, dict):
        return {k: _strip_latency(v) for k, v in obj.items() if "latency" not in k and k != "timing_s"}
    if isinstance(obj, list):
        return [_strip_latency(v) for v in obj]
    return obj


@pytest.mark.slow
def test_resumed_run_equals_uninterrupted_and_the_report_is_complete(single_dataset, tmp_path):
    full = tmp_path / "full"
    args = ["eval", "scenes", "--scenes", str(single_dataset), "--out", str(full), "--max-scenes", "2"]
    assert main(args) == 0
    report = json.loads((full / "report.json").read_text())
    md = (full / "report.md").read_text()
    for heading in ("Table I", "Variants", "Where the failures come from", "Detection, pose, joint, shape",
                    "Per category", "Outcomes", "Thresholds", "paper (theirs)"):  # fmt: skip
        assert heading in md, heading
    assert (full / "plots" / "sr_by_category.png").is_file() and (full / "plots" / "nearest_label.png").is_file()
    assert report["held_out"] and report["scenes_evaluated"] == 2 and not report["scenes_missing"]
    critic, beside = report["checkpoints"]["grasp_critic"], critic_path(default_checkpoint())
    if beside.is_file():  # the shipped decoder's critic ranked the grasps: recorded
        assert critic["sha256"] == file_sha256(beside) and critic["sha256"][:12] in md
    else:  # the report says the grasps were ranked without one
        assert critic is None and "no grasp critic" in md
    assert report["checkpoints"]["anchor_critic"] is None  # none is shipped: the cue ranking ranked them
    methods = {k.split("|")[1] for k in report["groups"]}
    assert methods == {"centerart", "baseline", "oracle"}
    assert report["groups"][next(k for k in report["groups"] if "|oracle|" in k)]["sr"] >= 0.5
    # both associations in every row and every report (the image association's keys, EVALUATION.md)
    rows = [r for f in (full / "records").glob("*/*.json") for r in json.loads(f.read_text())["rows"]]
    assert all(isinstance(r["sr_image"], bool) and "image_matched" in r for r in rows)
    assert all(r["sr_image"] == r["sr"] for r in rows if r["method"] != "centerart")
    assert all(r["sr_image"] == r["sr"] for r in rows if r.get("image_same_as_3d"))
    assert "SR img true" in md and "SR 3-D true" in md and "## Published protocol, for comparison only" in md
    assert all(g["sr_image"] is not None for g in report["groups"].values())
    # the stage analysis's code oracle: measured exactly where the true pose alone still fails
    learned = [r for r in rows if r["method"] == "centerart" and r["matched"]]
    assert all((r["sr_gt_pose_code"] is None) == bool(r["sr"] or r["sr_gt_pose"]) for r in learned)
    assert "shape code" in md and all("shape_code" in s["failures_by_stage"] for s in report["stages"].values())

    # "Killed" after one scene, then rerun: the second run evaluates only the missing scene.
    part = tmp_path / "part"
    cfg = EvalScenesConfig(scenes=(single_dataset,), out=part, max_scenes=1, progress=False)
    first = evaluate_scenes(cfg)
    assert first["scenes_evaluated"] == 1
    cfg.max_scenes = 2
    resumed = evaluate_scenes(cfg)
    assert resumed["run"]["scenes_this_run"] == 1
    for name in ("scene_000000", "scene_000001"):
        a = json.loads(next((full / "records").glob(f"*/{name}.json")).read_text())
        b = json.loads(next((part / "records").glob(f"*/{name}.json")).read_text())
        assert _strip_latency(a["rows"]) == _strip_latency(b["rows"])
    assert _strip_latency(resumed["groups"]) == _strip_latency(report["groups"])
    assert resumed["stages"] == report["stages"]


def test_eval_scenes_help_lists_the_options():
    with pytest.raises(SystemExit) as exit_info:
        main(["eval", "scenes", "--help"])
    assert exit_info.value.code == 0


def test_missing_scenes_folder_is_a_clear_error(tmp_path, capsys):
    assert main(["eval", "scenes", "--scenes", str(tmp_path / "nope"), "--out", str(tmp_path / "o")]) == 2
    assert "no such scenes folder" in capsys.readouterr().err


def test_record_paths_are_per_test_set(tmp_path):
    from centerart.evaluation.scene_eval import set_key

    assert set_key(tmp_path / "a" / "single") != set_key(tmp_path / "b" / "single")
    assert set_key(tmp_path / "a" / "single").startswith("single-")
    assert Path(tmp_path).exists()


def test_rerun_with_other_settings_into_the_same_folder_is_refused(tmp_path):
    from centerart.errors import CenterArtError
    from centerart.evaluation.scene_eval import check_same_settings

    jc = job_config(EvalScenesConfig(scenes=(), out=tmp_path))
    check_same_settings(tmp_path, jc)
    check_same_settings(tmp_path, {**jc, "workers": 7})  # how it runs may change
    with pytest.raises(CenterArtError, match="other settings \\(refine\\)"):
        check_same_settings(tmp_path, {**jc, "refine": ["none", "icp"]})


def test_labels_at_the_test_state_are_the_same_generated_or_cached(single_dataset, tmp_path):
    """A resumed scene reads its labels from the cache: they must be exactly the ones a fresh run uses."""
    from centerart.evaluation.scene_eval import state_labels
    from centerart.scenes.description import load_scene_object

    spec = SceneDescription.load(single_dataset / "scene_000000" / "scene.json").objects[0]
    cfg = job_config(EvalScenesConfig(scenes=(single_dataset,), out=tmp_path, labels_per_state=10))
    cache = tmp_path / "labels" / "obj0.npz"
    fresh = state_labels(load_scene_object(spec), spec.joint_state, cache, cfg, "scene/obj0")
    cached = state_labels(load_scene_object(spec), spec.joint_state, cache, cfg, "scene/obj0")
    assert len(fresh) > 0
    np.testing.assert_array_equal(fresh, cached)
