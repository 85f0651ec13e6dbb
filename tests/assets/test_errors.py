"""Bad input: one clear message naming the file and the problem, exit code 2, nothing half-written."""

import shutil

import pytest

from centerart.assets.articulated_object import ArticulatedObject
from centerart.cli import main
from centerart.errors import AssetError


@pytest.fixture()
def object_copy(generated_folders, tmp_path):
    dst = tmp_path / "obj"
    shutil.copytree(generated_folders[0], dst)
    return dst


def test_malformed_urdf(object_copy):
    urdf = object_copy / "mobility.urdf"
    urdf.write_text(urdf.read_text()[:-40])
    with pytest.raises(AssetError, match=r"mobility\.urdf: malformed URDF XML"):
        ArticulatedObject.load(object_copy)


def test_missing_mesh(object_copy):
    victim = sorted((object_copy / "textured_objs").glob("*.obj"))[0]
    victim.unlink()
    with pytest.raises(AssetError, match=f"missing mesh file textured_objs/{victim.name}"):
        ArticulatedObject.load(object_copy)


def test_joint_without_limits(object_copy):
    urdf = object_copy / "mobility.urdf"
    text = urdf.read_text()
    start = text.index("<limit")
    end = text.index("/>", start) + 2
    urdf.write_text(text[:start] + text[end:])
    with pytest.raises(AssetError, match="has no <limit"):
        ArticulatedObject.load(object_copy)


def test_missing_urdf(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(AssetError, match="missing URDF"):
        ArticulatedObject.load(tmp_path / "empty")


def test_unknown_category_cli(tmp_path, capsys):
    out = tmp_path / "objs"
    with pytest.raises(SystemExit) as exc:
        main(["objects", "generate", "--category", "toaster", "--out", str(out)])
    assert exc.value.code == 2
    assert "toaster" in capsys.readouterr().err
    assert not out.exists()


def test_cli_reports_asset_errors_in_one_line(object_copy, tmp_path, capsys):
    (object_copy / "mobility.urdf").write_text("<robot name='x'><link name='a'></robot>")
    code = main(["objects", "show", str(object_copy), "--out", str(tmp_path / "x.png")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.strip().splitlines()[-1].startswith("centerart: error:") and "mobility.urdf: malformed URDF XML" in err
    assert "Traceback" not in err
    assert not (tmp_path / "x.png").exists()
