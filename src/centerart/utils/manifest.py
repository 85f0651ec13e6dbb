"""Manifests: the JSON file beside every dataset that says what produced it.

Several runs may fill one folder (one category after another, or at the same time): :func:`merge_manifest` lists
the items of every run whose files are still there, recomputes the counts from them, and keeps each run's config
under ``runs``; it rewrites the manifest under the folder's lock, so concurrent runs never drop each other's items.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import json
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import Any

import centerart
from centerart.utils.atomic import atomic_write_json
from centerart.utils.folders import folder_lock

MAX_RUNS_KEPT = 100


def code_version() -> str:
    """Package version plus the git commit of the source tree when it is a checkout (``+dirty`` if modified)."""
    version = centerart.__version__
    src = Path(__file__).resolve().parents[3]
    try:
        sha = subprocess.run(
            ["git", "-C", str(src), "rev-parse", "--short=12", "HEAD"],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(src), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        ).stdout.strip()
        return f"{version}+g{sha}{'.dirty' if dirty else ''}"
    except (OSError, subprocess.SubprocessError):
        return version


def write_manifest(folder: Path, stage: str, config: Any, **fields: Any) -> Path:
    """Write ``folder/manifest.json`` with the stage name, config, code version, time and extra fields."""
    cfg = dataclasses.asdict(config) if dataclasses.is_dataclass(config) else config
    manifest = {
        "stage": stage,
        "code_version": code_version(),
        "created": _now(),
        "config": cfg,
        **fields,
    }
    path = Path(folder) / "manifest.json"
    atomic_write_json(path, manifest)
    return path


def merge_manifest(
    folder: Path,
    stage: str,
    config: Any,
    items: str,
    rows: list[dict],
    key: Callable[[dict], Any],
    summarize: Callable[[list[dict]], dict],
    present: Callable[[dict], bool] | None = None,
    **fields: Any,
) -> dict:
    """Write ``folder/manifest.json`` with this run's ``rows`` and the rows of earlier runs (same ``stage``) whose
    item is still ``present`` on disk, keyed by ``key`` (this run's row wins); ``summarize(all rows)`` gives the
    counts. Returns the fields written besides stage, config and version: ``fields``, the summary, ``items``."""
    folder = Path(folder)
    with folder_lock(folder):
        old = _previous_manifest(folder, stage)
        merged = {}
        for r in old.get(items, []):
            try:
                if present is None or present(r):
                    merged[_hashable(key(r))] = r
            except (KeyError, TypeError, ValueError):
                continue  # a hand-edited or damaged row: dropped, its item is listed again when regenerated
        merged.update({_hashable(key(r)): r for r in rows})
        all_rows = [merged[k] for k in sorted(merged)]
        cfg = dataclasses.asdict(config) if dataclasses.is_dataclass(config) else config
        run = {"created": _now(), "code_version": code_version(), "config": cfg, "items": len(rows)}
        runs = [*(old.get("runs") if isinstance(old.get("runs"), list) else []), run][-MAX_RUNS_KEPT:]
        written = {**fields, **summarize(all_rows), items: all_rows}
        write_manifest(folder, stage, config, **written, runs=runs)
    return written


def _previous_manifest(folder: Path, stage: str) -> dict:
    """The folder's manifest when it is readable and of the same stage, else {} (it is then replaced)."""
    try:
        old = json.loads((folder / "manifest.json").read_text())
    except (OSError, ValueError):
        return {}
    return old if isinstance(old, dict) and old.get("stage") == stage else {}


def _hashable(key: Any) -> Any:
    return tuple(key) if isinstance(key, list | tuple) else key


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
