"""``centerart recipe`` (issue 14): the tiny preset end to end, an interrupted run resuming, two runs of one seed
giving the same data and decoder, the data steps through a local Ray instance, and the decoder under DDP."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch

from centerart.assets.fingerprint import object_fingerprint
from centerart.cli import main
from centerart.recipe.config import STEPS, recipe_preset
from centerart.recipe.runner import format_seconds, run_recipe
from centerart.recipe.steps import Paths, plan_decoder

# Measured: two runs of one seed give bit-identical decoders on CPU (one torch thread, same data); the tolerance
# leaves room for other BLAS builds.
DECODER_ATOL = 1e-6


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory) -> Path:
    """The whole tiny recipe, through the command line, in this process (workers 1: the session's renderer)."""
    out = tmp_path_factory.mktemp("recipe") / "tiny"
    assert main(["recipe", "--preset", "tiny", "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    return out


def _manifest(out: Path) -> dict:
    return json.loads((out / "manifest.json").read_text())


@pytest.mark.slow  # ~50-70 s on 2 cores: every stage of the pipeline at its smallest
def test_tiny_recipe_runs_end_to_end_with_one_manifest(tiny_run):
    m = _manifest(tiny_run)
    assert m["stage"] == "recipe" and m["config"]["preset"] == "tiny" and m["seed"] != m["test_seed"]
    assert list(m["steps"]) == list(STEPS)
    for name, record in m["steps"].items():
        assert record["status"] == "done", name
        assert record["configs"] and record["code_version"] and record["seconds"] >= 0 and record["counts"], name
    counts = {n: r["counts"] for n, r in m["steps"].items()}
    assert counts["objects"]["objects"] == counts["objects"]["test_objects"] == 5
    assert counts["grasps"]["items"] == 10 and counts["sdf"]["states"] == 10
    assert counts["decoder"]["train_objects"] == 4 and counts["decoder"]["heldout_objects"] == 1
    assert set(counts["scenes"]) == {"train_kitchen", "val_single", "test_single"}
    assert counts["encoder"]["steps"] == 4 and counts["evaluation"]["held_out"] is True
    assert m["steps"]["objects"]["seeds"] == {"objects": 0, "test_objects": 9000}
    for f in ("decoder/decoder.pt", "encoder/encoder.pt", "evaluation/report.md", "evaluation/report.json"):
        assert (tiny_run / f).is_file(), f

    # Held out: no test object is a training object (by content), and the decoder records what it trained on.
    trained = set(torch.load(tiny_run / "decoder/decoder.pt", weights_only=False)["training_objects"].values())
    tests = {object_fingerprint(p) for p in (tiny_run / "test_objects").iterdir() if p.is_dir()}
    assert len(trained) == 4 and None not in trained and not trained & tests


def test_command_line_starts_from_the_named_preset_and_overrides_any_step():
    import tyro

    from centerart.recipe.config import RecipeConfig, cli_default

    def parse(*args):
        return tyro.cli(RecipeConfig, args=list(args), default=cli_default(list(args)))

    cfg = parse("--preset", "tiny", "--out", "x", "--decoder.epochs", "7", "--ray-address", "auto")
    assert cfg == replace(recipe_preset("tiny", out=Path("x"), ray_address="auto"), decoder=replace(
        recipe_preset("tiny", out=Path("x")).decoder, epochs=7))  # fmt: skip
    assert parse("--out", "x") == recipe_preset("small", out=Path("x"))
    assert recipe_preset("small").grasps.per_state == 100 and recipe_preset("paper").decoder.preset == "paper"
    with pytest.raises(SystemExit):
        parse("--preset", "tiny")  # --out is required


def test_cheap_training_views_change_the_training_sets_only(tmp_path):
    import json

    from centerart.recipe.steps import Paths, plan_scenes

    cfg = recipe_preset("small", out=tmp_path)
    cfg.scenes.train_intrinsics, cfg.scenes.train_depth = "d415-half", "stereo-model"
    (tmp_path / "decoder").mkdir()
    split = {"train_objects": ["a"], "heldout_objects": ["b"], "heldout_states": {}}
    (tmp_path / "decoder" / "split.json").write_text(json.dumps(split))
    planned = plan_scenes(cfg, Paths(tmp_path))
    made = {name: (c.intrinsics, c.depth) for name, c in planned.items()}
    assert made["train_kitchen"] == made["train_single"] == ("d415-half", "stereo-model")
    assert made["val_single"] == made["test_kitchen"] == ("d415", "stereo")


def test_changed_settings_and_equal_seeds_are_refused(tiny_run, capsys):
    args = ["recipe", "--preset", "tiny", "--out", str(tiny_run), "--until", "grasps", "--grasps.per-state", "5"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "grasps step was made with other settings" in err and "per_state: 4 -> 5" in err
    assert main(["recipe", "--preset", "tiny", "--out", str(tiny_run), "--test-seed", "0"]) == 2
    assert "--test-seed must differ from --seed" in capsys.readouterr().err
    # Lightning's own ddp launcher would re-run the whole command line in every process.
    assert main(["recipe", "--preset", "tiny", "--out", str(tiny_run), "--devices", "2", "--strategy", "ddp"]) == 2
    assert "needs a cluster launcher" in capsys.readouterr().err


def test_other_ranks_only_follow_the_training_steps(tiny_run, monkeypatch):
    before = (tiny_run / "manifest.json").read_bytes()
    monkeypatch.setenv("RANK", "1")  # as torchrun sets it in the second process
    lines = []
    assert run_recipe(recipe_preset("tiny", out=tiny_run, progress=False), echo=lines.append) == {}
    assert lines == [] and (tiny_run / "manifest.json").read_bytes() == before  # both training steps were done


@pytest.mark.slow  # ~40 s: a local Ray instance (~15 s to start), then the SDF samples and the decoder again
def test_interrupted_recipe_resumes_through_ray_and_reproduces_the_first_run(
    tiny_run, tmp_path, ray_shut_down_afterwards
):
    import ray

    out = tmp_path / "again"
    cfg = recipe_preset("tiny", out=out, workers=1, progress=False, until="grasps", ray_address="local")
    run_recipe(cfg)  # the data steps through a private Ray instance
    assert not ray.is_initialized(), "the recipe shuts down the Ray instance it started"
    first = _manifest(out)["steps"]
    assert list(first) == ["objects", "grasps"] and not (out / "sdf").exists()

    # Killed inside the grasps step: its record says running and one item is missing.
    m = _manifest(out)
    m["steps"]["grasps"]["status"] = "running"
    (out / "manifest.json").write_text(json.dumps(m))
    lost = out / "grasps" / "oven_0000" / "state_01.npz"
    lost.unlink()

    lines = []
    run_recipe(replace(cfg, until="decoder", ray_address=None), echo=lines.append)
    shown = format_seconds(first["objects"]["seconds"])  # "1 min 10 s" where a slow machine took over a minute
    assert lines[0] == f"[1/{len(STEPS)}] objects: finished earlier in {shown}, skipped"
    ran = [line.split(": ")[0] for line in lines[1:]]  # each step that ran prints "running" and "done in ..."
    assert ran == ["[2/7] grasps", "[2/7] grasps", "[3/7] sdf", "[3/7] sdf", "[4/7] decoder", "[4/7] decoder"]
    steps = _manifest(out)["steps"]
    assert steps["objects"] == first["objects"], "a skipped step keeps its record"
    assert steps["grasps"]["status"] == "done" and lost.is_file()
    assert [s for s in steps if steps[s]["status"] == "done"] == ["objects", "grasps", "sdf", "decoder"]

    # Same seed, same data: objects byte for byte, labels and samples array for array, the decoder within tolerance.
    _assert_same_files(tiny_run / "objects", out / "objects", "*/*")
    _assert_same_files(tiny_run / "test_objects", out / "test_objects", "*/*")
    _assert_same_arrays(tiny_run / "grasps", out / "grasps")
    _assert_same_arrays(tiny_run / "sdf", out / "sdf")
    a = torch.load(tiny_run / "decoder/decoder.pt", weights_only=False)
    b = torch.load(out / "decoder/decoder.pt", weights_only=False)
    assert a["object_ids"] == b["object_ids"] and a["split"] == b["split"]
    np.testing.assert_allclose(np.asarray(a["codes"]), np.asarray(b["codes"]), rtol=0, atol=DECODER_ATOL)
    for k, v in a["state_dict"].items():
        torch.testing.assert_close(v, b["state_dict"][k], rtol=0, atol=DECODER_ATOL)


def _assert_same_files(a: Path, b: Path, pattern: str) -> None:
    files = sorted(p.relative_to(a) for p in a.rglob(pattern) if p.is_file())
    assert files and files == sorted(p.relative_to(b) for p in b.rglob(pattern) if p.is_file())
    for rel in files:
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel


def _assert_same_arrays(a: Path, b: Path) -> None:
    files = sorted(p.relative_to(a) for p in a.glob("*/state_*.npz"))
    assert files and files == sorted(p.relative_to(b) for p in b.glob("*/state_*.npz"))
    for rel in files:
        x, y = np.load(a / rel), np.load(b / rel)
        assert sorted(x.files) == sorted(y.files), rel
        for key in x.files:
            np.testing.assert_array_equal(x[key], y[key], err_msg=f"{rel}:{key}")


@pytest.mark.slow  # ~25 s: two spawned training processes
def test_tiny_decoder_trains_with_ddp_on_two_cpu_processes(tiny_run, tmp_path):
    from centerart.models.checkpoint import load_shape_codes
    from centerart.training.decoder_module import DecoderModule
    from centerart.training.train_decoder import train_decoder

    cfg = recipe_preset("tiny", out=tiny_run, accelerator="cpu", devices=2, progress=False)
    assert cfg.training_strategy() == "ddp_spawn"
    dcfg = replace(plan_decoder(cfg, Paths(tiny_run))["decoder"], out=tmp_path / "ddp")
    result = train_decoder(dcfg)
    assert result["metrics"]["world_size"] == 2 and result["metrics"]["train_points_per_second"] > 0
    codes = load_shape_codes(Path(result["checkpoint"]))
    assert sorted(codes) == result["split"].train_objects and len(codes) == 4

    # Every object's code moved from its initial value: each was trained by whichever process drew it.
    import lightning as L

    L.seed_everything(dcfg.seed, verbose=False)
    initial = DecoderModule(dcfg.decoder_config(), dcfg.loss_config(), result["split"].train_objects).code_array()
    for i, oid in enumerate(result["split"].train_objects):
        assert np.isfinite(codes[oid]).all()
        assert np.abs(codes[oid] - initial[i]).max() > 1e-3, oid


def _data_steps_copied(run: Path, out: Path) -> None:
    """``out`` holds ``run``'s data steps (folders and records), as regenerating them with its options would."""
    import shutil

    for name in ("objects", "test_objects", "grasps", "sdf"):
        shutil.copytree(run / name, out / name)
    m = _manifest(run)
    m["steps"] = {k: v for k, v in m["steps"].items() if k in ("objects", "grasps", "sdf")}
    (out / "manifest.json").write_text(json.dumps(m))


def test_decoder_is_adopted_from_an_earlier_run_only_with_its_settings_and_objects(tiny_run, tmp_path):
    """``--decoder-from``: a run on a machine that kept nothing but the repository takes the decoder trained in an
    earlier session instead of training it again; other settings or other objects are refused, nothing written."""
    from centerart.errors import CenterArtError
    from centerart.recipe.adopt import check_training_objects

    out = tmp_path / "later"
    _data_steps_copied(tiny_run, out)
    cfg = recipe_preset("tiny", out=out, workers=1, progress=False, until="decoder", decoder_from=tiny_run)
    with pytest.raises(CenterArtError, match=r"--decoder-from .*other settings \(decoder.epochs: 3 -> 4\)"):
        run_recipe(replace(cfg, decoder=replace(cfg.decoder, epochs=4)))
    assert not (out / "decoder").exists() and "decoder" not in _manifest(out)["steps"]
    with pytest.raises(CenterArtError, match="trained on other objects than"):
        check_training_objects(tiny_run / "decoder/decoder.pt", tiny_run / "test_objects")

    lines = []
    run_recipe(cfg, echo=lines.append)
    assert lines[-1].startswith(f"[4/7] decoder: adopted from {tiny_run.resolve()}"), lines
    assert (out / "decoder/decoder.pt").read_bytes() == (tiny_run / "decoder/decoder.pt").read_bytes()
    assert (out / "decoder/split.json").is_file() and not (out / "decoder/lightning").exists()
    record = _manifest(out)["steps"]["decoder"]
    assert record["adopted_from"] == str(tiny_run.resolve()) and record["status"] == "done"
    assert {k: v for k, v in record.items() if k not in ("adopted_from", "adopted")} == _manifest(tiny_run)[
        "steps"]["decoder"]  # fmt: skip
