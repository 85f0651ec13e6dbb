"""Kill -9 in the middle of each generating stage, rerun the same command: the result equals an uninterrupted
run's, byte for byte (manifests aside: they hold times), and nothing temporary is left.

Each stage runs as a real process (``python -m centerart.cli``) that is killed with SIGKILL once its first item is
complete; the reference run is in-process. Inputs are tiny so the whole file takes well under a minute.
"""

from __future__ import annotations

import filecmp
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from centerart.cli import main


def kill_after_first(argv: list[str], out: Path, first_item: str, timeout: float = 120) -> None:
    """Run the command and SIGKILL it as soon as ``out.glob(first_item)`` finds something."""
    proc = subprocess.Popen([sys.executable, "-m", "centerart.cli", *argv], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})  # fmt: skip
    deadline = time.monotonic() + timeout
    try:
        while not list(out.glob(first_item)):
            if proc.poll() is not None:
                pytest.fail(
                    f"finished (exit {proc.returncode}) before it could be killed: {proc.stderr.read()[-2000:]}"
                )
            if time.monotonic() > deadline:
                pytest.fail("no item appeared in time")
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.kill()
        proc.wait()


def same_tree(a: Path, b: Path) -> list[str]:
    """Files that differ (or exist on one side only) between two output folders, manifests and timings aside."""

    def files(root: Path) -> set[str]:
        return {str(p.relative_to(root)) for p in root.rglob("*") if p.is_file() and not _volatile(p)}

    fa, fb = files(a), files(b)
    differ = sorted(fa ^ fb)
    differ += [f for f in sorted(fa & fb) if not filecmp.cmp(a / f, b / f, shallow=False)]
    return differ


def _volatile(p: Path) -> bool:
    # manifests and per-item statistics hold wall-clock times; .lock is the folder's lock file
    return p.name in ("manifest.json", ".lock", "checks.json") or (p.suffix == ".json" and p.name.startswith("state_"))


def _objects(tmp: Path, fx) -> tuple[list[str], str]:
    return ["objects", "generate", "--category", "storage_furniture", "--count", "6", "--workers", "1",
            "--seed", "7"], "storage_furniture_*/meta.json"  # fmt: skip


def _grasps(tmp: Path, fx) -> tuple[list[str], str]:
    return ["grasps", "generate", "--objects", str(fx.object_dir), "--states", "4", "--per-state", "2",
            "--max-trials", "8", "--max-candidates", "200", "--workers", "1"], "*/state_*.npz"  # fmt: skip


def _sdf(tmp: Path, fx) -> tuple[list[str], str]:
    grasps = tmp / "no_labels"
    grasps.mkdir(exist_ok=True)
    return ["sdf", "generate", "--objects", str(fx.object_dir), "--grasps", str(grasps), "--points", "3000",
            "--states", "4", "--workers", "1"], "*/state_*.json"  # fmt: skip


def _scenes(tmp: Path, fx) -> tuple[list[str], str]:
    return ["scenes", "generate", "--objects", str(fx.object_dir.parent), "--layout", "single", "--count", "4",
            "--views-per-scene", "1", "--depth", "analytic", "--intrinsics", "tiny", "--workers", "1"],  \
        "scene_*/scene.json"  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("stage", [_objects, _grasps, _sdf, _scenes], ids=["objects", "grasps", "sdf", "scenes"])
def test_killed_run_resumes_to_the_uninterrupted_result(stage, fuzz_inputs, tmp_path):
    argv, first_item = stage(tmp_path, fuzz_inputs)
    resumed, reference = tmp_path / "resumed", tmp_path / "reference"
    kill_after_first([*argv, "--out", str(resumed)], resumed, first_item)
    done_at_kill = len(list(resumed.glob(first_item)))
    assert main([*argv, "--out", str(resumed)]) == 0
    assert main([*argv, "--out", str(reference)]) == 0
    assert done_at_kill < len(list(reference.glob(first_item))), "the kill came after the last item"
    assert same_tree(reference, resumed) == []
    assert not list(resumed.rglob(".tmp-*"))
