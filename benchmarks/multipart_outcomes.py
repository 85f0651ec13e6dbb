"""Failed top grasps on objects with more than one movable part: did the grasp open another part? Prints JSON.

Generated storage furniture has 1-3 columns of drawers and doors and refrigerators a door and a freezer drawer or
door; one part is the *target* (drawn at random, ``assets/generator.py``) and the others are held closed. SR counts
only the target's motion, so a grasp that opens a neighbouring drawer fails. This re-executes each failed top
grasp of a scene evaluation (the 3-D matched prediction's, which the records store in the camera frame) once per
other movable part, with that part as the target and the true target held at its state, in the rebuilt scene and
with the evaluation's executor and thresholds:

    python benchmarks/multipart_outcomes.py --eval OUT --scenes ROOT --out multipart.json
    # OUT: a `centerart eval scenes` output (its records/); ROOT: the folder holding the test sets it names
    # (single/, kitchen/, ...). Generated sets only (real objects' other parts are not described in meta.json).
"""

from __future__ import annotations

import argparse
import copy
import json
from collections import Counter
from pathlib import Path

import numpy as np

from bench_report import emit, run_main


def failed_rows(eval_out: Path):
    """(set name, row) of every failed top grasp on a multi-part generated object whose grasp was recorded."""
    from centerart.evaluation.paired import learned_rows

    for set_name, row in learned_rows(eval_out):
        if set_name.startswith("real") or row["visible_fraction"] < 0.3 or row["sr_image"]:
            continue
        if row.get("image_same_as_3d") and row.get("grasp_camera") is not None:
            yield set_name, row


def world_grasp(scene_dir: Path, row: dict) -> np.ndarray:
    view = next(d for d in (scene_dir / "views").iterdir() if int(d.name) == row["view"])
    world_T_camera = np.asarray(json.loads((view / "labels.json").read_text())["world_T_camera"], float)
    return world_T_camera @ np.asarray(row["grasp_camera"], float)


def opens_other_parts(scene, k: int, world_T_tcp: np.ndarray) -> list[str]:
    """The other movable parts of object ``k`` that the grasp opens (each tried as the target in turn)."""
    from centerart.evaluation.physics_scene import build_physics_scene
    from centerart.evaluation.trials import execute_grasp
    from centerart.scenes.description import load_scene_object

    spec = scene.objects[k]
    joints = json.loads((Path(spec.path) / "meta.json").read_text())["joints"]
    opened = []
    for other, q in spec.held_states.items():
        alt = copy.deepcopy(scene)
        s = alt.objects[k]
        held = {j: v for j, v in spec.held_states.items() if j != other}
        s.held_states = held | {spec.target_joint: spec.joint_state}
        s.target_joint, s.joint_state, s.joint_type = other, q, joints[other]["type"]
        phys = build_physics_scene(alt, [load_scene_object(x) for x in alt.objects])
        try:
            if execute_grasp(phys, k, world_T_tcp)["success"]:
                opened.append(other)
        finally:
            phys.close()
    return opened


def main() -> None:
    from centerart.scenes.description import SceneDescription

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--eval", type=Path, required=True)
    ap.add_argument("--scenes", type=Path, required=True)
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    rows, counts = [], Counter()
    for set_name, row in failed_rows(args.eval):
        scene_dir = args.scenes / set_name / row["scene"]
        scene = SceneDescription.load(scene_dir / "scene.json")
        spec = scene.objects[row["instance"]]
        if not spec.held_states:
            continue
        opened = opens_other_parts(scene, row["instance"], world_grasp(scene_dir, row))
        counts[f"{set_name}|{row['category']}|{'other part opened' if opened else 'nothing opened'}"] += 1
        rows.append({"set": set_name, "scene": row["scene"], "view": row["view"], "object_id": row["object_id"],
                     "state_normalized": row["state_normalized"], "target": spec.target_joint,
                     "movable_parts": len(spec.held_states) + 1, "abort": row["sr_image_abort"],
                     "opened_other": opened})  # fmt: skip
    emit({"eval": str(args.eval), "failed_top_grasps_tried": len(rows), "counts": dict(sorted(counts.items())),
          "rows": rows}, args.out)  # fmt: skip


if __name__ == "__main__":
    run_main(main)
