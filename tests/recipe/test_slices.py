"""``centerart slices`` (issue 29): a tiny run of two slices through the CLI, one of them stopped and resumed; its
ledger replays to the same weights; a damaged ledger, a state another slice wrote, or a state of another layout is
one error line naming the file, before any data is made."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import torch

from centerart.cli import main
from centerart.errors import CenterArtError
from centerart.models.checkpoint_files import file_sha256
from centerart.models.encoder.checkpoint import load_encoder
from centerart.models.encoder.config import PRESETS
from centerart.recipe.ledger import read_ledger
from centerart.recipe.slices import learning_curve, refuse_changed_settings
from centerart.training.slice_training import load_state, new_state, save_state
from centerart.viz.learning_curve import draw_learning_curve

COMMON = ["--threads", "1", "--workers", "1", "--no-progress"]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory) -> tuple[Path, Path]:
    """Two tiny slices; the first stopped after one of its three steps and resumed by a second call."""
    root = tmp_path_factory.mktemp("slices")
    run, work = root / "run", root / "work"
    args = ["slices", "next", "--run", str(run), "--work", str(work), "--preset", "tiny", *COMMON]
    assert main([*args, "--stop-after", "1"]) == 0
    assert not (run / "ledger.jsonl").exists() and (work / "slice_001" / "progress.pt").is_file()
    assert main([*args, "--steps", "5"]) == 2  # a started slice keeps its settings
    assert main(args) == 0
    assert main([*args, "--steps", "2", "--depth", "stereo-model"]) == 0
    return run, work


@pytest.mark.slow  # ~70 s on 2 cores: 120 objects, 8 tiny scenes, two slices and their replay
def test_two_slices_write_a_ledger_that_replays_to_the_same_weights(tiny_run, tmp_path, capsys):
    run, _ = tiny_run
    lines = read_ledger(run)
    assert [x["slice"] for x in lines] == [1, 2] and [x["steps"] for x in lines] == [3, 2]
    assert [x["first_step"] for x in lines] == [0, 3] and lines[1]["images_seen"] == 5 * 2
    assert lines[0]["seeds"] != lines[1]["seeds"] and min(lines[0]["seeds"].values()) >= 100_000
    assert lines[0]["images"] == 3 and lines[1]["distinct_images"] == 6
    assert lines[0]["data"]["depth"] == "analytic" and lines[1]["data"]["depth"] == "stereo-model"
    assert lines[0]["code_version"] and lines[1]["finished_with"]
    # Slice 1 took two calls (stopped, resumed): its line counts both calls' wall time, not the last one's.
    assert [x["calls"] for x in lines] == [2, 1] and {"data", "train", "validation"} <= set(lines[0]["wall_s"])
    # Slice 1 also measured where the run started (the first point of its learning curve); later slices do not.
    assert lines[0]["start_validation"]["views"] == 2 and "start_validation" not in lines[1]
    assert lines[1]["state_sha256"] == file_sha256(run / "state.pt")
    assert lines[1]["encoder_sha256"] == file_sha256(run / "encoder.pt")
    assert {"recall", "precision", "views"} <= set(lines[1]["validation"])
    assert load_state(run / "state.pt").step == 5
    # The exported encoder loads like any other (with the decoder it was trained against) and names its objects.
    loaded = load_encoder(run / "encoder.pt")
    assert loaded.encoder.config == PRESETS["tiny"].__class__(**{**PRESETS["tiny"].to_dict(), "code_dim": 32})
    assert loaded.meta["metrics"]["val/views"] == 2
    assert len(torch.load(run / "encoder.pt", weights_only=True)["training_objects"]) == 102  # the shipped decoder's

    assert main(["slices", "status", "--run", str(run), "--plot", str(tmp_path / "curve.png")]) == 0
    table = capsys.readouterr().out
    assert "| 2 | 2 | 5 | 3 | 6 |" in table and f"learning curve: {tmp_path / 'curve.png'}" in table
    assert "stopping rule (3 consecutive slices without a new best validation figure)" in table
    assert (tmp_path / "curve.png").read_bytes()[:8] == PNG_SIGNATURE
    # The replay trains each slice in one go: equal weights also say the stopped-and-resumed slice 1 lost nothing.
    assert main(["slices", "replay", "--run", str(run), "--work", str(tmp_path / "replay"), *COMMON]) == 0
    assert "largest weight difference 0" in capsys.readouterr().out


def _copy(tiny_run, tmp_path: Path) -> Path:
    return Path(shutil.copytree(tiny_run[0], tmp_path / "run"))


def _one_error_line(capsys, argv: list[str], names: str) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("centerart: error:") and "\n" not in err and "Traceback" not in err, err
    assert names in err, err
    return err


@pytest.mark.slow  # shares the tiny run above
@pytest.mark.parametrize("damage", ["not-json", "missing-field", "wrong-slice", "state-of-another-slice",
                                    "state-missing", "state-of-another-layout"])  # fmt: skip
def test_a_damaged_run_folder_is_one_error_line_and_no_data(tiny_run, tmp_path, capsys, damage):
    run = _copy(tiny_run, tmp_path)
    ledger = run / "ledger.jsonl"
    lines = ledger.read_text().splitlines()
    names = "ledger.jsonl"
    if damage == "not-json":
        ledger.write_text(lines[0] + "\n{oops\n")
    elif damage == "missing-field":
        ledger.write_text(json.dumps({k: v for k, v in json.loads(lines[0]).items() if k != "steps"}) + "\n")
    elif damage == "wrong-slice":
        ledger.write_text(lines[1] + "\n")
    else:
        names = "state.pt"
        if damage == "state-of-another-slice":
            ledger.write_text(lines[0] + "\n")
        elif damage == "state-missing":
            (run / "state.pt").unlink()
        else:  # a state file of the small layout whose hash the ledger is made to name
            save_state(run / "state.pt", new_state(PRESETS["small"], seed=0))
            last = json.loads(lines[1]) | {"state_sha256": file_sha256(run / "state.pt")}
            ledger.write_text(lines[0] + "\n" + json.dumps(last) + "\n")
    work = tmp_path / "work"
    _one_error_line(capsys, ["slices", "next", "--run", str(run), "--work", str(work), *COMMON], names)
    assert not work.exists()


def test_a_plan_saved_before_new_fields_trains_as_it_did_then():
    """Runs keep their loss and read-out when defaults change: plans without the recorded encoder config or the
    newer loss fields get the values they were made with; new plans record today's."""
    from centerart.models.encoder.losses import EncoderLossConfig
    from centerart.recipe.slice_plan import SlicePlan
    from centerart.recipe.slices import encoder_config

    codes = {"a": [0.0] * 32}
    old = encoder_config(SlicePlan(preset="small"), codes)
    assert old.read_radius_cells == 1 and old.code_dim == 32
    new = encoder_config(SlicePlan(preset="small", encoder=PRESETS["small"].to_dict()), codes)
    assert new.read_radius_cells is None
    legacy = EncoderLossConfig.from_dict({"heatmap": 100.0})
    assert legacy.pose_decoupled is False and legacy.keypoint_arm_m == pytest.approx(0.1)
    assert EncoderLossConfig.from_dict(EncoderLossConfig().to_dict()) == EncoderLossConfig()


def test_a_run_started_from_a_sliced_runs_encoder_takes_another_seed_block(tmp_path, capsys):
    """The shipped encoder came out of slices of seed block 2: a run from it must render other scenes."""
    from centerart.models.encoder.checkpoint import default_encoder
    from centerart.recipe.slice_plan import slice_seeds
    from centerart.recipe.slices import create_plan

    args = ["slices", "next", "--run", str(tmp_path / "run"), "--work", str(tmp_path / "work"),
            "--init", str(default_encoder()), "--seed-block", "2", *COMMON]  # fmt: skip
    _one_error_line(capsys, args, "--seed-block 3")
    # a block below it too: blocks grow along a lineage, and block 1 is the one its start was trained on
    _one_error_line(capsys, [*args[: -len(COMMON) - 1], "1", *COMMON], "--seed-block 3")
    assert not (tmp_path / "work").exists() and not (tmp_path / "run").exists()
    plan = create_plan(tmp_path / "run2", "small", default_encoder(), seed_block=3)
    assert plan.seed_block == 3 and (tmp_path / "run2" / "init.pt").is_file()
    assert plan.objects_count == 24  # the shipped decoder's objects per category
    assert set(slice_seeds(1, 3).values()).isdisjoint(
        slice_seeds(k, 2)[s] for k in range(1, 999) for s in ("kitchen", "single")
    )


def test_a_run_against_another_decoder_keeps_a_copy_and_warm_starts_from_an_encoder_of_the_old_one(tmp_path, capsys):
    """--decoder: the plan pins a copy in the run folder and takes its objects per category; an --init trained
    against other codes loads as a warm start only then (without --decoder it is refused, as before)."""
    from centerart.models.checkpoint import default_checkpoint, load_shape_codes
    from centerart.models.encoder.checkpoint import default_encoder
    from centerart.recipe.slices import create_plan, encoder_config, initial_state

    blob = torch.load(default_checkpoint(), map_location="cpu", weights_only=True)
    other = tmp_path / "other_decoder.pt"
    torch.save({**blob, "metrics": {"note": 1.0}}, other)  # the same objects and codes, another file
    plan = create_plan(tmp_path / "run", "small", default_encoder(), seed_block=3, decoder=other)
    assert plan.objects_count == 24 and plan.init_other_decoder
    assert file_sha256(tmp_path / "run" / "decoder.pt") == plan.decoder_sha256 == file_sha256(other)
    config = encoder_config(plan, load_shape_codes(other))
    assert initial_state(plan, config).step == 0
    plan.init_other_decoder = False  # what a run without --decoder checks: the init's decoder must be the run's
    with pytest.raises(CenterArtError, match="trained against the shape codes"):
        initial_state(plan, config)
    same = create_plan(tmp_path / "run2", "small", default_encoder(), seed_block=3, decoder=default_checkpoint())
    assert not same.init_other_decoder
    _one_error_line(capsys, ["slices", "next", "--run", str(tmp_path / "run3"), "--work", str(tmp_path / "w"),
                             "--decoder", str(default_encoder()), *COMMON], "not a decoder checkpoint")  # fmt: skip
    assert not (tmp_path / "run3").exists()  # refused before anything was copied


def _write_ledger(run: Path, lines: list[dict], plan: dict | None = None) -> None:
    run.mkdir(exist_ok=True)
    (run / "ledger.jsonl").write_text("".join(json.dumps(x) + "\n" for x in lines))
    if plan is not None:
        (run / "run.json").write_text(json.dumps(plan))


def test_the_learning_curve_starts_where_the_run_started_and_has_a_point_per_slice(tmp_path):
    base = {"seeds": {}, "data": {}, "batch_size": 8, "lr_scale": 1.0, "images": 10, "state_sha256": "x",
            "code_version": "v"}  # fmt: skip
    first = {**base, "slice": 1, "steps": 4, "first_step": 0, "distinct_images": 10,
             "validation": {"recall": 0.5, "translation_cm_median": 6.0},
             "start_validation": {"recall": 0.25, "translation_cm_median": 9.0}}  # fmt: skip
    second = {**base, "slice": 2, "steps": 6, "first_step": 4, "distinct_images": 20, "validation": {"recall": 0.75}}
    _write_ledger(tmp_path / "run", [first, second])
    curve = learning_curve(tmp_path / "run")
    assert curve["kind"] == "encoder" and curve["columns"] == ["recall", "translation_cm_median"]
    assert curve["units"] == {"recall": "rate", "translation_cm_median": "cm"}
    points = curve["points"]
    assert [(p["slice"], p["total_steps"], p["distinct_images"]) for p in points] == [
        (0, 0, 0),
        (1, 4, 10),
        (2, 10, 20),
    ]
    assert [p["recall"] for p in points] == [0.25, 0.5, 0.75] and points[2]["translation_cm_median"] is None
    assert draw_learning_curve(curve, tmp_path / "curve.png").read_bytes()[:8] == PNG_SIGNATURE


def test_a_decoder_runs_learning_curve_is_in_mm_and_an_empty_ledger_is_one_error(tmp_path):
    line = {"slice": 1, "steps": 3, "first_step": 0, "batch_size": 2, "lr_scale": 1.0, "objects_sha256": "o",
            "state_sha256": "s", "code_version": "v", "validation": {"val_object/sdf_near": 0.004},
            "start_validation": {"val_object/sdf_near": 0.005}}  # fmt: skip
    _write_ledger(tmp_path / "dec", [line], {"kind": "decoder"})
    curve = learning_curve(tmp_path / "dec")
    assert curve["kind"] == "decoder" and curve["units"] == {"val_object/sdf_near": "mm"}
    assert [p["val_object/sdf_near"] for p in curve["points"]] == pytest.approx([5.0, 4.0])
    assert [p["distinct_images"] for p in curve["points"]] == [None, None]
    _write_ledger(tmp_path / "empty", [])
    with pytest.raises(CenterArtError, match="no slice in its ledger yet"):
        learning_curve(tmp_path / "empty")


def test_a_run_with_the_decoded_shape_term_keeps_its_weight_and_builds_the_frozen_decoder(tmp_path):
    """--shape-sdf: the plan's loss keeps the weight (old plans, without it, train as before: weight 0), and the
    slice's loop gets the decoder's query points only then."""
    from centerart.models.checkpoint import default_checkpoint, load_shape_codes
    from centerart.models.encoder.losses import EncoderLossConfig
    from centerart.recipe.slices import create_plan, decoded_shape_of, load_plan

    plan = create_plan(tmp_path / "run", "small", None, shape_sdf=30.0)
    assert load_plan(tmp_path / "run").loss["shape_sdf"] == 30.0
    codes = dict(list(load_shape_codes(default_checkpoint()).items())[:3])
    decoded = decoded_shape_of(plan, EncoderLossConfig.from_dict(plan.loss), codes)
    assert decoded is not None and decoded.points.shape[:2] == (3, 512)
    old = {k: v for k, v in plan.loss.items() if k != "shape_sdf"}
    assert EncoderLossConfig.from_dict(old).shape_sdf == 0.0
    assert decoded_shape_of(plan, EncoderLossConfig.from_dict(old), codes) is None


def test_a_resumed_slice_names_each_changed_setting_with_the_value_it_started_with():
    """Left-out flags (None) pass; a flag with a default that differs is named with both values, since leaving
    it out would not restore what the slice started with."""
    started = {"steps": 2400, "lr_scale": 0.1, "codes_from_sdf": True}
    refuse_changed_settings(7, started, {"steps": None, "lr_scale": 0.1, "codes_from_sdf": True})
    with pytest.raises(CenterArtError) as err:
        refuse_changed_settings(7, started, {"steps": None, "lr_scale": 1.0, "codes_from_sdf": False})
    assert str(err.value) == (
        "slice 7 started with other settings (lr_scale: 0.1 -> 1.0, codes_from_sdf: True -> False); "
        "rerun with those it started with"
    )
