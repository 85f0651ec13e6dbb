"""`centerart eval decoder` end to end on real pipeline outputs: objects -> grasps -> SDF -> shipped checkpoint."""

import json
import math

import pytest
import torch

from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
from centerart.cli import main
from centerart.grasps.generate import GenerateGraspsConfig, generate_grasps
from centerart.sdf.generate import GenerateSdfConfig, generate_sdf


@pytest.mark.slow
def test_eval_decoder_cli_writes_a_complete_report(tmp_path):
    torch.set_num_threads(1)
    objects = tmp_path / "objects"
    # seed 0 dishwasher_0000 is one of the shipped checkpoint's training objects
    generate_objects(GenerateObjectsConfig(out=objects, category="dishwasher", count=1, seed=0, workers=1))
    grasps = tmp_path / "grasps"
    generate_grasps(
        GenerateGraspsConfig(objects=objects, out=grasps, states=2, per_state=30, max_trials=300, workers=1)
    )
    sdf = tmp_path / "sdf"
    generate_sdf(GenerateSdfConfig(objects=objects, grasps=grasps, out=sdf, points=20000, workers=1))
    out = tmp_path / "eval"
    code = main(
        [
            "eval",
            "decoder",
            "--data",
            str(sdf),
            "--objects",
            str(objects),
            "--grasps",
            str(grasps),
            "--out",
            str(out),
            "--states-per-object",
            "1",
            "--resolution",
            "64",
            "--code-fit-steps",
            "20",
            "--code-fit-dropout",
        ]
    )
    assert code == 0 and (out / "report.png").stat().st_size > 10_000
    report = json.loads((out / "report.json").read_text())
    assert report["config"]["code_fit_dropout"] is True  # recorded beside the figures it changes
    row = report["summary"]["train"]
    assert row["states"] >= 1
    assert math.isfinite(row["chamfer_mm"]) and row["chamfer_mm"] < 150.0
    assert 0.0 <= row["fscore"] <= 1.0
    for key in ("precision_at_k", "coverage", "physics_top1", "physics_any5"):
        assert 0.0 <= row[key] <= 1.0, key
    # state kinds partition the group; calibration pools exactly the executed grasps with their scores
    kinds = row["by_state_kind"]
    assert set(kinds) <= {"closed", "interior", "open"} and sum(k["states"] for k in kinds.values()) == row["states"]
    executed = [s for s in report["states"] if s["group"] == "train"]
    assert row["calibration"]["count"] == sum(len(s["grasp_scores"]) for s in executed)
    assert all(len(s["grasp_scores"]) == len(s["grasp_successes"]) <= 5 for s in executed)
    assert report["summary"]["calibration_all_groups"]["count"] >= row["calibration"]["count"]


def test_a_namesake_of_a_training_object_is_not_given_its_code(tmp_path):
    """Seed 0 dishwasher_0000 is a training object of the shipped decoder; seed 7's dishwasher_0000 is another
    object with the same id: it must be evaluated as a held-out object (fitted code), not with its namesake's."""
    from centerart.evaluation.decoder_eval import trained_object_ids
    from centerart.models.checkpoint import load_decoder

    loaded = load_decoder(None)
    for seed in (0, 7):
        generate_objects(
            GenerateObjectsConfig(out=tmp_path / str(seed), category="dishwasher", count=1, seed=seed, workers=1)
        )
    assert trained_object_ids(loaded, tmp_path / "0", ["dishwasher_0000"]) == {"dishwasher_0000"}
    assert trained_object_ids(loaded, tmp_path / "7", ["dishwasher_0000"]) == set()
