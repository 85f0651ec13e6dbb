"""Several runs writing into one folder: temporaries are owned per process, manifests merge, training refuses.

The subprocess tests run the real command line (``python -m centerart.cli``), two at once, as a user would.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

from centerart.errors import CenterArtError
from centerart.utils.atomic import FOREIGN_STALE_SECONDS, remove_stale_temporaries, temporary_prefix
from centerart.utils.folders import FolderBusy, folder_lock
from centerart.utils.manifest import merge_manifest


def cli(*args: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen([sys.executable, "-m", "centerart.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)  # fmt: skip


def finish(proc: subprocess.Popen, timeout: float = 120) -> tuple[int, str]:
    _, err = proc.communicate(timeout=timeout)
    return proc.returncode, err


def test_clean_up_removes_only_temporaries_of_dead_owners(tmp_path):
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    try:
        mine = tmp_path / f"{temporary_prefix('a')}x1"
        live = tmp_path / (temporary_prefix("b").replace(f".{os.getpid()}.", f".{sleeper.pid}.") + "x")
        gone = tmp_path / (temporary_prefix("c").replace(f".{os.getpid()}.", f".{dead.pid}.") + "x")
        foreign_new = tmp_path / ".tmp-d.123.0badc0de.x"
        foreign_old = tmp_path / ".tmp-e.123.0badc0de.x"
        legacy = tmp_path / ".tmp-f-abc"
        for p in (mine, live, gone, foreign_new, foreign_old, legacy):
            p.mkdir()
        old = time.time() - FOREIGN_STALE_SECONDS - 10
        os.utime(foreign_old, (old, old))
        assert remove_stale_temporaries(tmp_path) == 3
        assert {p.name for p in tmp_path.iterdir()} == {mine.name, live.name, foreign_new.name}
        sleeper.kill()
        sleeper.wait()
        assert remove_stale_temporaries(tmp_path) == 1  # its owner is gone now
        assert not live.exists() and mine.exists()
    finally:
        sleeper.kill()


def test_concurrent_runs_of_two_categories_keep_both(tmp_path):
    out = tmp_path / "objects"
    common = ["--count", "2", "--out", str(out), "--workers", "1"]
    a = cli("objects", "generate", "--category", "microwave", *common)
    b = cli("objects", "generate", "--category", "oven", *common)
    assert finish(a)[0] == 0 and finish(b)[0] == 0
    # one after the other: a third category joins the same manifest
    assert finish(cli("objects", "generate", "--category", "dishwasher", "--count", "1", "--out", str(out)))[0] == 0
    manifest = json.loads((out / "manifest.json").read_text())
    ids = [r["id"] for r in manifest["objects"]]
    assert ids == ["dishwasher_0000", "microwave_0000", "microwave_0001", "oven_0000", "oven_0001"]
    assert {c: v["objects"] for c, v in manifest["counts"].items()} == {"dishwasher": 1, "microwave": 2, "oven": 2}
    assert len(manifest["runs"]) == 3
    assert all((out / i / "meta.json").is_file() for i in ids)
    assert not list(out.glob(".tmp-*"))


def test_concurrent_runs_of_the_same_items_both_succeed(tmp_path, generated_dir):
    out = tmp_path / "objects"
    args = ["objects", "generate", "--category", "dishwasher", "--count", "1", "--out", str(out), "--workers", "1"]
    a, b = cli(*args), cli(*args)
    (code_a, err_a), (code_b, err_b) = finish(a), finish(b)
    assert code_a == 0 and code_b == 0, err_a + err_b
    for f in ("mobility.urdf", "meta.json"):  # deterministic: same bytes as the shared fixture's object
        assert (out / "dishwasher_0000" / f).read_bytes() == (generated_dir / "dishwasher_0000" / f).read_bytes()
    assert [r["id"] for r in json.loads((out / "manifest.json").read_text())["objects"]] == ["dishwasher_0000"]
    assert not list(out.glob(".tmp-*"))


def test_merge_drops_rows_whose_items_are_gone_and_damaged_rows(tmp_path):
    def merge(rows):
        return merge_manifest(tmp_path, "x", {"run": len(rows)}, "items", rows, key=lambda r: r["id"],
                              summarize=lambda all_rows: {"n": len(all_rows)},
                              present=lambda r: (tmp_path / r["id"]).is_dir())  # fmt: skip

    for name in ("a", "b"):
        (tmp_path / name).mkdir()
    merge([{"id": "a"}, {"id": "b"}])
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    manifest["items"].append({"no_id": 1})
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    (tmp_path / "b").rmdir()
    (tmp_path / "c").mkdir()
    written = merge([{"id": "c", "new": True}])
    assert [r["id"] for r in written["items"]] == ["a", "c"] and written["n"] == 2
    assert len(json.loads((tmp_path / "manifest.json").read_text())["runs"]) == 2


def test_a_second_training_run_into_the_same_folder_refuses(tmp_path):
    from centerart.training.synthetic import write_box_cabinet_dataset
    from centerart.training.train_decoder import TrainDecoderConfig, train_decoder

    data = tmp_path / "sdf"
    write_box_cabinet_dataset(data, n_objects=2, n_states=2, n_points=300, seed=0)
    out = tmp_path / "run"
    out.mkdir()
    cfg = TrainDecoderConfig(data=data, out=out, preset="tiny", epochs=1, progress=False)
    with folder_lock(out), pytest.raises(FolderBusy, match="another run is writing into this folder"):
        train_decoder(cfg)
    assert isinstance(FolderBusy(out), CenterArtError)
    assert sorted(p.name for p in out.iterdir()) == [".lock"]  # nothing written by the refused run
