"""``centerart eval decoder``: shape and grasp quality of a decoder checkpoint, per split.

Groups (from the split stored in the checkpoint):

- ``train``: training objects at their training states (trained codes);
- ``heldout_state``: training objects at held-out joint states (trained codes, unseen joint codes);
- ``heldout_object``: objects without a trained code (held out in training, or any other object in --data, also
  one that shares an id but not its content with a training object: :func:`trained_object_ids`);
  their code is fitted to all their SDF samples with the decoder frozen (``models/code_fitting.py``).

Per (object, state), in the object's canonical frame:

- shape: the coarse-to-fine mesh at the state's normalized joint code against
  ``ArticulatedObject.watertight_mesh(q)``: Chamfer-L1 in mm (mean of both directions, ``SURFACE_SAMPLES``
  surface samples each) and F-score at ``FSCORE_THRESHOLD``;
- grasps (with --grasps): precision@k = share of the top-k predictions within ``GRASP_MATCH_DISTANCE`` (TCP
  position) and ``GRASP_MATCH_ANGLE_DEG`` (rotation, finger-swapped gripper counted as equal) of some label;
  coverage = share of labels matched by some returned prediction (all ranked grasps, up to ``top_k_coverage``);
- physics (with --physics, default on): the top-1 and the top-5 predictions executed one by one with the
  grasp-label simulator (``grasps/executor.py``: same gripper, forces and success rule as the labels; no
  denominator trimming: a missing prediction counts as a failure). top-1 success = the first grasp succeeds;
  top-5 success = mean over the 5 slots (missing slots fail); any-of-5 = at least one succeeds. The same rows per
  state kind (``closed`` = lower joint limit, ``open`` = upper limit, ``interior``), and the calibration of the
  grasps' confidence scores against their physics outcomes (``metrics.score_calibration``: reliability table,
  expected calibration error, Brier score, ROC AUC), per group and over all executed grasps.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
from tqdm import tqdm

from centerart.errors import CenterArtError
from centerart.evaluation.metrics import (
    CALIBRATION_BINS,
    GRASP_MATCH_ANGLE_DEG,
    grasp_matches,
    score_calibration,
)
from centerart.evaluation.metrics import (
    CHAMFER_SAMPLES as SURFACE_SAMPLES,
)
from centerart.evaluation.metrics import (
    FSCORE_THRESHOLD_M as FSCORE_THRESHOLD,
)
from centerart.evaluation.metrics import (
    GRASP_MATCH_POSITION_M as GRASP_MATCH_DISTANCE,
)
from centerart.utils.checks import at_least

GROUPS = ("train", "heldout_state", "heldout_object")
STATE_KINDS = ("closed", "interior", "open")


@dataclass
class EvalDecoderConfig:
    data: Path
    """SDF sample folder the checkpoint was trained on (or any SDF folder of other objects)."""
    objects: Path
    """Object folders (for the true meshes at each state)."""
    out: Path = Path("decoder_eval")
    """Output folder: report.json and plots."""
    checkpoint: Path | None = None
    """Decoder checkpoint (default: the shipped small checkpoint)."""
    grasps: Path | None = None
    """Grasp-label folder (``centerart grasps generate`` output) for precision/coverage."""
    physics: bool = True
    """Execute the top-1/top-5 predicted grasps in pybullet (needs --grasps only for the metrics above)."""
    states_per_object: int = 3
    """Evaluate at most this many states per (object, group), evenly chosen."""
    top_k: int = 5
    top_k_coverage: int = 20
    resolution: int = 128
    code_fit_steps: int = 200
    code_fit_dropout: bool = False
    """Fit each object's code under the decoder's dropout (``CodeFitConfig.dropout``), as a run with dropout
    learned its training codes; off, the fit sees the deterministic decoder (as the slices' held-out figures)."""
    seed: int = 0
    max_objects: int | None = None
    grasp_critic: bool = True
    """Rank grasps by the checkpoint's grasp critic (``models.grasp_critic``) where it has one."""
    grasp_extraction: Literal["default", "shell", "before"] = "default"
    """Grasp extraction setting (``inference.decoder_grasps.extraction_setting``): default; shell (no clearance
    check); before (neither shell points nor clearance check), for A/B measurements."""

    def __post_init__(self):
        for name in ("states_per_object", "top_k", "top_k_coverage"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 1)
        at_least("--resolution", self.resolution, 8)
        at_least("--code-fit-steps", self.code_fit_steps, 0)
        at_least("--max-objects", self.max_objects, 1, allow_none=True)


# --------------------------------------------------------------------------------------- metric functions
def chamfer_fscore(pred, true, n: int = SURFACE_SAMPLES, threshold: float = FSCORE_THRESHOLD, seed: int = 0):
    """(Chamfer-L1 in mm, F-score) between two meshes (``evaluation.metrics.shape_metrics``: samples of each
    surface measured to the other surface); an empty prediction gives (inf, 0)."""
    from centerart.evaluation.metrics import shape_metrics

    if len(pred.faces) == 0:
        return float("inf"), 0.0
    m = shape_metrics(pred, true, n, threshold, seed)
    return float(m.chamfer_l1_mm), float(m.fscore)


# --------------------------------------------------------------------------------------- evaluation
@dataclass
class StateResult:
    object_id: str
    state_index: int
    group: str
    joint: float
    chamfer_mm: float
    fscore: float
    seconds_mesh_grasps: float
    num_grasps: int
    precision_at_k: float | None = None
    coverage: float | None = None
    physics_top1: float | None = None
    physics_top5: float | None = None
    physics_any5: float | None = None
    grasp_scores: list[float] = field(default_factory=list)
    """Confidence of each executed grasp (the top 5, best first)."""
    grasp_successes: list[bool] = field(default_factory=list)
    """Physics outcome of each executed grasp, aligned with ``grasp_scores``."""
    extra: dict = field(default_factory=dict)

    @property
    def state_kind(self) -> str:
        """``closed`` (normalized joint 0: the lower limit), ``open`` (1: the upper limit) or ``interior``."""
        return "closed" if self.joint <= 1e-6 else "open" if self.joint >= 1.0 - 1e-6 else "interior"


def _select(indices: list[int], k: int) -> list[int]:
    if len(indices) <= k:
        return indices
    return [indices[i] for i in np.linspace(0, len(indices) - 1, k).round().astype(int)]


def execute_grasps(obj, q: float, poses: np.ndarray, k: int) -> list[bool]:
    """Execute up to k TCP poses (object frame = world frame here) on the object at state q."""
    return [bool(r.success) for r in execute_grasp_results(obj, q, poses[:k])]


def execute_grasp_results(obj, q: float, poses) -> list:
    """Each TCP pose (object frame = world frame here) executed on the object at state q, in one physics world:
    its ``grasps.executor.GraspResult`` (success, displacement, abort reason)."""
    import pybullet as pb

    from centerart.grasps import executor as ex
    from centerart.grasps.sim_world import connect, spawn_object_in_pybullet

    client = connect()
    try:
        target = spawn_object_in_pybullet(client, obj, q)
        executor = ex.GraspExecutor(client)
        direction = ex.commanded_direction(obj.joint_type, q, obj.joint_range[1])
        return [executor.execute(p, target, direction) for p in poses]
    finally:
        pb.disconnect(client)


def evaluate_decoder(cfg: EvalDecoderConfig) -> dict:
    """Evaluate a checkpoint per group (see the module doc); writes ``report.json`` to ``cfg.out`` and returns
    the report (``viz.decoder_eval_plots`` draws it)."""
    from centerart.inference.decoder_grasps import extraction_setting
    from centerart.inference.reconstruction import MeshConfig
    from centerart.models.checkpoint import load_decoder
    from centerart.sdf.samples import load_states
    from centerart.utils.atomic import atomic_write_json
    from centerart.utils.folders import check_output_folder

    check_output_folder(cfg.out)  # before minutes of evaluation, not after
    loaded = load_decoder(cfg.checkpoint)
    states = load_states(cfg.data, 30000, cfg.seed, progress=False)
    by_obj: dict[str, list] = {}
    for s in states:
        by_obj.setdefault(s.object_id, []).append(s)
    mesh_cfg = MeshConfig(resolution=cfg.resolution)
    grasp_cfg = extraction_setting(cfg.grasp_extraction, top_k=max(cfg.top_k, cfg.top_k_coverage))
    results: list[StateResult] = []
    codes: dict[str, np.ndarray] = {}
    trained = trained_object_ids(loaded, Path(cfg.objects), sorted(by_obj))
    for oid, g, k in tqdm(_jobs(loaded, by_obj, trained, cfg), desc="eval decoder"):
        obj_folder = Path(cfg.objects) / oid
        if not obj_folder.is_dir():
            raise CenterArtError(f"{obj_folder}: object folder missing (needed for the true mesh of {oid})")
        if oid not in codes:
            codes[oid] = _object_code(loaded, oid, oid in trained, by_obj[oid], cfg)
        st = next(s for s in by_obj[oid] if s.state_index == k)
        results.append(_evaluate_state(loaded, codes[oid], obj_folder, st, g, cfg, mesh_cfg, grasp_cfg))
    report = _report(cfg, loaded, results)
    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "report.json", report)
    return report


def trained_object_ids(loaded, objects: Path, object_ids: list[str]) -> set[str]:
    """The ids among ``object_ids`` whose trained code belongs to this very object: the checkpoint has a code of
    that id and, where it recorded the object's content fingerprint, the folder ``objects/<id>`` has the same one.
    Ids are not identities (seed-0 and seed-9000 ``oven_0003`` are different objects): without this check a test
    object would be decoded with the code of its namesake. An id without a recorded fingerprint is trusted."""
    from centerart.assets.fingerprint import object_fingerprint
    from centerart.evaluation.heldout import checkpoint_training_objects

    recorded = {oid: fp for fp, oid in checkpoint_training_objects(loaded.path, "decoder").fingerprints.items()}
    trained = set()
    for oid in object_ids:
        if oid in loaded.codes and (oid not in recorded or object_fingerprint(objects / oid) == recorded[oid]):
            trained.add(oid)
    return trained


def _jobs(loaded, by_obj: dict[str, list], trained_ids: set[str], cfg: EvalDecoderConfig) -> list[tuple[str, str, int]]:
    """(object id, group, state index) to evaluate: at most ``states_per_object`` per (object, group)."""
    from centerart.training.decoder_data import DecoderSplit

    split = DecoderSplit.from_dict(loaded.meta["split"]) if loaded.meta.get("split") else None
    objects = sorted(by_obj)[: cfg.max_objects] if cfg.max_objects else sorted(by_obj)
    jobs = []
    for oid in objects:
        trained = oid in trained_ids
        groups: dict[str, list[int]] = {}
        for s in by_obj[oid]:
            if not trained:
                g = "heldout_object"
            elif split is not None and s.state_index in split.heldout_states.get(oid, []):
                g = "heldout_state"
            else:
                g = "train"
            groups.setdefault(g, []).append(s.state_index)
        for g, idx in groups.items():
            jobs.extend((oid, g, k) for k in _select(sorted(idx), cfg.states_per_object))
    return jobs


def _object_code(loaded, oid: str, trained: bool, states: list, cfg: EvalDecoderConfig) -> np.ndarray:
    """The trained shape code, or one fitted to all the object's SDF samples with the decoder frozen."""
    if trained:
        return loaded.code(oid)
    return fitted_code(loaded, states, cfg.code_fit_steps, cfg.seed, dropout=cfg.code_fit_dropout)


def fitted_code(
    loaded, states: list, steps: int, seed: int, points_per_step: int = 4096, dropout: bool = False
) -> np.ndarray:
    """A shape code fitted to all of one object's SDF samples (each with ``joint``, ``points``, ``sdf`` as
    ``sdf.samples.StateData``), the decoder of ``loaded`` (a ``LoadedDecoder``) frozen, under the code prior it was
    trained with (and, with ``dropout``, under the decoder's dropout: ``CodeFitConfig.dropout``)."""
    from centerart.models.code_fitting import CodeFitConfig, Observations, fit_code

    obs = Observations.from_states(states)
    cfg = CodeFitConfig(
        steps=steps, points_per_step=points_per_step, code_weight=loaded.code_weight, seed=seed, dropout=dropout
    )
    return fit_code(loaded.decoder, obs, cfg)[0]


def _evaluate_state(loaded, code, obj_folder: Path, st, group: str, cfg, mesh_cfg, grasp_cfg) -> StateResult:
    """Shape, grasp-label and physics metrics of one (object, state) (see the module doc)."""
    from centerart.assets.articulated_object import ArticulatedObject
    from centerart.inference.decoder_grasps import predict_shape_and_grasps

    obj = ArticulatedObject.load(obj_folder)
    q = obj.denormalize(st.joint)
    t0 = time.perf_counter()
    critic = loaded.critic if cfg.grasp_critic else None
    recon, grasps = predict_shape_and_grasps(
        loaded.decoder, code, st.joint, loaded.bounds, mesh_cfg, grasp_cfg, critic=critic
    )
    seconds = time.perf_counter() - t0
    cd, fs = chamfer_fscore(recon.mesh, obj.watertight_mesh(q), seed=cfg.seed)
    r = StateResult(st.object_id, st.state_index, group, st.joint, cd, fs, seconds, len(grasps))
    r.extra["evaluated_points"] = recon.stats["evaluated_points"]
    if cfg.grasps is not None:
        _label_metrics(r, grasps.poses, cfg)
    if cfg.physics:
        ok = execute_grasps(obj, q, grasps.poses, 5)
        r.grasp_scores, r.grasp_successes = [float(x) for x in grasps.scores[: len(ok)]], ok
        ok = ok + [False] * (5 - len(ok))
        r.physics_top1, r.physics_top5, r.physics_any5 = float(ok[0]), float(np.mean(ok)), float(any(ok))
    return r


def _label_metrics(r: StateResult, poses: np.ndarray, cfg: EvalDecoderConfig) -> None:
    """Precision@k and coverage of ranked TCP poses (object frame) against the state's labels, when it has any."""
    from centerart.grasps.labels import StateLabels, state_path

    lp = state_path(cfg.grasps, r.object_id, r.state_index)
    if not lp.is_file():
        return
    lab = StateLabels.load(lp)
    if lab.count:
        topk = poses[: cfg.top_k]
        m = grasp_matches(poses, lab.poses.astype(np.float64))
        r.precision_at_k = float(m[: cfg.top_k].any(1).sum() / cfg.top_k) if len(topk) else 0.0
        r.coverage = float(m.any(0).mean()) if len(m) else 0.0
        r.extra["labels"] = lab.count


def _summary(results: list[StateResult]) -> dict:
    """Per group: counts, the mean (and the Chamfer median) of every metric over its states, the same per state
    kind, and the calibration of the executed grasps' scores; ``all`` pools the groups' calibration."""
    summary = {}
    for g in GROUPS:
        rs = [r for r in results if r.group == g]
        if not rs:
            continue
        row = _metric_row(rs)
        row["by_state_kind"] = {k: _metric_row(ks) for k in STATE_KINDS if (ks := [r for r in rs if r.state_kind == k])}
        row["calibration"] = _calibration(rs)
        summary[g] = row
    if results:
        summary["calibration_all_groups"] = _calibration(results)
    return summary


def _metric_row(rs: list[StateResult]) -> dict:
    row = {
        "states": len(rs),
        "objects": len({r.object_id for r in rs}),
        # no zero crossing predicted: Chamfer is undefined (left out of its mean), F-score counts as 0
        "empty_meshes": sum(not np.isfinite(r.chamfer_mm) for r in rs),
    }
    for key in (
        "chamfer_mm",
        "fscore",
        "precision_at_k",
        "coverage",
        "physics_top1",
        "physics_top5",
        "physics_any5",
        "seconds_mesh_grasps",
    ):
        vals = [getattr(r, key) for r in rs if getattr(r, key) is not None and np.isfinite(getattr(r, key))]
        if vals:
            row[key] = float(np.mean(vals))
            if key == "chamfer_mm":
                row["chamfer_mm_median"] = float(np.median(vals))
    return row


def _calibration(rs: list[StateResult]) -> dict:
    scores = [x for r in rs for x in r.grasp_scores]
    return score_calibration(np.asarray(scores, float), np.asarray([x for r in rs for x in r.grasp_successes], bool))


def _report(cfg: EvalDecoderConfig, loaded, results: list[StateResult]) -> dict:
    from centerart.utils.manifest import code_version

    return {
        "checkpoint": str(loaded.path),
        "config": {k: str(v) if isinstance(v, Path) else v for k, v in asdict(cfg).items()},
        "thresholds": {
            "fscore_m": FSCORE_THRESHOLD,
            "surface_samples": SURFACE_SAMPLES,
            "grasp_match_distance_m": GRASP_MATCH_DISTANCE,
            "grasp_match_angle_deg": GRASP_MATCH_ANGLE_DEG,
            "top_k": cfg.top_k,
            "calibration_bins": CALIBRATION_BINS,
        },
        "summary": _summary(results),
        "states": [asdict(r) for r in results],
        "code_version": code_version(),
    }
