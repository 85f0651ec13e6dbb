"""``centerart eval scenes``: predicted grasps executed in physics on held-out scenes (EVALUATION.md).

Per scene (parallel over scenes, each a job): load the description, generate ground-truth grasp labels of every
object at its exact state (the label generator, cached), rebuild the scene in pybullet, then for every view and
depth mode run each method and execute its grasps (:mod:`centerart.evaluation.scene_rows`). Methods: the learned
predictor (``centerart``, plus ``centerart+icp`` / ``centerart+sdf`` when asked), the ``oracle`` (a label, executed)
and the geometric ``baseline``.

On disk (OUT)::

    records/<set>/<scene>.json   every row and image record of one scene (atomic; a rerun skips it: resume)
    labels/<set>/<scene>/objK.npz ground-truth labels at the scene's state (object frame; cached)
    testset.json                 which objects (fingerprints) and states the test sets hold
    settings.json                what a record depends on (checkpoints, methods, depth modes, seed): a rerun
                                 with other settings into the same OUT is refused
    report.json, report.md       written by :mod:`centerart.evaluation.scene_report`

A kill loses at most the scenes in flight; rerunning the command resumes, and since every trial is deterministic
the final report equals an uninterrupted run's (latency figures aside).
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from centerart.errors import CenterArtError
from centerart.utils.atomic import atomic_write_json
from centerart.utils.checks import at_least
from centerart.utils.folders import check_output_folder
from centerart.utils.torch_cpu import use_cpu_threads

REFINE_METHODS = {"none": "centerart", "icp": "centerart+icp", "sdf": "centerart+sdf"}
#: Grasp settings of the learned method (``inference.grasp_anchoring.LADDER``); ``full`` is the predictor's default.
GraspSetting = Literal["proposal", "checks", "snap", "square", "observed", "handle", "full", "pose"]


def method_name(refine: str, grasps: str) -> str:
    """The learned method's name in records and reports: ``centerart`` (+ refinement) with the grasp setting in
    brackets unless it is the default (``full``)."""
    return REFINE_METHODS[refine] + ("" if grasps == "full" else f"[{grasps}]")


@dataclass
class EvalScenesConfig:
    """Closed-loop evaluation: predict on held-out scenes, execute the top grasps in physics, write a report."""

    scenes: tuple[Path, ...]
    """Scene folders (``centerart scenes generate`` outputs) of objects no model was trained on."""
    out: Path
    """Output folder (created). Finished scenes already there are kept and skipped (resume)."""
    encoder: Path | None = None
    """Encoder checkpoint (default: the shipped one)."""
    decoder: Path | None = None
    """Decoder checkpoint (default: the shipped one)."""
    depth: tuple[Literal["true", "realistic"], ...] = ("true", "realistic")
    """Depth modes: rendered true depth, and the realistic (stereo) depth the scenes were made with."""
    refine: tuple[Literal["none", "icp", "sdf"], ...] = ("none",)
    """Refinement settings of the learned method, each a row (sdf costs about 20 s per image on CPU)."""
    grasps: tuple[GraspSetting, ...] = ("full",)
    """Grasp settings of the learned method, each a row: ``full`` (the default: grasps made on, snapped to, checked
    against and ranked on the observed points), ``proposal`` (the decoder's grasps alone), a step between, or
    ``pose`` (``full`` after the pose is corrected from the depth, with the camera's true gravity as a robot has it
    from TF) (``inference.grasp_anchoring.LADDER``)."""
    shape_prior: Literal["regressed", "nearest", "best_fit"] = "regressed"
    """The predictor's shape code: the encoder's regression, or snapped to a decoder training code
    (``inference.shape_prior``)."""
    oracle: bool = True
    """Reference row: a ground-truth label of each object, executed in the scene."""
    baseline: bool = True
    """Reference row: grasp the handle found in the object's depth points inside its true mask."""
    shape: bool = True
    """Chamfer / F-score of each matched object's decoded mesh (the slowest part: a mesh per object)."""
    ablation: bool = True
    """Stage analysis: re-run grasps with the true pose and joint state swapped in."""
    code_oracle: bool = True
    """Stage analysis: where the true pose still fails, also swap in a shape code fitted to the object's true surface
    (``evaluation.code_oracle``: about 4 s per object on one core), which tells the encoder's shape code from the
    decoder's grasps."""
    labels_per_state: int = 100
    """Ground-truth labels generated per object at its test state (RSR and the oracle)."""
    label_max_trials: int = 400
    """Physics trials per object at most while making those labels."""
    max_scenes: int | None = None
    """Evaluate only the first N scenes of each folder."""
    workers: int = 1
    """Parallel processes (each loads the models once)."""
    threads: int = 1
    """torch threads per process."""
    seed: int = 0
    """Seed of the label generator and the baseline's RANSAC (every trial is deterministic)."""
    progress: bool = True
    """Show a progress bar."""
    allow_training_objects: bool = False
    """Diagnostics only: evaluate scenes of objects the models were trained on (an upper bound, not a held-out
    result). The report then says so at its top and lists the shared objects."""

    def __post_init__(self):
        for name in ("labels_per_state", "label_max_trials", "workers", "threads"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 1)
        at_least("--max-scenes", self.max_scenes, 1, allow_none=True)


def set_key(folder: Path) -> str:
    """A test set's name in records: its folder name plus a short hash of its absolute path."""
    folder = Path(folder).resolve()
    return f"{folder.name}-{hashlib.sha256(str(folder).encode()).hexdigest()[:8]}"


def list_scene_dirs(folder: Path, limit: int | None) -> list[Path]:
    folder = Path(folder)
    if not folder.is_dir():
        raise CenterArtError(f"{folder}: no such scenes folder")
    dirs = sorted(p for p in folder.glob("scene_*") if (p / "scene.json").is_file())
    if not dirs:
        raise CenterArtError(f"{folder}: no scenes (expected scene_*/scene.json, from centerart scenes generate)")
    return dirs[:limit] if limit else dirs


# ---------------------------------------------------------------------------- per-process models
_PREDICTORS: dict = {}


def predictor_for(cfg: dict, refine: str, grasps: str = "full"):
    """The predictor of one refinement and grasp setting, loaded once per process."""
    from centerart.inference.grasp_anchoring import ladder_predictor_settings
    from centerart.inference.predictor import Predictor, PredictorConfig
    from centerart.inference.refinement import RefineConfig, SdfRefineConfig

    key = (cfg["encoder"], cfg["decoder"], refine, grasps, cfg["shape_prior"])
    if key not in _PREDICTORS:
        config = PredictorConfig(
            refine=RefineConfig(icp=refine == "icp"),
            refine_sdf=SdfRefineConfig(enabled=refine == "sdf"),
            shape_prior=cfg["shape_prior"],
            **ladder_predictor_settings(grasps),
        )
        _PREDICTORS[key] = Predictor(cfg["encoder"], cfg["decoder"], config=config)
    return _PREDICTORS[key]


# ---------------------------------------------------------------------------- labels at the test state
def state_labels(obj, q: float, cache: Path, cfg: dict, seed_key: str) -> np.ndarray:
    """(L, 4, 4) ground-truth TCP labels (object frame) of ``obj`` at state ``q``, generated once and cached."""
    from centerart.grasps.labels import StateLabels

    if not cache.is_file():
        _generate_state_labels(obj, q, cache, cfg, seed_key)
    # Read back also right after generating: the file holds float32, and a resumed run must use exactly what an
    # uninterrupted one did.
    return StateLabels.load(cache).poses


def _generate_state_labels(obj, q: float, cache: Path, cfg: dict, seed_key: str) -> None:
    from centerart.grasps.generate import GenerateGraspsConfig, label_joint_state
    from centerart.grasps.labels import LABEL_SHAPES
    from centerart.utils.npz_records import save_record
    from centerart.utils.seeding import item_rng

    gcfg = GenerateGraspsConfig(
        objects=Path(obj.path), out=cache.parent, per_state=cfg["labels_per_state"],
        max_trials=cfg["label_max_trials"], max_candidates=8 * cfg["label_max_trials"], keep_failures=0,
    )  # fmt: skip
    labels, _ = label_joint_state(obj, q, item_rng(cfg["seed"], seed_key), gcfg)
    save_record(cache, labels, compressed=True, shapes=LABEL_SHAPES)


def scene_context(scene_dir: Path, labels_dir: Path, cfg: dict):
    """Scene description, objects, labels at each object's state (world frame) and the physics world."""
    from centerart.evaluation.physics_scene import build_physics_scene
    from centerart.evaluation.scene_rows import SceneContext
    from centerart.scenes.description import SceneDescription, load_scene_object

    scene = SceneDescription.load(scene_dir / "scene.json")
    objects = [load_scene_object(spec) for spec in scene.objects]
    labels_world = []
    for k, (spec, obj) in enumerate(zip(scene.objects, objects, strict=True)):
        cache = labels_dir / scene_dir.name / f"{spec.name}.npz"
        poses = state_labels(obj, spec.joint_state, cache, cfg, f"{scene.scene_id}/{spec.name}")
        labels_world.append(scene.object_pose(k) @ poses if len(poses) else np.zeros((0, 4, 4)))
    phys = build_physics_scene(scene, objects)
    return scene, SceneContext(phys, labels_world, code_oracle=bool(cfg["ablation"] and cfg.get("code_oracle")))


def view_inputs(scene_dir: Path, depth_modes) -> list:
    from centerart.evaluation.scene_rows import ViewInput
    from centerart.scenes.dataset import load_view

    out = []
    for view_dir in sorted((scene_dir / "views").iterdir()):
        if not (view_dir / "labels.json").is_file():
            continue
        v = load_view(view_dir)
        for mode in depth_modes:
            depth = v.depth_true if mode == "true" else v.depth_realistic
            if depth is None:
                continue
            out.append(ViewInput(scene_dir.name, int(view_dir.name), mode, v.rgb, depth, v.instances, v.labels))
    return out


def evaluate_scene(scene_dir: Path, labels_dir: Path, cfg: dict) -> dict:
    """Every row and image record of one scene (see the module docstring)."""
    from centerart.evaluation.scene_rows import baseline_rows, learned_rows, oracle_rows

    started = time.perf_counter()
    scene, ctx = scene_context(scene_dir, labels_dir, cfg)
    rows, images = [], []
    try:
        for v in view_inputs(scene_dir, cfg["depth"]):
            first = predictor_for(cfg, cfg["refine"][0], cfg.get("grasps", ("full",))[0])
            encoded = first.encode(v.rgb, v.depth, v.K)  # one encoder pass per image, shared by every setting
            for refine in cfg["refine"]:
                for grasps in cfg.get("grasps", ("full",)):
                    ablation = cfg["ablation"] and refine == cfg["refine"][0]
                    predictor, method = predictor_for(cfg, refine, grasps), method_name(refine, grasps)
                    r, image = learned_rows(ctx, v, predictor, method, cfg["shape"], ablation, encoded)
                    rows += r
                    images.append(image)
            if cfg["baseline"]:
                rows += baseline_rows(ctx, v, cfg["seed"])
            if cfg["oracle"]:
                rows += oracle_rows(ctx, v)
    finally:
        ctx.phys.close()
    labels_count = {s.name: len(lw) for s, lw in zip(scene.objects, ctx.labels_world, strict=True)}
    return {
        "scene": scene_dir.name,
        "layout": scene.layout,
        "rows": rows,
        "images": images,
        "labels_per_object": labels_count,
        "seconds": round(time.perf_counter() - started, 2),
    }


def _scene_job(job: tuple[str, str, str, dict]) -> dict:
    set_name, scene_dir, out, cfg = job
    use_cpu_threads(max(1, cfg["threads"]))
    record_path = Path(out) / "records" / set_name / f"{Path(scene_dir).name}.json"
    if record_path.is_file():
        return {"skipped": True}
    record = evaluate_scene(Path(scene_dir), Path(out) / "labels" / set_name, cfg)
    record["set"] = set_name
    atomic_write_json(record_path, record)
    return {"skipped": False, "seconds": record["seconds"]}


def job_config(cfg: EvalScenesConfig) -> dict:
    from centerart.models.checkpoint import default_checkpoint
    from centerart.models.encoder.checkpoint import default_encoder

    d = json.loads(json.dumps(asdict(cfg), default=str))
    d["encoder"] = str(Path(cfg.encoder) if cfg.encoder else default_encoder())
    d["decoder"] = str(Path(cfg.decoder) if cfg.decoder else default_checkpoint())
    return d


#: Settings that change what a scene record holds; a rerun into the same --out must keep them.
RECORD_SETTINGS = ("encoder", "decoder", "depth", "refine", "grasps", "shape_prior", "oracle", "baseline", "shape",
                   "ablation", "code_oracle", "labels_per_state", "label_max_trials", "seed")  # fmt: skip


def check_same_settings(out: Path, jc: dict) -> None:
    """Refuse to resume into ``out`` with settings that would mix records of two different evaluations."""
    from centerart.models.checkpoint_files import file_sha256
    from centerart.models.grasp_critic import critic_record

    settings = {k: jc[k] for k in RECORD_SETTINGS}
    settings["checkpoint_sha256"] = [file_sha256(Path(jc["encoder"])), file_sha256(Path(jc["decoder"]))]
    settings["grasp_critic"] = critic_record(Path(jc["decoder"]))  # it ranks the grasps: part of what is measured
    settings["anchor_critic"] = critic_record(Path(jc["decoder"]), "anchor_critic")  # ranks anchored grasps too
    path = out / "settings.json"
    if path.is_file():
        before = json.loads(path.read_text())
        changed = sorted(k for k in settings if before.get(k) != json.loads(json.dumps(settings[k])))
        if changed:
            raise CenterArtError(
                f"{out}: holds an evaluation made with other settings ({', '.join(changed)}); "
                "use another --out, or delete the folder to start over"
            )
    atomic_write_json(path, settings)


def evaluate_scenes(cfg: EvalScenesConfig) -> dict:
    """Run (or resume) the evaluation and write ``report.json`` / ``report.md``; returns the report."""
    from centerart.evaluation.scene_report import write_report
    from centerart.evaluation.testset import check_test_sets
    from centerart.utils.parallel import parallel_map

    if not cfg.scenes:
        raise CenterArtError("--scenes: give at least one scenes folder")
    jc = job_config(cfg)
    out = check_output_folder(cfg.out)
    sets = {set_key(f): list_scene_dirs(f, cfg.max_scenes) for f in cfg.scenes}
    testset = check_test_sets(cfg.scenes, sets, Path(jc["encoder"]), Path(jc["decoder"]), cfg.allow_training_objects)
    out.mkdir(parents=True, exist_ok=True)
    check_same_settings(out, jc)
    atomic_write_json(out / "testset.json", testset)
    jobs = [(name, str(d), str(out), jc) for name, dirs in sets.items() for d in dirs]
    started = time.perf_counter()
    done = list(parallel_map(_scene_job, jobs, cfg.workers, "scenes", disable_progress=not cfg.progress))
    run = {"wall_seconds_this_run": round(time.perf_counter() - started, 1), "scenes_this_run": sum(
        not d["skipped"] for d in done)}  # fmt: skip
    return write_report(out, jc, sets, testset, run)
