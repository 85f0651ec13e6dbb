"""``centerart slices decoder`` (issue 29): a tiny decoder run of two slices through the CLI, the first stopped and
resumed; its ledger replays to the same weights; the exported decoder loads; other objects than slice 1's, a
damaged state or the encoder's command on a decoder run are one error line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from centerart.cli import main
from centerart.models.checkpoint import load_decoder
from centerart.models.checkpoint_files import file_sha256
from centerart.recipe.ledger import DECODER_LINE_FIELDS, read_ledger

COMMON = ["--threads", "1", "--workers", "1", "--no-progress"]


@pytest.fixture(scope="module")
def tiny_decoder_run(tmp_path_factory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("decoder_slices")
    run, work = root / "run", root / "work"
    args = ["slices", "decoder", "--run", str(run), "--work", str(work), "--preset", "tiny", *COMMON]
    assert main([*args, "--stop-after", "1"]) == 0
    assert not (run / "ledger.jsonl").exists() and (work / "slice_001" / "progress.pt").is_file()
    assert main([*args, "--steps", "5"]) == 2  # a started slice keeps its settings
    assert main(args) == 0
    assert main([*args, "--steps", "2", "--lr-scale", "0.5"]) == 0
    return run, work


@pytest.mark.slow  # ~25 s on 2 cores: 5 objects, their labels and SDF samples, two slices and a replay
def test_two_decoder_slices_write_a_ledger_that_replays(tiny_decoder_run, tmp_path, capsys):
    run, _ = tiny_decoder_run
    lines = read_ledger(run, DECODER_LINE_FIELDS)
    assert [x["steps"] for x in lines] == [3, 2] and [x["first_step"] for x in lines] == [0, 3]
    assert [x["lr_scale"] for x in lines] == [1.0, 0.5] and lines[0]["objects_sha256"] == lines[1]["objects_sha256"]
    assert lines[0]["objects"] == 4 and lines[0]["heldout_objects"] == 1
    assert [x["calls"] for x in lines] == [2, 1]  # slice 1: stopped and resumed, both calls' wall time counted
    assert "val_object/sdf_near" in lines[1]["validation"] and "start_validation" in lines[0]
    # the held-out object's shape and grasps, meshed and executed (eval decoder's figures, in the line)
    v = lines[1]["validation"]
    assert v["heldout_eval/states"] == 1 and v["heldout_eval/physics_top1"] in (0.0, 1.0)
    assert 0 < v.get("heldout_eval/chamfer_mm", 1) < 1000 and v["heldout_eval/empty_meshes"] in (0, 1)
    assert lines[1]["state_sha256"] == file_sha256(run / "state.pt")
    assert lines[1]["decoder_sha256"] == file_sha256(run / "decoder.pt")
    loaded = load_decoder(run / "decoder.pt")  # the exported decoder loads like any other
    assert len(loaded.codes) == 4 and loaded.meta["train_config"]["sliced_run"]["step"] == 5
    assert loaded.code_weight == 1e-2  # new shape codes are fitted under the prior it was trained with

    assert main(["slices", "status", "--run", str(run)]) == 0
    table = capsys.readouterr().out
    assert "| 2 | 2 | 5 | 0.5 |" in table and "heldout_eval/chamfer_mm" in table
    assert main(["slices", "replay", "--run", str(run), "--work", str(tmp_path / "replay"), *COMMON]) == 0
    assert "largest weight difference 0" in capsys.readouterr().out


def _one_error_line(capsys, argv: list[str], names: str) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err, err
    last = err.splitlines()[-1]  # after the object and label stages' progress bars, when they ran
    assert last.startswith("centerart: error:") and names in last, err


@pytest.mark.slow  # shares the tiny run above
def test_bad_decoder_runs_are_one_error_line(tiny_decoder_run, tmp_path, capsys):
    run = Path(shutil.copytree(tiny_decoder_run[0], tmp_path / "run"))
    args = ["--run", str(run), "--work", str(tiny_decoder_run[1]), *COMMON]
    _one_error_line(capsys, ["slices", "next", *args], "run.json")  # the encoder's command on a decoder run
    ledger = run / "ledger.jsonl"
    lines = [json.loads(t) for t in ledger.read_text().splitlines()]
    lines[0]["objects_sha256"] = "0" * 64  # slice 1 trained on other objects than WORK holds
    ledger.write_text("".join(json.dumps(x) + "\n" for x in lines))
    _one_error_line(capsys, ["slices", "decoder", *args], "not the objects slice 1 trained on")
    (run / "state.pt").write_bytes(b"damaged")
    _one_error_line(capsys, ["slices", "decoder", *args], "state.pt")


@pytest.mark.slow  # ~10 s: two more tiny slices on the run above's data
def test_a_decoder_run_with_the_papers_dropout_and_weight_norm_keeps_them(tiny_decoder_run, tmp_path, capsys):
    work, run = tmp_path / "work", tmp_path / "run"
    work.mkdir()
    for name in ("objects", "grasps", "sdf"):  # the same objects, labels and samples as the run above
        (work / name).symlink_to(tiny_decoder_run[1] / name)
    args = ["slices", "decoder", "--run", str(run), "--work", str(work), "--preset", "tiny", *COMMON]
    assert main([*args, "--dropout", "0.2", "--weight-norm", "True"]) == 0
    plan = json.loads((run / "run.json").read_text())
    assert plan["decoder_overrides"] == {"dropout": 0.2, "weight_norm": True}
    config = load_decoder(run / "decoder.pt").decoder.config
    assert config.dropout == 0.2 and config.weight_norm
    _one_error_line(capsys, [*args, "--dropout", "0.5"], "made with dropout=0.2")
    assert main(args) == 0  # slice 2 continues the run with the decoder it was made with
    assert main(["slices", "status", "--run", str(run)]) == 0
    assert "dropout 0.2, weight_norm True" in capsys.readouterr().out


@pytest.mark.slow  # ~30 s: one more tiny slice whose codes are refitted (4 code fits), and its replay
def test_a_slice_whose_codes_learn_from_the_sdf_refits_them_and_replays(tiny_decoder_run, tmp_path, capsys):
    run = Path(shutil.copytree(tiny_decoder_run[0], tmp_path / "run"))
    before = load_decoder(run / "decoder.pt").codes
    args = ["slices", "decoder", "--run", str(run), "--work", str(tiny_decoder_run[1]), *COMMON]
    assert main([*args, "--steps", "1", "--codes-from-sdf"]) == 0
    line = read_ledger(run, DECODER_LINE_FIELDS)[-1]
    assert line["slice"] == 3 and line["codes_from_sdf"] and line["refit_codes"]
    assert line["codes_refit"]["max_code_change"] > 0 and line["wall_s"]["refit_codes"] > 0
    after = load_decoder(run / "decoder.pt").codes
    assert all(not (after[o] == before[o]).all() for o in before)
    assert main(["slices", "status", "--run", str(run)]) == 0
    assert "| sdf, refitted |" in capsys.readouterr().out
    assert main(["slices", "replay", "--run", str(run), "--work", str(tmp_path / "replay"), *COMMON]) == 0
    assert "largest weight difference 0" in capsys.readouterr().out
