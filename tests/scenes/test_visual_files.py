"""Real objects whose material files name missing texture images (``scenes.visual_files``): the mesh loads from a
copy whose materials drop the missing maps and name the present ones by absolute path; a mesh whose maps all exist
loads as it is; a scene of such a PartNet-Mobility object renders (SAPIEN stopped with a filesystem error before)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from centerart.scenes.visual_files import loadable_visual

PARTNET_DEV = Path(__file__).resolve().parents[3] / "shared" / "partnet-mobility-dev"


def _mesh(folder: Path, maps: list[str]) -> Path:
    """A one-triangle OBJ whose material names ``maps`` as diffuse / bump images (relative paths)."""
    objs = folder / "textured_objs"
    objs.mkdir(parents=True)
    statements = [f"map_Kd {maps[0]}", *(f"map_Bump -bm 1.0 {m}" for m in maps[1:])]
    (objs / "a.mtl").write_text("\n".join(["newmtl m", "Kd 0.8 0.2 0.2", *statements]) + "\n")
    (objs / "a.obj").write_text("mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n")
    return objs / "a.obj"


def test_a_mesh_with_a_missing_image_loads_from_a_mended_copy(tmp_path):
    obj = _mesh(tmp_path / "object", ["../images/gone.jpg", "../images/there.png"])
    (tmp_path / "object" / "images").mkdir()
    (tmp_path / "object" / "images" / "there.png").write_bytes(b"png")
    copy = loadable_visual(obj, tmp_path / "cache")
    assert copy != obj and copy.read_text() == obj.read_text()
    material = (copy.parent / "a.mtl").read_text()
    assert "gone.jpg" not in material and "Kd 0.8 0.2 0.2" in material  # the colour stays
    assert f"map_Bump -bm 1.0 {(tmp_path / 'object' / 'images' / 'there.png').resolve()}" in material
    assert loadable_visual(obj, tmp_path / "cache") == copy  # made once, then reused


def test_a_mesh_whose_images_exist_loads_as_it_is(tmp_path):
    obj = _mesh(tmp_path / "object", ["../images/there.png"])
    (tmp_path / "object" / "images").mkdir()
    (tmp_path / "object" / "images" / "there.png").write_bytes(b"png")
    assert loadable_visual(obj, tmp_path / "cache") == obj and not (tmp_path / "cache").exists()


def test_a_real_object_without_its_images_folder_renders(tmp_path):
    source = PARTNET_DEV / "19825"  # a table whose 21 materials name ../images/, which its copy lacks
    if not (source / "mobility.urdf").is_file():
        pytest.skip(f"PartNet-Mobility dev objects not found at {PARTNET_DEV}")
    from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes

    (tmp_path / "objects").mkdir()
    (tmp_path / "objects" / "19825").symlink_to(source)
    generate_scenes(GenerateScenesConfig(objects=tmp_path / "objects", out=tmp_path / "scenes", layout="single",
                                         count=1, views_per_scene=1, seed=1, depth="true", intrinsics="tiny",
                                         save_ir=False, workers=1))  # fmt: skip
    from PIL import Image

    rgb = np.asarray(Image.open(next((tmp_path / "scenes").glob("scene_*/views/00/rgb.png"))))
    assert rgb.shape == (240, 320, 3) and rgb.std() > 10  # an image, not a blank frame
