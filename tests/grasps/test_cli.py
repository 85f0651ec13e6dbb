"""The grasp commands through the real CLI entry point."""

from __future__ import annotations

from centerart.cli import main


def test_help_lists_grasp_commands(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert "grasps generate" in out and "grasps show" in out


def test_generate_on_a_folder_without_objects_is_one_line_error(tmp_path, capsys):
    assert main(["grasps", "generate", "--objects", str(tmp_path), "--out", str(tmp_path / "labels")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no object folders" in err[0]


def test_generate_rejects_zero_states(tmp_path, capsys):
    assert main(["grasps", "generate", "--objects", str(tmp_path), "--out", str(tmp_path), "--states", "0"]) == 2
    assert "--states must be >= 1" in capsys.readouterr().err
