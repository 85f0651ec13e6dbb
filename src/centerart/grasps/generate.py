"""Generate physics-verified grasp labels for every (object, joint state): parallel, resumable, with a manifest.

On-disk layout (the label file format is :mod:`centerart.grasps.labels`)::

    LABELS/manifest.json                 config, seed, code version, protocol constants, counts per category
    LABELS/<object_id>/state_<k:02d>.npz   successes (poses, displacement) and failed trials (negatives)
    LABELS/<object_id>/state_<k:02d>.json  statistics of that item (trials, pre-filtered, aborts, seconds)

Per (object, state k): the target joint is set to the k-th of ``states`` evenly spaced values over its range
(closed to fully open); candidates (:mod:`~centerart.grasps.candidates`) are drawn with a generator seeded by
(seed, object id, k), pre-filtered for hand collisions at the pre-grasp and grasp poses, and executed
(:mod:`~centerart.grasps.executor`) until ``per_state`` successes, ``max_trials`` executed trials or
``max_candidates`` drawn candidates. An item depends only on (seed, object, k, config), never on the number of
workers or on which items already exist, so an interrupted run that is restarted gives the same files.
"""

from __future__ import annotations

import json
import time
from collections import Counter
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.dataset import list_objects
from centerart.geometry.transforms import make_pose
from centerart.grasps import executor as ex
from centerart.grasps.candidates import CandidateSampler
from centerart.grasps.labels import StateLabels, state_path
from centerart.utils.atomic import atomic_write_json, remove_stale_temporaries
from centerart.utils.checks import at_least, workers
from centerart.utils.folders import check_output_folder, output_folder
from centerart.utils.manifest import merge_manifest
from centerart.utils.parallel import parallel_map
from centerart.utils.seeding import item_rng

CANDIDATE_BATCH = 128
PREFILTER_TOL = 0.0005  # m of contact depth tolerated by the grasp-pose pre-filter (touching is fine)


@dataclass
class GenerateGraspsConfig:
    """Generate physics-verified grasp labels on the movable part of every object at several joint states."""

    objects: Path
    """Folder of object folders (generated or real PartNet-Mobility), or one object folder."""
    out: Path
    """Output folder (created). Finished (object, state) items are kept and skipped (resume)."""
    states: int = 10
    """Joint states per object, evenly spaced from closed (lower limit) to fully open (upper limit)."""
    per_state: int = 500
    """Stop an (object, state) after this many successful grasps."""
    max_trials: int = 3000
    """... or after this many executed physics trials."""
    max_candidates: int = 12000
    """... or after this many drawn candidates (pre-filtered ones included)."""
    keep_failures: int = 2000
    """Failed trials stored per state as negatives (the first ones, in trial order)."""
    seed: int = 0
    """Global seed: item (object, k) depends only on (seed, object id, k)."""
    workers: int | None = None
    """Parallel worker processes (default: all cores)."""
    ray_address: str | None = None
    """Run on a Ray cluster at this address instead of a local process pool; ``local`` starts a Ray instance on
    this machine with ``workers`` CPUs."""

    def __post_init__(self):
        for name in ("states", "per_state", "max_trials", "max_candidates"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 1)
        at_least("--keep-failures", self.keep_failures, 0)
        workers("--workers", self.workers)


def state_values(obj: ArticulatedObject, n: int) -> np.ndarray:
    """``n`` target-joint values (metric) evenly spaced from the lower to the upper limit (``n = 1``: lower)."""
    lo, hi = obj.joint_range
    return np.linspace(lo, hi, n) if n > 1 else np.array([lo])


def label_state(obj: ArticulatedObject, k: int, cfg: GenerateGraspsConfig) -> tuple[StateLabels, dict]:
    """Labels and statistics of object ``obj`` at state index ``k`` (see the module docstring)."""
    q = float(state_values(obj, cfg.states)[k])
    return label_joint_state(obj, q, item_rng(cfg.seed, obj.object_id, k), cfg, state_index=k)


def label_joint_state(
    obj: ArticulatedObject, q: float, rng: np.random.Generator, cfg: GenerateGraspsConfig, state_index: int = -1
) -> tuple[StateLabels, dict]:
    """Labels and statistics of ``obj`` at joint state ``q`` (metric), candidates from ``rng``, budgets from ``cfg``;
    the evaluation calls it at a test scene's exact state (``state_index`` -1: not one of the grid's)."""
    import pybullet as pb

    from centerart.grasps.sim_world import connect, spawn_object_in_pybullet

    started, cpu_started = time.perf_counter(), time.process_time()
    client = connect()
    try:
        target = spawn_object_in_pybullet(client, obj, q)
        executor = ex.GraspExecutor(client)
        direction = ex.commanded_direction(obj.joint_type, q, obj.joint_range[1])
        sampler = CandidateSampler(obj, q, rng)
        back = make_pose(translation=[0.0, 0.0, -ex.APPROACH_DISTANCE])
        ok_poses, ok_disp, bad_poses, bad_disp = [], [], [], []
        outcomes, sources_ok = Counter(), Counter()
        drawn = trials = 0
        sim_seconds = 0.0
        while len(ok_poses) < cfg.per_state and trials < cfg.max_trials and drawn < cfg.max_candidates:
            poses, sources = sampler.sample(CANDIDATE_BATCH)
            if len(poses) == 0:
                break
            for pose, source in zip(poses, sources, strict=True):
                if len(ok_poses) >= cfg.per_state or trials >= cfg.max_trials or drawn >= cfg.max_candidates:
                    break
                drawn += 1
                if executor.hand_collides(pose, tol=PREFILTER_TOL) or executor.hand_collides(pose @ back):
                    outcomes["prefiltered"] += 1
                    continue
                t0 = time.perf_counter()
                result = executor.execute(pose, target, direction)
                sim_seconds += time.perf_counter() - t0
                trials += 1
                if result.success:
                    ok_poses.append(pose)
                    ok_disp.append(result.displacement)
                    outcomes["success"] += 1
                    sources_ok[source] += 1
                else:
                    outcomes[result.abort or "too_little_motion"] += 1
                    if len(bad_poses) < cfg.keep_failures:
                        bad_poses.append(pose)
                        bad_disp.append(result.displacement)
    finally:
        pb.disconnect(client)
    labels = StateLabels(
        object_id=obj.object_id,
        state_index=state_index,
        q=q,
        q_normalized=float(obj.normalize(q)),
        joint_type=obj.joint_type,
        direction=direction,
        poses=np.asarray(ok_poses).reshape(-1, 4, 4),
        displacement=np.asarray(ok_disp),
        failed_poses=np.asarray(bad_poses).reshape(-1, 4, 4),
        failed_displacement=np.asarray(bad_disp),
    )
    approach = labels.poses[:, :3, 2] if labels.count else np.zeros((0, 3))
    stats = {
        "object_id": obj.object_id,
        "category": obj.category,
        "state_index": state_index,
        "q": q,
        "joint_type": obj.joint_type,
        "direction": direction,
        "successes": labels.count,
        "trials": trials,
        "candidates": drawn,
        "outcomes": dict(sorted(outcomes.items())),
        "successes_by_source": dict(sorted(sources_ok.items())),
        "edge_sites": len(sampler.sites),
        "approach_spread_deg": approach_spread_deg(approach),
        "seconds": round(time.perf_counter() - started, 3),
        "sim_seconds": round(sim_seconds, 3),
        "cpu_seconds": round(time.process_time() - cpu_started, 3),
    }
    return labels, stats


def approach_spread_deg(approach: np.ndarray) -> float:
    """Orientation diversity: mean angle (degrees) between the approach directions and their mean direction
    (0 for identical approaches; 90 for directions spread uniformly over a hemisphere...)."""
    if len(approach) < 2:
        return 0.0
    mean = approach.mean(0)
    norm = np.linalg.norm(mean)
    if norm < 1e-9:
        return 90.0
    cos = np.clip(approach @ (mean / norm), -1.0, 1.0)
    return float(np.degrees(np.arccos(cos)).mean())


def _stats_path(out: Path, object_id: str, k: int) -> Path:
    return state_path(out, object_id, k).with_suffix(".json")


def _job(item: tuple[str, int, dict]) -> dict:
    folder, k, cfg_dict = item
    cfg = GenerateGraspsConfig(**cfg_dict)
    obj = ArticulatedObject.load(folder)
    out = Path(cfg.out)
    npz, stats_file = state_path(out, obj.object_id, k), _stats_path(out, obj.object_id, k)
    if npz.is_file() and stats_file.is_file():
        return {**json.loads(stats_file.read_text()), "resumed": True}
    labels, stats = label_state(obj, k, cfg)
    # Statistics first, labels last: the .npz is the item's completion marker.
    atomic_write_json(stats_file, stats)
    labels.save(out)
    return stats


def generate_grasps(cfg: GenerateGraspsConfig) -> dict:
    """Generate (or complete) the label set described by ``cfg``; returns the manifest's counts per category
    (of every item in the folder, earlier runs' included)."""
    folders = list_objects(Path(cfg.objects))
    check_output_folder(cfg.out)
    for f in folders:  # fail early, in this process and before writing, on objects that cannot be loaded
        ArticulatedObject.load(f)
    out = output_folder(cfg.out)
    for sub in out.iterdir():
        if sub.is_dir():
            remove_stale_temporaries(sub)
    cfg_dict = {k: (str(v) if isinstance(v, Path) else v) for k, v in asdict(cfg).items()}
    items = [(str(f), k, cfg_dict) for f in folders for k in range(cfg.states)]
    rows = list(parallel_map(_job, items, cfg.workers, desc="grasp labels", ray_address=cfg.ray_address))
    rows = [{k: v for k, v in r.items() if k != "resumed"} for r in rows]
    written = merge_manifest(
        out, "grasps", cfg, "items", rows, key=lambda r: (r["object_id"], r["state_index"]),
        summarize=lambda all_rows: {"counts": summarize(all_rows)},
        present=lambda r: state_path(out, r["object_id"], r["state_index"]).is_file(),
        seed=cfg.seed, protocol=protocol_constants(),
    )  # fmt: skip
    return written["counts"]


def summarize(rows: list[dict], enough: int = 100) -> dict:
    """Per category: items, labels, trials, yield, items with >= ``enough`` labels, approach spread."""
    out: dict[str, dict] = {}
    for cat in sorted({r["category"] for r in rows}):
        rs = [r for r in rows if r["category"] == cat]
        trials = sum(r["trials"] for r in rs)
        succ = sum(r["successes"] for r in rs)
        out[cat] = {
            "items": len(rs),
            "labels": succ,
            "trials": trials,
            "yield": round(succ / trials, 4) if trials else 0.0,
            f"items_with_{enough}_labels": sum(r["successes"] >= enough for r in rs),
            "mean_approach_spread_deg": round(float(np.mean([r["approach_spread_deg"] for r in rs])), 2),
        }
    return out


def protocol_constants() -> dict:
    """The executor's named constants, recorded in every manifest and report."""
    names = [
        "SUCCESS_ANGLE",
        "SUCCESS_DISTANCE",
        "OPEN_MARGIN_REVOLUTE",
        "OPEN_MARGIN_PRISMATIC",
        "APPROACH_DISTANCE",
        "GRASP_FORCE",
        "FINGER_FRICTION",
        "HAND_MAX_FORCE",
        "APPROACH_SPEED",
        "FINGER_SPEED",
        "PULL_SPEED",
        "PULL_ANGLE",
        "PULL_DISTANCE",
        "APPROACH_TOLERANCE",
    ]
    return {n: getattr(ex, n) for n in names}
