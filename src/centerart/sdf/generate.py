"""``centerart sdf generate``: SDF samples with nearest-grasp targets for every (object, joint state).

On-disk layout (see :mod:`centerart.sdf.samples` for the ``.npz`` keys)::

    OUT/manifest.json                    config, seed, code version, counts, per-object sign agreement
    OUT/<object_id>/state_<k:02d>.npz    one SdfSamples file per state
    OUT/<object_id>/state_<k:02d>.json   its statistics (sign methods and agreement, timing, label count)

States: exactly those of the object's grasp-label files (same ``state_index`` and ``q``). An object without a
label folder gets ``--states`` states evenly spread over its joint range, with no grasp targets
(``grasp_distance = inf``). Each (object, state) is one work item, seeded by (seed, object_id, state_index), so
results do not depend on the number of workers or on which items already exist; finished items are skipped.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.dataset import list_objects
from centerart.errors import CenterArtError
from centerart.grasps.labels import StateLabels
from centerart.sdf.grasp_targets import nearest_grasp_targets
from centerart.sdf.samples import SdfSamples, sample_path
from centerart.sdf.sampling import SamplingConfig, sample_points, signed_distance
from centerart.sdf.surface import object_surface
from centerart.utils.atomic import atomic_write_json, remove_stale_temporaries
from centerart.utils.checks import at_least, workers
from centerart.utils.folders import check_output_folder, output_folder
from centerart.utils.manifest import merge_manifest
from centerart.utils.parallel import parallel_map
from centerart.utils.seeding import item_rng

#: Sign agreement below which the manifest flags an object (the issue's acceptance bar).
MIN_SIGN_AGREEMENT = 0.99


@dataclass
class GenerateSdfConfig:
    """Sample signed distances and nearest-grasp targets per (object, joint state), canonical object frame."""

    objects: Path
    """Folder of object folders (PartNet-Mobility layout), or one object folder."""
    grasps: Path
    """Grasp-label folder (``<object_id>/state_*.npz``); objects without a subfolder get evenly spaced states
    and no grasp targets."""
    out: Path
    """Output folder (created). Finished (object, state) files are kept and skipped (resume)."""
    points: int = 100_000
    """Query points per (object, state)."""
    states: int = 10
    """States per object that has no grasp labels (evenly spaced over the joint range, both ends included)."""
    workers: int | None = None
    """Parallel worker processes (default: all cores)."""
    seed: int = 0
    """Global seed: item (object, state) depends only on (seed, object_id, state_index)."""
    ray_address: str | None = None
    """Run on a Ray cluster at this address instead of a local process pool; ``local`` starts a Ray instance on
    this machine with ``workers`` CPUs."""
    sampling: SamplingConfig = field(default_factory=SamplingConfig)
    """Point mix and sign methods."""

    def __post_init__(self):
        at_least("--points", self.points, 1)
        at_least("--states", self.states, 1)
        workers("--workers", self.workers)
        _check_sampling(self.sampling)


def _check_sampling(s: SamplingConfig) -> None:
    if not (0 <= s.near_fraction and 0 <= s.far_fraction and s.near_fraction + s.far_fraction <= 1):
        raise CenterArtError("--sampling.near-fraction and --sampling.far-fraction must be >= 0 and sum to <= 1")
    if s.parity_rays < 1 or s.parity_rays % 2 == 0:
        raise CenterArtError(f"--sampling.parity-rays must be odd and >= 1, got {s.parity_rays}")
    if s.escape_rays < 1 or s.flood_cells < 8 or s.flood_thin_cells < 2 or s.check_points < 1:
        raise CenterArtError(
            "--sampling.escape-rays, --sampling.flood-cells (>= 8), --sampling.flood-thin-cells (>= 2), "
            "--sampling.check-points must be positive"
        )
    if s.flood_max_voxels < 1000 or s.escape_min_rays < 1:
        raise CenterArtError("--sampling.flood-max-voxels must be >= 1000 and --sampling.escape-min-rays >= 1")
    if s.escape_opening_spacing < 0 or s.escape_opening_offset <= 0:
        raise CenterArtError(
            "--sampling.escape-opening-spacing must be >= 0 (0: no aimed rays) and --sampling.escape-opening-offset > 0"
        )


@dataclass(frozen=True)
class _Item:
    object_dir: str
    object_id: str
    state_index: int
    n_states: int  # 0: the state comes from label_file; else the k-th of n evenly spaced states
    label_file: str | None
    out: str
    seed: int
    points: int
    sampling: SamplingConfig


def _plan(cfg: GenerateSdfConfig) -> list[_Item]:
    objects_dir, grasps_dir = Path(cfg.objects), Path(cfg.grasps)
    if not objects_dir.is_dir():
        raise CenterArtError(f"{objects_dir}: objects folder does not exist")
    if not grasps_dir.is_dir():
        raise CenterArtError(f"{grasps_dir}: grasp-label folder does not exist")
    check_output_folder(cfg.out)
    s = cfg.sampling
    items = []
    for folder in list_objects(objects_dir):
        oid = folder.name
        label_files = sorted((grasps_dir / oid).glob("state_*.npz"))
        if label_files:
            for f in label_files:
                try:
                    k = int(f.stem.split("_")[1])
                except (IndexError, ValueError):
                    raise CenterArtError(f"{f}: grasp-label file name is not state_<k>.npz") from None
                items.append(_Item(str(folder), oid, k, 0, str(f), str(cfg.out), cfg.seed, cfg.points, s))
        else:
            for k in range(cfg.states):
                items.append(_Item(str(folder), oid, k, cfg.states, None, str(cfg.out), cfg.seed, cfg.points, s))
    return items


def _check_inputs(items: list[_Item]) -> None:
    """Load every object and label file once, in this process, before anything is written: a damaged one is a
    clear error here instead of an empty output folder and a worker's failure."""
    for folder in sorted({it.object_dir for it in items}):
        ArticulatedObject.load(folder)
    for it in items:
        if it.label_file is not None:
            StateLabels.load(Path(it.label_file))


def _stats_path(out: Path, object_id: str, state_index: int) -> Path:
    return sample_path(out, object_id, state_index).with_suffix(".json")


def _fingerprint(item: _Item) -> dict:
    return {"seed": item.seed, "points": item.points, "sampling": asdict(item.sampling)}


def _generate_one(item: _Item) -> dict:
    try:
        return _generate_one_unchecked(item)
    except CenterArtError as err:
        # Re-raise as the base class: AssetError's two-argument constructor does not survive the trip back from
        # a worker process (pickle rebuilds exceptions from their message alone).
        raise CenterArtError(str(err)) from None
    except (ValueError, RuntimeError, MemoryError) as err:
        raise CenterArtError(
            f"{item.object_dir} state {item.state_index}: SDF sampling failed ({type(err).__name__}: {err})"
        ) from None


def _generate_one_unchecked(item: _Item) -> dict:
    out = Path(item.out)
    npz, stats_file = (
        sample_path(out, item.object_id, item.state_index),
        _stats_path(out, item.object_id, item.state_index),
    )
    if npz.is_file() and stats_file.is_file():
        stats = json.loads(stats_file.read_text())
        if stats.get("config") != _fingerprint(item):
            raise CenterArtError(
                f"{npz}: was made with other settings ({stats.get('config')}); "
                "use a new --out or the same options to resume"
            )
        return {**stats, "resumed": True}
    started = time.perf_counter()
    obj = ArticulatedObject.load(item.object_dir)
    if item.label_file is not None:
        labels = StateLabels.load(Path(item.label_file))
        if labels.object_id != item.object_id or labels.state_index != item.state_index:
            raise CenterArtError(
                f"{item.label_file}: holds object {labels.object_id!r} state {labels.state_index}, "
                f"expected {item.object_id!r} state {item.state_index}"
            )
        q, poses = float(labels.q), labels.poses
        lo, hi = obj.joint_range
        if not lo - 1e-6 <= q <= hi + 1e-6:
            raise CenterArtError(f"{item.label_file}: q={q:.4f} is outside the joint range [{lo:.4f}, {hi:.4f}]")
    else:
        u = 0.5 if item.n_states == 1 else item.state_index / (item.n_states - 1)
        q, poses = obj.denormalize(u), np.zeros((0, 4, 4))
    rng = item_rng(item.seed, item.object_id, item.state_index)
    surface = object_surface(obj, q)
    points = sample_points(surface.mesh, item.points, item.sampling, rng)
    signed = signed_distance(surface, points, item.sampling, rng)
    t_sdf = time.perf_counter() - started
    t0 = time.perf_counter()
    grasp_points, grasp_distance = nearest_grasp_targets(signed.points, poses)
    t_grasp = time.perf_counter() - t0
    SdfSamples(
        object_id=item.object_id,
        state_index=item.state_index,
        q=q,
        q_normalized=obj.normalize(q),
        joint_type=obj.joint_type,
        points=signed.points,
        sdf=signed.sdf,
        grasp_points=grasp_points,
        grasp_distance=grasp_distance,
    ).save(out)
    stats = {
        "object_id": item.object_id,
        "state_index": item.state_index,
        "q": q,
        "closed_mesh": surface.closed,
        "triangles": len(surface.mesh.faces),
        "soup_pieces": len(surface.pieces),
        "points": len(signed.points),
        "inside_fraction": float(np.mean(signed.sdf < 0)),
        "sign_method": signed.sign_method,
        "check_method": signed.check_method,
        "sign_agreement": signed.sign_agreement,
        "checked_points": signed.checked,
        "grasps": len(poses),
        "seconds_sdf": round(t_sdf, 3),
        "seconds_grasp_targets": round(t_grasp, 4),
        "config": _fingerprint(item),
    }
    atomic_write_json(stats_file, stats)  # written last: its presence marks the item finished
    return stats


def generate_sdf(cfg: GenerateSdfConfig, progress: bool = True) -> dict:
    """Generate (or complete) the SDF dataset described by ``cfg``; returns the manifest's summary fields (of
    every state in the folder, earlier runs' included)."""
    items = _plan(cfg)
    _check_inputs(items)
    out = output_folder(cfg.out)
    for oid in {it.object_id for it in items}:
        remove_stale_temporaries(out / oid)
    rows = parallel_map(
        _generate_one, items, cfg.workers, "sdf states", ray_address=cfg.ray_address, disable_progress=not progress
    )
    rows = [{k: v for k, v in r.items() if k != "config"} for r in rows]
    written = merge_manifest(
        out, "sdf", cfg, "states", rows, key=lambda r: (r["object_id"], r["state_index"]), summarize=_summary,
        present=lambda r: sample_path(out, r["object_id"], r["state_index"]).is_file(),
        seed=cfg.seed, min_sign_agreement=MIN_SIGN_AGREEMENT,
    )  # fmt: skip
    return {k: written[k] for k in ("seed", "min_sign_agreement", "counts", "objects")}


def _summary(rows: list[dict]) -> dict:
    """Counts and per-object sign agreement of the manifest's state rows."""
    per_object: dict[str, dict] = {}
    for r in rows:
        o = per_object.setdefault(
            r["object_id"],
            {"states": 0, "points": 0, "grasps": 0, "sign_method": r["sign_method"], "check_method": r["check_method"]},
        )
        o["states"] += 1
        o["points"] += r["points"]
        o["grasps"] += r["grasps"]
        o.setdefault("_agree", []).append(r["sign_agreement"])
    for o in per_object.values():
        agree = o.pop("_agree")
        o["sign_agreement_mean"] = float(np.mean(agree))
        o["sign_agreement_min"] = float(np.min(agree))
        o["meets_min_sign_agreement"] = bool(np.min(agree) >= MIN_SIGN_AGREEMENT)
    counts = {
        "objects": len(per_object),
        "states": len(rows),
        "points": int(sum(r["points"] for r in rows)),
        "states_without_grasps": sum(r["grasps"] == 0 for r in rows),
        "resumed": sum(bool(r.get("resumed")) for r in rows),
        "objects_below_min_sign_agreement": sorted(
            k for k, o in per_object.items() if not o["meets_min_sign_agreement"]
        ),
    }
    return {"counts": counts, "objects": per_object}
