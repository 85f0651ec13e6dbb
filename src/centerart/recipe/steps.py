"""The recipe's steps. Each builds its stages' configs from the recipe config (``plan``), says where its outputs
are (``folders``) and whether they are complete (``done``), and runs its stages (``run``), returning counts.

Layout of OUT (one folder per stage run)::

    objects/  test_objects/            training objects (--seed), held-out test objects (--test-seed)
    grasps/  sdf/                      grasp labels and SDF samples of the training objects
    decoder/                           centerart train decoder output (decoder.pt, split.json, ...)
    split/train/  split/heldout/       links to the decoder's training and held-out objects
    scenes/<set>/                      train_kitchen, train_single (decoder's training objects, with shape codes),
                                       val_kitchen, val_single (decoder's held-out objects),
                                       test_single, test_kitchen (test objects)
    encoder/                           centerart train encoder output (encoder.pt, ...)
    evaluation/                        centerart eval scenes output (report.md, report.json, ...)
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from centerart.errors import CenterArtError
from centerart.recipe.config import RecipeConfig


@dataclass(frozen=True)
class Paths:
    out: Path

    def __getattr__(self, name: str) -> Path:  # objects, grasps, sdf, decoder, encoder, evaluation, ...
        if name.startswith("_"):
            raise AttributeError(name)
        return self.out / name

    def scenes(self, name: str) -> Path:
        return self.out / "scenes" / name


@dataclass(frozen=True)
class SceneSet:
    name: str
    role: str  # train | val | test
    layout: str
    seed_offset: int  # added to --seed (train, val) or --test-seed (test)


# Seeds as the shipped encoder's scenes (100-400 for seed 0) and the evaluation's test scenes (9100, 9200).
SCENE_SETS = (
    SceneSet("train_kitchen", "train", "kitchen", 100),
    SceneSet("train_single", "train", "single", 200),
    SceneSet("val_kitchen", "val", "kitchen", 300),
    SceneSet("val_single", "val", "single", 400),
    SceneSet("test_single", "test", "single", 100),
    SceneSet("test_kitchen", "test", "kitchen", 200),
)


# ---------------------------------------------------------------------------- objects
def plan_objects(cfg: RecipeConfig, p: Paths) -> dict[str, Any]:
    from centerart.assets.dataset import GenerateObjectsConfig

    o = cfg.objects
    common = {"category": o.category, "variety": o.variety, "workers": cfg.workers, "ray_address": cfg.ray_address}
    return {
        "objects": GenerateObjectsConfig(out=p.objects, count=cfg.objects.count, seed=cfg.seed, **common),
        "test_objects": GenerateObjectsConfig(
            out=p.test_objects, count=cfg.objects.test_count, seed=cfg.test_seed, **common
        ),
    }


def run_objects(cfg: RecipeConfig, p: Paths, planned: dict) -> dict:
    from centerart.assets.dataset import generate_objects

    counts = {}
    for name, stage_cfg in planned.items():
        per_category = generate_objects(stage_cfg)["counts"]
        counts[name] = sum(c["objects"] for c in per_category.values())
        counts[f"{name}_rejected_attempts"] = sum(c["rejected_attempts"] for c in per_category.values())
    return counts


# ---------------------------------------------------------------------------- grasps, sdf
def plan_grasps(cfg: RecipeConfig, p: Paths) -> dict[str, Any]:
    from centerart.grasps.generate import GenerateGraspsConfig

    g = cfg.grasps
    return {
        "grasps": GenerateGraspsConfig(
            objects=p.objects,
            out=p.grasps,
            states=g.states,
            per_state=g.per_state,
            max_trials=g.max_trials,
            max_candidates=g.max_candidates,
            keep_failures=g.keep_failures,
            seed=cfg.seed,
            workers=cfg.workers,
            ray_address=cfg.ray_address,
        )
    }


def run_grasps(cfg: RecipeConfig, p: Paths, planned: dict) -> dict:
    from centerart.grasps.generate import generate_grasps

    summary = generate_grasps(planned["grasps"])
    keys = ("items", "labels", "trials", "items_with_100_labels")
    return {k: sum(c[k] for c in summary.values()) for k in keys}


def plan_sdf(cfg: RecipeConfig, p: Paths) -> dict[str, Any]:
    from centerart.sdf.generate import GenerateSdfConfig

    return {
        "sdf": GenerateSdfConfig(
            objects=p.objects,
            grasps=p.grasps,
            out=p.sdf,
            points=cfg.sdf.points,
            states=cfg.grasps.states,
            workers=cfg.workers,
            seed=cfg.seed,
            ray_address=cfg.ray_address,
        )
    }


def run_sdf(cfg: RecipeConfig, p: Paths, planned: dict) -> dict:
    from centerart.sdf.generate import generate_sdf

    c = generate_sdf(planned["sdf"], progress=cfg.progress)["counts"]
    return {k: c[k] for k in ("objects", "states", "points", "states_without_grasps")} | {
        "objects_below_min_sign_agreement": len(c["objects_below_min_sign_agreement"])
    }


# ---------------------------------------------------------------------------- training
def _training(cfg: RecipeConfig, threads: int) -> dict:
    return {
        "seed": cfg.seed, "accelerator": cfg.accelerator, "devices": cfg.devices, "num_nodes": cfg.num_nodes,
        "strategy": cfg.training_strategy(), "threads": threads, "progress": cfg.progress,
    }  # fmt: skip


def plan_decoder(cfg: RecipeConfig, p: Paths) -> dict[str, Any]:
    from centerart.training.train_decoder import TrainDecoderConfig

    d = cfg.decoder
    fields = {k: getattr(d, k) for k in (
        "preset", "epochs", "batch_items", "points_per_item", "min_items_per_epoch", "max_points_per_state",
        "lr_decoder", "lr_codes", "code_weight", "heldout_object_fraction", "heldout_states_per_object", "val_every",
        "val_code_fit_steps")}  # fmt: skip
    return {"decoder": TrainDecoderConfig(data=p.sdf, out=p.decoder, **fields, **_training(cfg, d.threads))}


def run_decoder(cfg: RecipeConfig, p: Paths, planned: dict) -> dict:
    from centerart.training.train_decoder import train_decoder

    result = train_decoder(planned["decoder"])
    if result["checkpoint"] is None:  # a DDP process other than rank 0
        return {}
    split, m = result["split"], result["metrics"]
    shown = {k: round(v, 5) for k, v in m.items() if k.startswith(("val_state/", "val_object/"))}
    return {
        "train_objects": len(split.train_objects),
        "heldout_objects": len(split.heldout_objects),
        "heldout_states": sum(len(v) for v in split.heldout_states.values()),
        "train_seconds": round(m["train_seconds"], 1),
        "train_points_per_second": round(m["train_points_per_second"]),
        **shown,
    }


def _decoder_split(p: Paths) -> dict:
    path = p.decoder / "split.json"
    if not path.is_file():
        raise CenterArtError(f"{path}: missing; the decoder step has not finished (rerun without --until)")
    return json.loads(path.read_text())


def plan_scenes(cfg: RecipeConfig, p: Paths) -> dict[str, Any]:
    """One scene-generation config per set with scenes to make (validation sets need held-out objects)."""
    from centerart.scenes.dataset import GenerateScenesConfig

    split, s = _decoder_split(p), cfg.scenes
    objects = {"train": p.split / "train", "val": p.split / "heldout", "test": p.test_objects}
    has_objects = {"train": bool(split["train_objects"]), "val": bool(split["heldout_objects"]), "test": True}
    planned = {}
    for ss in SCENE_SETS:
        count = getattr(s, ss.name)
        if count == 0 or not has_objects[ss.role]:
            continue
        planned[ss.name] = GenerateScenesConfig(
            objects=objects[ss.role], out=p.scenes(ss.name), layout=ss.layout, count=count,
            views_per_scene=s.kitchen_views if ss.layout == "kitchen" else s.single_views,
            seed=(cfg.test_seed if ss.role == "test" else cfg.seed) + ss.seed_offset,
            depth=(s.train_depth or s.depth) if ss.role == "train" else s.depth,
            intrinsics=(s.train_intrinsics or s.intrinsics) if ss.role == "train" else s.intrinsics,
            save_ir=s.save_ir, ir_shading=s.ir_shading, workers=cfg.workers,
            ray_address=cfg.ray_address,
            decoder_checkpoint=p.decoder / "decoder.pt" if ss.role == "train" else None,
        )  # fmt: skip
    return planned


def link_split(p: Paths) -> None:
    """``split/train`` and ``split/heldout``: one link per object to its folder in ``objects/`` (scenes of a part of
    the objects are made from a folder holding just that part)."""
    split = _decoder_split(p)
    link_objects(p.out, {"train": split["train_objects"], "heldout": split["heldout_objects"]})


def link_objects(root: Path, roles: dict[str, list[str]]) -> dict[str, Path]:
    """``root/split/<role>/<id>``: a relative link to ``root/objects/<id>`` for each role's ids; returns the role
    folders."""
    folders = {}
    for role, ids in roles.items():
        folders[role] = Path(root) / "split" / role
        folders[role].mkdir(parents=True, exist_ok=True)
        for oid in ids:
            link = folders[role] / oid
            if not link.is_symlink():
                link.symlink_to(Path("..") / ".." / "objects" / oid, target_is_directory=True)
    return folders


def run_scenes(cfg: RecipeConfig, p: Paths, planned: dict) -> dict:
    from centerart.scenes.dataset import generate_scenes

    link_split(p)
    counts = {}
    for name, stage_cfg in planned.items():
        c = generate_scenes(stage_cfg)["counts"]
        counts[name] = {"scenes": c["scenes"], "images": c["images"], "objects": c["objects_available"]}
    return counts


def plan_encoder(cfg: RecipeConfig, p: Paths) -> dict[str, Any]:
    from centerart.training.train_encoder import TrainEncoderConfig

    sets = plan_scenes(cfg, p)
    e = cfg.encoder
    return {
        "encoder": TrainEncoderConfig(
            scenes=tuple(c.out for n, c in sets.items() if n.startswith("train_")),
            val_scenes=tuple(c.out for n, c in sets.items() if n.startswith("val_")),
            decoder=p.decoder / "decoder.pt",
            out=p.encoder,
            preset=e.preset,
            epochs=e.epochs,
            batch_size=e.batch_size,
            lr=e.lr,
            val_every=e.val_every,
            workers=e.loader_workers,
            **_training(cfg, e.threads),
        )
    }


def run_encoder(cfg: RecipeConfig, p: Paths, planned: dict) -> dict:
    from centerart.training.train_encoder import train_encoder

    result = train_encoder(planned["encoder"])
    if result["checkpoint"] is None:  # a DDP process other than rank 0
        return {}
    m = result["metrics"]
    keep = ("steps", "epochs", "train_seconds_this_run", "train_images_per_second")
    return {k: m[k] for k in keep if k in m} | {k: round(v, 4) for k, v in m.items() if k.startswith("val/")}


# ---------------------------------------------------------------------------- evaluation
def plan_evaluation(cfg: RecipeConfig, p: Paths) -> dict[str, Any]:
    from centerart.evaluation.scene_eval import EvalScenesConfig
    from centerart.utils.parallel import default_workers

    tests = tuple(c.out for n, c in plan_scenes(cfg, p).items() if n.startswith("test_"))
    if not tests:
        return {}
    v = cfg.evaluation
    return {
        "evaluation": EvalScenesConfig(
            scenes=tests,
            out=p.evaluation,
            encoder=p.encoder / "encoder.pt",
            decoder=p.decoder / "decoder.pt",
            depth=v.depth,
            labels_per_state=v.labels_per_state,
            label_max_trials=v.label_max_trials,
            shape=v.shape,
            ablation=v.ablation,
            oracle=v.oracle,
            baseline=v.baseline,
            max_scenes=v.max_scenes,
            workers=cfg.workers or default_workers(),
            threads=v.threads,
            seed=cfg.seed,
            progress=cfg.progress,
        )
    }


def run_evaluation(cfg: RecipeConfig, p: Paths, planned: dict) -> dict:
    from centerart.evaluation.scene_eval import evaluate_scenes
    from centerart.evaluation.scene_report import group_label
    from centerart.viz.eval_report import draw_eval_pictures

    report = evaluate_scenes(planned["evaluation"])
    draw_eval_pictures(p.evaluation, report)
    groups = {
        group_label(report, k): {"objects": g["objects"], "sr": g["sr"], "sr_axis": g["sr_axis"], "rsr": g["rsr"]}
        for k, g in report["groups"].items()
    }
    return {"scenes": report["scenes_evaluated"], "held_out": report["held_out"], "groups": groups}


# ---------------------------------------------------------------------------- the table of steps
@dataclass(frozen=True)
class Step:
    plan: Any
    run: Any
    outputs: Any  # planned -> the files whose presence means the step finished
    training: bool = False
    data: bool = False


def _manifests(planned: dict) -> list[Path]:
    return [Path(c.out) / "manifest.json" for c in planned.values()]


STEP_TABLE: dict[str, Step] = {
    "objects": Step(plan_objects, run_objects, _manifests, data=True),
    "grasps": Step(plan_grasps, run_grasps, _manifests, data=True),
    "sdf": Step(plan_sdf, run_sdf, _manifests, data=True),
    "decoder": Step(plan_decoder, run_decoder, lambda planned: [Path(planned["decoder"].out) / "decoder.pt"], True),
    "scenes": Step(plan_scenes, run_scenes, _manifests, data=True),
    "encoder": Step(plan_encoder, run_encoder, lambda planned: [Path(planned["encoder"].out) / "encoder.pt"], True),
    "evaluation": Step(
        plan_evaluation, run_evaluation, lambda planned: [Path(c.out) / "report.json" for c in planned.values()]
    ),
}


def step_folders(name: str, p: Paths) -> list[Path]:
    """Where a step writes (to tell a step that never started from one that did)."""
    return {"objects": [p.objects, p.test_objects], "scenes": [p.out / "scenes", p.split]}.get(name, [p.out / name])
