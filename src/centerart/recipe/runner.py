"""``centerart recipe``: run the steps in order, skip finished ones, keep one manifest for the whole run.

``OUT/manifest.json`` (stage ``recipe``) holds the recipe config and, per step: the configs of the stage commands
it ran (``configs``: results-relevant fields only, paths inside OUT written as ``OUT/...``), its status (``running``
or ``done``), the code version, its counts and its wall time (``seconds``, summed over the calls that worked on it).

Resuming: a step whose record says ``done`` with the same configs and whose outputs exist is skipped; a step that
was interrupted runs again and its stage resumes item by item (each stage skips finished items). A rerun with
settings that change a step's results is refused with the fields that differ, instead of mixing two runs' data.

Several processes (DDP across nodes, started by a cluster launcher on every node): global rank 0 runs every step;
the other ranks only join the training steps (:func:`follow`).
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from centerart.errors import CenterArtError
from centerart.recipe.adopt import adopt_decoder, source_record
from centerart.recipe.config import STEPS, RecipeConfig
from centerart.recipe.steps import STEP_TABLE, Paths, step_folders
from centerart.utils.checks import at_least
from centerart.utils.folders import output_folder
from centerart.utils.manifest import code_version, write_manifest
from centerart.utils.parallel import init_ray, launcher_rank

#: Fields of the stage configs that do not change what a step produces (processes, devices, progress bars).
RESOURCE_KEYS = frozenset(
    {"workers", "ray_address", "progress", "threads", "accelerator", "devices", "num_nodes", "strategy", "resume"}
)
#: Fields added to stage configs after recipe runs were recorded, with the value those runs implicitly used: a
#: record without the field matches a plan that holds that value (older runs stay resumable).
ADDED_FIELDS = {"variety": "classic", "ir_shading": "full", "code_weight": 1e-4}
FOLLOW_POLL_S = 5.0


def run_recipe(cfg: RecipeConfig, echo=print) -> dict:
    """Run (or resume) the recipe up to ``cfg.until``; returns the manifest's step records."""
    check_config(cfg)
    out = output_folder(Path(cfg.out).resolve())  # --out naming a file is one clear error, before anything is made
    paths = Paths(out)
    if launcher_rank() != 0:
        follow(cfg, paths, echo)
        return {}
    manifest = load_manifest(out)
    records = manifest.setdefault("steps", {})
    ray_started = False
    try:
        for i, name in enumerate(cfg.steps(), 1):
            step = STEP_TABLE[name]
            label = f"[{i}/{len(STEPS)}] {name}"
            planned = step.plan(cfg, paths)
            record = usable_record(name, records, paths, planned)
            if name == "decoder" and record is None and cfg.decoder_from is not None:
                _adopt_decoder(cfg, paths, planned, records, manifest, label, echo)
                continue
            if record and record["status"] == "done" and all(f.is_file() for f in step.outputs(planned)):
                echo(f"{label}: finished earlier in {format_seconds(record['seconds'])}, skipped")
                continue
            if step.data and cfg.ray_address and not ray_started:
                ray_started = init_ray(cfg.ray_address, cfg.workers)
            echo(f"{label}: running")
            seconds = _run_step(cfg, name, paths, planned, records, manifest)
            echo(f"{label}: done in {format_seconds(seconds)}")
    finally:
        if ray_started:
            import ray

            ray.shutdown()
    return records


def _adopt_decoder(cfg: RecipeConfig, paths: Paths, planned: dict, records: dict, manifest: dict, label: str,
                   echo) -> None:  # fmt: skip
    """``--decoder-from``: the earlier run's decoder instead of training one (:mod:`centerart.recipe.adopt`)."""
    source = source_record(cfg.decoder_from)
    changed = _differences(source["configs"], comparable(planned, paths.out))
    records["decoder"] = {**adopt_decoder(cfg.decoder_from, source, paths, changed), "adopted": _now()}
    save_manifest(cfg, paths.out, manifest)
    trained = format_seconds(records["decoder"].get("seconds", 0.0))
    echo(f"{label}: adopted from {records['decoder']['adopted_from']} (trained there in {trained})")


def _run_step(cfg: RecipeConfig, name: str, paths: Paths, planned: dict, records: dict, manifest: dict) -> float:
    """Record the step as running, run it, record it as done with its counts and time; returns this call's time."""
    before = (records.get(name) or {}).get("seconds", 0.0)
    records[name] = {
        "status": "running",
        "configs": comparable(planned, paths.out),
        "seeds": {stage: getattr(c, "seed", None) for stage, c in planned.items()},
        "code_version": code_version(),
        "started": _now(),
        "seconds": before,
    }
    save_manifest(cfg, paths.out, manifest)
    t0 = time.perf_counter()
    counts = STEP_TABLE[name].run(cfg, paths, planned) if planned else {"note": "nothing to do"}
    seconds = time.perf_counter() - t0
    records[name].update(
        status="done", counts=counts, seconds=round(before + seconds, 1), seconds_last_call=round(seconds, 1)
    )
    records[name]["finished"] = _now()
    save_manifest(cfg, paths.out, manifest)
    return seconds


# ---------------------------------------------------------------------------- checks
def check_config(cfg: RecipeConfig) -> None:
    if cfg.seed == cfg.test_seed:
        raise CenterArtError(
            f"--test-seed must differ from --seed (both {cfg.seed}): test objects are drawn with their own seed"
        )
    if cfg.objects.count < 1:
        raise CenterArtError(f"--objects.count must be >= 1, got {cfg.objects.count}")
    if cfg.workers is not None and cfg.workers < 1:  # checked here, not by the first step's config: before --out
        raise CenterArtError(f"--workers must be >= 1, got {cfg.workers}")
    if cfg.devices < 1 or cfg.num_nodes < 1:
        raise CenterArtError("--devices and --num-nodes must be >= 1")
    # Checked here too: the decoder step's own check would only come after the data steps' minutes of work.
    at_least("--decoder.code-weight", cfg.decoder.code_weight, 0.0)
    if cfg.decoder_from is not None:
        source_record(cfg.decoder_from)  # a wrong folder is named before the data steps run
    world = cfg.devices * cfg.num_nodes
    if cfg.strategy == "ddp" and world > 1 and not _launched_externally():
        # Lightning would start the other processes by re-running this command line: each would run the recipe.
        raise CenterArtError(
            "--strategy ddp needs a cluster launcher (torchrun, SLURM srun) starting the recipe once per process; "
            "on one machine leave --strategy auto (the recipe then spawns the training processes itself)"
        )


def _launched_externally() -> bool:
    return any(k in os.environ for k in ("RANK", "SLURM_PROCID", "LOCAL_RANK", "OMPI_COMM_WORLD_RANK"))


def usable_record(name: str, records: dict, paths: Paths, planned: dict) -> dict | None:
    """The step's record when it can be resumed or skipped; None for a fresh start; an error for a mix-up."""
    record = records.get(name)
    started = any(f.exists() for f in step_folders(name, paths))
    if record is None and started:
        shown = ", ".join(str(f) for f in step_folders(name, paths) if f.exists())
        raise CenterArtError(
            f"{shown}: exists but {paths.out / 'manifest.json'} has no record of the {name} step that made it; "
            "use a new --out, or delete it"
        )
    if record is None or not started:
        later = [n for n in STEPS[STEPS.index(name) + 1 :] if any(f.exists() for f in step_folders(n, paths))]
        if later:
            raise CenterArtError(
                f"the {name} step starts afresh, but the {', '.join(later)} step(s) hold results made from its "
                "earlier outputs; delete their folders too, or use a new --out"
            )
        records.pop(name, None)
        return None
    changed = _differences(record["configs"], comparable(planned, paths.out))
    if changed:
        raise CenterArtError(
            f"{paths.out}: the {name} step was made with other settings ({', '.join(changed[:6])}); rerun with the "
            f"same options to resume, or delete {' and '.join(str(f) for f in step_folders(name, paths))} and the "
            "later steps' folders to redo it"
        )
    return record


def comparable(planned: dict, out: Path) -> dict:
    """The stage configs as JSON values, without fields that do not change results (:data:`RESOURCE_KEYS`) and
    with paths inside ``out`` written as ``OUT/...`` (so the folder may move between calls)."""
    raw = json.loads(json.dumps({k: asdict(v) for k, v in planned.items()}, default=str))
    return _relative(raw, str(out))


def _relative(x: Any, root: str) -> Any:
    if isinstance(x, dict):
        return {k: _relative(v, root) for k, v in x.items() if k not in RESOURCE_KEYS}
    if isinstance(x, list):
        return [_relative(v, root) for v in x]
    if isinstance(x, str) and (x == root or x.startswith(root + "/")):
        return "OUT" + x[len(root) :]
    return x


def _differences(a: Any, b: Any, prefix: str = "") -> list[str]:
    """Dotted keys where two JSON values differ, as ``key: old -> new``."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            old = a[k] if k in a else ADDED_FIELDS.get(k)  # a record from before the field: its implicit value
            out += _differences(old, b.get(k), f"{prefix}.{k}" if prefix else k)
        return out
    return [] if a == b else [f"{prefix}: {a!r} -> {b!r}"]


# ---------------------------------------------------------------------------- manifest
def load_manifest(out: Path) -> dict:
    path = Path(out) / "manifest.json"
    if not path.is_file():
        return {"steps": {}, "first_started": _now()}
    try:
        manifest = json.loads(path.read_text())
    except json.JSONDecodeError as err:
        raise CenterArtError(f"{path}: damaged ({err}); use a new --out") from None
    if manifest.get("stage") != "recipe":
        raise CenterArtError(f"{path}: not a recipe's manifest (stage {manifest.get('stage')!r}); use a new --out")
    return manifest


def save_manifest(cfg: RecipeConfig, out: Path, manifest: dict) -> None:
    steps = manifest["steps"]
    fields = {
        "seed": cfg.seed,
        "test_seed": cfg.test_seed,
        "first_started": manifest.get("first_started", _now()),
        "steps": {n: steps[n] for n in STEPS if n in steps},
        "seconds": round(sum(r.get("seconds", 0.0) for r in steps.values()), 1),
    }
    write_manifest(out, "recipe", cfg, **fields)


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def format_seconds(seconds: float) -> str:
    if seconds < 60:
        return f"{seconds:.1f} s"
    minutes, s = divmod(round(seconds), 60)
    return f"{minutes} min {s:02d} s" if minutes < 60 else f"{minutes // 60} h {minutes % 60:02d} min"


# ---------------------------------------------------------------------------- other ranks
def follow(cfg: RecipeConfig, paths: Paths, echo=print) -> None:
    """A process other than global rank 0: join each training step when rank 0 starts it (its record turns
    ``running``; DDP then waits for every rank), leave every other step to rank 0."""
    for name in cfg.steps():
        step = STEP_TABLE[name]
        if not step.training:
            continue
        while True:
            record = load_manifest(paths.out).get("steps", {}).get(name)
            if record and record["status"] == "running":
                echo(f"rank {launcher_rank()}: joining the {name} step")
                step.run(cfg, paths, step.plan(cfg, paths))
                break
            if record and record["status"] == "done":
                break
            time.sleep(FOLLOW_POLL_S)
