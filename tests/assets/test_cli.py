"""The objects CLI end to end: generate (resumable, manifest) and show (a real SAPIEN render)."""

import json

import numpy as np
from PIL import Image

from centerart.cli import main


def test_generate_resume_and_manifest(tmp_path, capsys):
    out = tmp_path / "objs"
    assert (
        main(["objects", "generate", "--category", "dishwasher", "--count", "2", "--out", str(out), "--workers", "1"])
        == 0
    )
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["counts"]["dishwasher"]["objects"] == 2
    assert manifest["config"]["seed"] == 0 and "code_version" in manifest
    first = (out / "dishwasher_0000" / "mobility.urdf").read_bytes()
    # an interrupted run leaves a temporary folder; the next run removes it and resumes
    (out / ".tmp-dishwasher_0002-abc").mkdir()
    assert (
        main(["objects", "generate", "--category", "dishwasher", "--count", "3", "--out", str(out), "--workers", "1"])
        == 0
    )
    manifest = json.loads((out / "manifest.json").read_text())
    assert [r.get("resumed", False) for r in manifest["objects"]] == [True, True, False]
    assert (out / "dishwasher_0000" / "mobility.urdf").read_bytes() == first
    assert not list(out.glob(".tmp-*"))


def test_show_writes_a_contact_sheet(generated_folders, tmp_path):
    png = tmp_path / "sheet.png"
    assert (
        main(
            [
                "objects",
                "show",
                str(generated_folders[0].parent),
                "--out",
                str(png),
                "--max-objects",
                "2",
                "--image-width",
                "160",
                "--image-height",
                "120",
            ]
        )
        == 0
    )
    img = np.asarray(Image.open(png))
    assert img.shape[0] > 120 and img.shape[1] > 3 * 160
    # the renders are not blank: objects add contrast against the floor
    assert img[..., :3].std() > 20


def test_help_lists_commands(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert "objects generate" in out and "objects show" in out
