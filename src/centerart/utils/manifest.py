"""Manifests: the JSON file beside every dataset that says what produced it."""

from __future__ import annotations

import dataclasses
import datetime as _dt
import subprocess
from pathlib import Path
from typing import Any

import centerart
from centerart.utils.atomic import atomic_write_json


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
        "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "config": cfg,
        **fields,
    }
    path = Path(folder) / "manifest.json"
    atomic_write_json(path, manifest)
    return path
