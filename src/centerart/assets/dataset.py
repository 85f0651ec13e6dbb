"""Generate a folder of checked objects: parallel over objects, resumable, with a manifest.

On-disk layout::

    OUT/manifest.json            config, seed, code version, counts, rejections per category, one row per object
    OUT/<category>_<index:04d>/  one object in PartNet-Mobility layout (see :mod:`centerart.assets.writer`)

Object ``<category>_<i>`` is drawn from a generator seeded by (seed, category, i, attempt), so it does not depend
on how many objects are asked for, on the number of workers or on which objects already exist. Attempts that fail
:func:`~centerart.assets.physics_checks.check_object` are discarded (and counted) and the next attempt is drawn.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from centerart.assets.categories import CATEGORIES
from centerart.assets.generator import generate_spec
from centerart.assets.physics_checks import check_object
from centerart.assets.writer import write_object
from centerart.errors import CenterArtError
from centerart.utils.atomic import atomic_directory
from centerart.utils.checks import at_least, workers
from centerart.utils.folders import output_folder
from centerart.utils.json_schema import json_problem
from centerart.utils.manifest import code_version, merge_manifest
from centerart.utils.parallel import parallel_map
from centerart.utils.seeding import item_rng, item_seed

MAX_ATTEMPTS = 20


@dataclass
class GenerateObjectsConfig:
    """Generate procedural articulated objects (PartNet-Mobility layout) that pass the physics checks."""

    out: Path
    """Output folder (created). Existing complete objects are kept and skipped (resume)."""
    category: Literal["microwave", "oven", "refrigerator", "dishwasher", "storage_furniture", "all"] = "all"
    """Category to generate, or all five."""
    count: int = 20
    """Objects per category."""
    seed: int = 0
    """Global seed: object i of a category depends only on (seed, category, i)."""
    workers: int | None = None
    """Parallel worker processes (default: all cores)."""
    variety: Literal["classic", "extended"] = "classic"
    """Object variety: ``classic`` (the generator the shipped models were trained on) or ``extended`` (issue 15's
    realism and size lever: real size ranges, side-by-side and French-door fridges, double and twin ovens,
    shelves, racks, baskets, turntables, displays, cooktops, countertops and feet; see
    :mod:`centerart.assets.furnishing`)."""
    skip_checks: bool = False
    """Write objects without the physics checks (faster; not for training data)."""
    ray_address: str | None = None
    """Run on a Ray cluster at this address instead of a local process pool; ``local`` starts a Ray instance on
    this machine with ``workers`` CPUs."""

    def __post_init__(self):
        at_least("--count", self.count, 0)
        workers("--workers", self.workers)


def object_id(category: str, index: int) -> str:
    return f"{category}_{index:04d}"


def _generate_one(job: tuple[str, int, int, str, str, bool, str]) -> dict:
    category, index, seed, out, variety, skip_checks, version = job
    oid = object_id(category, index)
    final = Path(out) / oid
    if (final / "meta.json").is_file():
        record, made = _finished_record(final)
        if made != variety:
            raise CenterArtError(f"{final}: a {made} object, not {variety}; generate the {variety} variety elsewhere")
        return {**record, "resumed": True}
    started = time.perf_counter()
    rejections = []
    for attempt in range(MAX_ATTEMPTS):
        rng = item_rng(seed, category, index, attempt)
        spec = generate_spec(category, rng, variety)
        record = {
            "id": oid,
            "category": category,
            "index": index,
            "attempt": attempt,
            "target_joint": spec.target_joint,
            "joint_type": spec.joint(spec.target_joint).type,
            "rejected": list(rejections),
        }
        info = {
            "name": "centerart",
            "version": version,
            "seed": seed,
            "item_seed": item_seed(seed, category, index, attempt),
            "record": record,
        }
        try:
            with atomic_directory(final) as tmp:
                meta = write_object(spec, tmp, oid, info)
                report = None if skip_checks else check_object(tmp)
                if report is not None and not report.ok:
                    raise _Rejected("; ".join(report.problems))
                record["triangles"] = _count_triangles(tmp)
                (tmp / "meta.json").write_text(json.dumps(meta, indent=2) + "\n")
            # Timing goes to the manifest only, so that object files are byte-identical for a seed.
            return {**record, "seconds": round(time.perf_counter() - started, 3)}
        except _Rejected as rejection:
            rejections.append(str(rejection))
    raise CenterArtError(f"{oid}: no attempt out of {MAX_ATTEMPTS} passed the checks: {rejections[-3:]}")


#: The manifest row of a generated object, kept in its meta.json (``generator.record``) for resuming.
RECORD_SCHEMA = {"id": str, "category": str, "joint_type": str, "rejected": list, "triangles": int}


def _finished_record(final: Path) -> tuple[dict, str]:
    """The manifest row of an object an earlier run finished and the variety it was generated with (objects from
    before varieties existed are classic); one clear error when its meta.json is damaged."""
    meta_path = final / "meta.json"
    try:
        meta = json.loads(meta_path.read_text())
        record = meta["generator"]["record"]
    except (OSError, ValueError, KeyError, TypeError) as err:
        meta, record, problem = {}, None, f"no generator.record ({type(err).__name__})"
    else:
        problem = json_problem(record, RECORD_SCHEMA, "generator.record")
    if problem:
        raise CenterArtError(f"{meta_path}: damaged ({problem}); delete {final} to generate it again")
    params = meta.get("params")
    return record, params.get("variety", "classic") if isinstance(params, dict) else "classic"


class _Rejected(Exception):
    pass


def _count_triangles(folder: Path) -> int:
    n = 0
    for obj in (folder / "textured_objs").glob("*.obj"):
        n += sum(1 for line in obj.read_text().splitlines() if line.startswith("f "))
    return n


def generate_objects(cfg: GenerateObjectsConfig) -> dict:
    """Generate (or complete) the dataset described by ``cfg``; returns the manifest's counts and rows, which list
    every object in the folder (earlier or concurrent runs of other categories too)."""
    categories = CATEGORIES if cfg.category == "all" else (cfg.category,)
    for c in categories:
        if c not in CATEGORIES:
            raise CenterArtError(f"unknown category {c!r}; choose from {', '.join(CATEGORIES)} or all")
    out = output_folder(cfg.out)
    version = code_version()
    jobs = [
        (c, i, cfg.seed, str(out), cfg.variety, cfg.skip_checks, version) for c in categories for i in range(cfg.count)
    ]
    results = parallel_map(_generate_one, jobs, cfg.workers, desc="objects", ray_address=cfg.ray_address)
    records = sorted(results, key=lambda r: r["id"])
    written = merge_manifest(
        out, "objects", cfg, "objects", records, key=lambda r: r["id"], summarize=_counts,
        present=lambda r: (out / r["id"] / "meta.json").is_file(), seed=cfg.seed,
    )  # fmt: skip
    return {"counts": written["counts"], "objects": written["objects"]}


def _counts(records: list[dict]) -> dict:
    """Objects, rejections, joint types and mean triangles per category of the manifest's rows."""
    per_category = {}
    for c in sorted({r["category"] for r in records}):
        rows = [r for r in records if r["category"] == c]
        per_category[c] = {
            "objects": len(rows),
            "rejected_attempts": int(sum(len(r["rejected"]) for r in rows)),
            "revolute": sum(r["joint_type"] == "revolute" for r in rows),
            "prismatic": sum(r["joint_type"] == "prismatic" for r in rows),
            "mean_triangles": float(np.mean([r["triangles"] for r in rows])) if rows else 0.0,
        }
    return {"counts": per_category}


def list_objects(folder: Path) -> list[Path]:
    """Object folders (those with a mobility.urdf) directly inside ``folder``, or ``folder`` itself if it is one."""
    folder = Path(folder)
    if (folder / "mobility.urdf").is_file():
        return [folder]
    if not folder.is_dir():
        raise CenterArtError(f"{folder}: no such folder")
    found = sorted(p for p in folder.iterdir() if (p / "mobility.urdf").is_file())
    if not found:
        raise CenterArtError(f"{folder}: no object folders (with mobility.urdf) inside")
    return found
