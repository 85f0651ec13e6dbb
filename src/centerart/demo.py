"""``centerart demo``: the main job on its built-in default, end to end on a CPU in a few minutes.

The main job: generate one object of every category with a seed no model was trained on, render a kitchen of
them with realistic (stereo) depth, predict with the shipped weights (``centerart predict``: overlay, 3-D scene,
predictions, meshes) and compare the predictions with the ground truth. Then a tour of the stages:

1. generate two checked objects of every category and render them closed, half-open and open;
2. label grasps on one oven in physics and draw them;
3. sample its SDF and reconstruct it with the shipped decoder, top grasps drawn;
4. render a kitchen scene of the generated objects with realistic (stereo) depth and its labels.

Every step calls the same code as the stage commands, at a small scale.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from centerart.geometry.gravity import gravity_from_world_T_camera

MATCH_DISTANCE_M = 0.10  # the evaluation's 3-D centre match distance (m), reported per object


@dataclass
class DemoConfig:
    """Run every stage at a small scale and write the pictures to --out."""

    out: Path = Path("outputs/demo")
    """Output folder."""
    count: int = 2
    """Objects per category."""
    seed: int = 0
    workers: int | None = None
    """Parallel worker processes (default: all cores)."""
    unseen_seed: int = 1000
    """Seed of the objects the prediction step renders (the shipped models were trained on seed-0 objects)."""
    stages: bool = True
    """Also run the tour of the stages (objects, grasp labels, SDF and decoder, scene pictures)."""


def run_demo(cfg: DemoConfig) -> None:
    out = Path(cfg.out)
    report = predict_unseen_kitchen(cfg, out)
    pictures = stage_tour(cfg, out) if cfg.stages else []
    print("prediction (open these first):")
    for name in ("overlay.png", "scene.glb", "predictions.json", "comparison.json"):
        print(f"  {out / 'predict' / name}")
    print(f"  3-D viewer: centerart view {out / 'predict'}")
    if pictures:
        print("stage pictures:\n" + "\n".join(f"  {p}" for p in pictures))
    rows = report["objects"]
    found, within = sum(r["found"] for r in rows), sum(r.get("centre_within", False) for r in rows)
    print(f"found {found} of {len(rows)} objects in the image, {within} with the 3-D centre within "
          f"{MATCH_DISTANCE_M * 100:.0f} cm (table above)")  # fmt: skip


def predict_unseen_kitchen(cfg: DemoConfig, out: Path) -> dict:
    """Render a kitchen of unseen objects, predict on it, compare with its labels; returns the comparison."""
    from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
    from centerart.predict import PredictConfig, run_predict
    from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes, list_views

    objects, scenes = out / "unseen_objects", out / "unseen_kitchen"
    for folder in (objects, scenes):
        if folder.is_dir():
            shutil.rmtree(folder)
    print(f"1/5 a kitchen of objects no model has seen (seed {cfg.unseen_seed}), stereo depth")
    generate_objects(GenerateObjectsConfig(out=objects, category="all", count=1, seed=cfg.unseen_seed, workers=1))
    generate_scenes(
        GenerateScenesConfig(objects=objects, out=scenes, layout="kitchen", count=1, views_per_scene=1,
                             seed=cfg.seed + 11, depth="stereo", workers=1, save_ir=False)
    )  # fmt: skip
    view = list_views(scenes)[0]
    print("2/5 prediction with the shipped encoder and decoder")
    # The camera's gravity direction, as a robot has it from TF: objects' poses are then corrected from the depth.
    world_T_camera = np.asarray(json.loads((view / "labels.json").read_text())["world_T_camera"], float)
    record = run_predict(
        PredictConfig(rgb=view / "rgb.png", depth=view / "depth_realistic.png", intrinsics=view / "labels.json",
                      out=out / "predict", gravity=tuple(gravity_from_world_T_camera(world_T_camera).tolist()))
    )  # fmt: skip
    return write_comparison(record, view, out / "predict" / "comparison.json")


def compare_with_labels(record: dict, labels: dict) -> list[dict]:
    """Per labelled object: the prediction whose peak lies on its box (nearest centre first), and that
    prediction's pose and joint errors; ``centre_within`` says whether the 3-D centre is within MATCH_DISTANCE_M."""
    import numpy as np

    from centerart.geometry.transforms import rotation_angle_between

    def pose(o):
        return np.asarray(o["camera_T_object"])

    rows = []
    for obj in labels["objects"]:
        x0, y0, x1, y1 = obj["bbox_xyxy"]
        on_box = [p for p in record["objects"] if x0 <= p["peak_uv"][0] <= x1 and y0 <= p["peak_uv"][1] <= y1]
        row = {"object_id": obj["object_id"], "visible_fraction": obj["visible_fraction"], "found": bool(on_box)}
        if on_box:
            p = min(on_box, key=lambda q: np.linalg.norm(pose(q)[:3, 3] - pose(obj)[:3, 3]))
            joint = obj["joint"]
            scale, unit = (180 / np.pi, "deg") if joint["type"] == "revolute" else (100.0, "cm")
            t_err = float(np.linalg.norm(pose(p)[:3, 3] - pose(obj)[:3, 3]))
            row.update(
                translation_cm=100 * t_err,
                centre_within=t_err < MATCH_DISTANCE_M,
                rotation_deg=float(np.degrees(rotation_angle_between(pose(p)[:3, :3], pose(obj)[:3, :3]))),
                joint_type_correct=p["joint"]["type"] == joint["type"],
                joint_state_error=abs(p["joint"]["state"] - joint["state"]) * scale,
                joint_state_unit=unit,
                grasps=len(p["grasps"]),
                **top_grasp_check(p, min_closing_points(record)),
            )
        rows.append(row)
    return rows


def min_closing_points(record: dict) -> int:
    """The anchoring check's threshold (observed points between the pads) the record was predicted with."""
    from centerart.inference.observed_checks import ObservedCheckConfig

    checks = ((record.get("config") or {}).get("anchoring") or {}).get("checks") or {}
    return int(checks.get("min_closing_points", ObservedCheckConfig().min_closing_points))


def top_grasp_check(obj: dict, min_points: int) -> dict:
    """Of one predicted object (a predictions.json object): where its top grasp came from (``decoder``,
    ``observed``, ``handle``; None without anchoring) and whether it touches observed material: "yes" when at least
    ``min_points`` observed points of the object lie between its pads, "no" when fewer, "n/a" when anchoring was
    off (no closing points saved), "no grasp" when the object has none."""
    top = (obj.get("grasps") or [None])[0]
    if top is None:
        return {"top_grasp_source": None, "top_grasp_on_material": "no grasp"}
    if "closing_points" not in top:
        return {"top_grasp_source": None if top is None else top.get("source"), "top_grasp_on_material": "n/a"}
    on = "yes" if int(top["closing_points"]) >= min_points else "no"
    return {"top_grasp_source": top.get("source"), "top_grasp_on_material": on}


def print_comparison(rows: list[dict]) -> None:
    """The comparison table: per labelled object its detection, pose and joint errors, and whether the top grasp
    touches observed material (anchoring's closing points >= its threshold; n/a when anchoring was off) and its
    source."""
    within = f"<{MATCH_DISTANCE_M * 100:.0f}cm"
    head = f"{'object':24s} {'visible':>7s} {'found':>5s} {'t err cm':>8s} {within:>6s} {'R err deg':>9s}"
    print(f"{head} {'type':>5s} {'q err':>10s} {'grasp on material':>17s} {'from':>8s}")
    for r in rows:
        line = f"{r['object_id']:24s} {r['visible_fraction']:7.2f} {'yes' if r['found'] else 'no':>5s}"
        if r["found"]:
            kind = "ok" if r["joint_type_correct"] else "wrong"
            line += f" {r['translation_cm']:8.1f} {'yes' if r['centre_within'] else 'no':>6s} {r['rotation_deg']:9.1f}"
            line += f" {kind:>5s} {r['joint_state_error']:7.1f} {r['joint_state_unit']:>2s}"
            line += f" {r.get('top_grasp_on_material', 'n/a'):>17s} {r.get('top_grasp_source') or '-':>8s}"
        print(line)


def write_comparison(record: dict, view: Path, path: Path) -> dict:
    """Compare a prediction record with a rendered view's labels; print the table and write it as JSON."""
    import json

    from centerart.utils.atomic import atomic_write_json

    rows = compare_with_labels(record, json.loads((Path(view) / "labels.json").read_text()))
    print_comparison(rows)
    report = {"match_distance_m": MATCH_DISTANCE_M, "predictions": len(record["objects"]), "objects": rows}
    atomic_write_json(path, report)
    return report


def stage_tour(cfg: DemoConfig, out: Path) -> list[Path]:

    from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
    from centerart.grasps.generate import GenerateGraspsConfig, generate_grasps
    from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes
    from centerart.sdf.generate import GenerateSdfConfig, generate_sdf
    from centerart.viz.decoder_sheet import ShowDecoderConfig, show_decoder
    from centerart.viz.grasps_sheet import ShowGraspsConfig, show_grasps
    from centerart.viz.objects_sheet import ShowObjectsConfig, show_objects
    from centerart.viz.scenes_sheet import ShowScenesConfig, show_scenes

    objects, one, grasps, sdf, scenes = (out / name for name in ("objects", "oven", "grasps", "sdf", "kitchen"))
    # Start every run from scratch: the stage commands refuse to resume folders made with other settings (e.g.
    # by an older version of this package), which is right for datasets but would stop a rerun of the demo.
    # Only the demo's own subfolders are removed.
    for folder in (objects, one, grasps, sdf, scenes):
        if folder.is_dir():
            shutil.rmtree(folder)
    pictures = []
    print("3/5 stages: objects")
    generate_objects(
        GenerateObjectsConfig(out=objects, category="all", count=cfg.count, seed=cfg.seed, workers=cfg.workers)
    )
    pictures.append(show_objects(ShowObjectsConfig(path=objects, out=out / "objects.png", objects_per_row=2)))

    print("4/5 stages: grasp labels (one oven, 3 joint states), SDF samples, shipped decoder")
    # The same seed gives the same oven_0000 as in the objects folder; a folder of its own keeps the run short.
    generate_objects(GenerateObjectsConfig(out=one, category="oven", count=1, seed=cfg.seed, workers=1))
    generate_grasps(
        GenerateGraspsConfig(
            objects=one, out=grasps, states=3, per_state=60, max_trials=400, seed=cfg.seed, workers=cfg.workers
        )
    )
    pictures.append(
        show_grasps(ShowGraspsConfig(labels=grasps, objects=one, object="oven_0000", out=out / "grasps.png"))
    )

    generate_sdf(
        GenerateSdfConfig(objects=one, grasps=grasps, out=sdf, points=20000, seed=cfg.seed, workers=cfg.workers)
    )
    pictures.append(show_decoder(ShowDecoderConfig(data=sdf, object="oven_0000", out=out / "reconstruction.png")))

    print("5/5 stages: a kitchen scene with realistic depth")
    generate_scenes(
        GenerateScenesConfig(
            objects=objects,
            out=scenes,
            layout="kitchen",
            count=1,
            views_per_scene=2,
            seed=cfg.seed,
            depth="stereo",
            workers=1,
        )
    )
    pictures.append(show_scenes(ShowScenesConfig(path=scenes, out=out / "kitchen.png")))
    return pictures
