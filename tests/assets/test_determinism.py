"""Same seed, same files; and a golden summary that changes only when the generator is changed on purpose.

Refresh the golden file after a deliberate generator change with:
    CENTERART_UPDATE_GOLDEN=1 python -m pytest tests/assets/test_determinism.py
"""

import json
import os
from pathlib import Path

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.dataset import GenerateObjectsConfig, generate_objects

GOLDEN = Path(__file__).parent / "golden" / "objects_seed0.json"


def _files(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name != "manifest.json"
    }


def test_same_seed_same_files(generated_dir, tmp_path):
    again = tmp_path / "again"
    generate_objects(GenerateObjectsConfig(out=again, category="all", count=1, seed=0, workers=2))
    a, b = _files(generated_dir), _files(again)
    assert a.keys() == b.keys()
    differing = [k for k in a if a[k] != b[k]]
    assert not differing, differing[:5]


def test_other_seed_other_objects(generated_dir, tmp_path):
    other = tmp_path / "other"
    generate_objects(GenerateObjectsConfig(out=other, category="microwave", count=1, seed=1, workers=1))
    a = ArticulatedObject.load(generated_dir / "microwave_0000").extents
    b = ArticulatedObject.load(other / "microwave_0000").extents
    assert not np.allclose(a, b)


def _summary(folder: Path) -> dict:
    obj = ArticulatedObject.load(folder)
    return {
        "extents": np.round(obj.extents, 5).tolist(),
        "target_joint": obj.target_joint,
        "joint_type": obj.joint_type,
        "joint_range": np.round(obj.joint_range, 5).tolist(),
        "axis": np.round(obj.target_axis().direction, 5).tolist(),
        "handles": sorted(h["type"] for h in obj.meta["handles"]),
        "links": len(obj.links),
        "triangles": obj.meta["generator"]["record"]["triangles"],
    }


def test_golden_summary(generated_folders):
    summary = {f.name: _summary(f) for f in generated_folders}
    if os.environ.get("CENTERART_UPDATE_GOLDEN") == "1" or not GOLDEN.exists():
        GOLDEN.parent.mkdir(exist_ok=True)
        GOLDEN.write_text(json.dumps(summary, indent=1) + "\n")
    golden = json.loads(GOLDEN.read_text())
    assert golden.keys() == summary.keys()
    for key, expected in golden.items():
        got = summary[key]
        for field, value in expected.items():
            if isinstance(value, list) and value and isinstance(value[0], float):
                np.testing.assert_allclose(got[field], value, atol=2e-5, err_msg=f"{key}.{field}")
            else:
                assert got[field] == value, f"{key}.{field}: {got[field]} != {value}"
