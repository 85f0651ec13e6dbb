"""The demo's comparison table on hand-made records (no model run): the top grasp's source and whether it touches
observed material (closing points against the anchoring threshold the record was predicted with; n/a when
anchoring was off)."""

from __future__ import annotations

import numpy as np

from centerart.demo import compare_with_labels, min_closing_points, print_comparison, top_grasp_check

POSE = np.eye(4)
POSE[:3, 3] = [0.0, 0.0, 1.5]


def predicted(grasps: list[dict], u: float) -> dict:
    return {"peak_uv": [u, 100.0], "camera_T_object": POSE.tolist(), "grasps": grasps,
            "joint": {"type": "revolute", "state": 0.3}}  # fmt: skip


def label(name: str, x0: float) -> dict:
    return {"object_id": name, "visible_fraction": 0.9, "bbox_xyxy": [x0, 50, x0 + 100, 150],
            "camera_T_object": POSE.tolist(), "joint": {"type": "revolute", "state": 0.25}}  # fmt: skip


def test_top_grasp_check():
    assert top_grasp_check({"grasps": [{"source": "handle", "closing_points": 8}]}, 8) == {
        "top_grasp_source": "handle", "top_grasp_on_material": "yes"}  # fmt: skip
    assert top_grasp_check({"grasps": [{"source": "decoder", "closing_points": 3}]}, 8)["top_grasp_on_material"] == "no"
    off = top_grasp_check({"grasps": [{"score": 0.5}]}, 8)
    assert off == {"top_grasp_source": None, "top_grasp_on_material": "n/a"}
    assert top_grasp_check({"grasps": []}, 8)["top_grasp_on_material"] == "no grasp"
    assert min_closing_points({"config": {"anchoring": {"checks": {"min_closing_points": 20}}}}) == 20
    assert min_closing_points({}) == 8  # an older record: the default threshold


def test_table_column(capsys):
    record = {
        "config": {"anchoring": {"enabled": True, "checks": {"min_closing_points": 10}}},
        "objects": [
            predicted([{"source": "observed", "closing_points": 25}, {"source": "decoder", "closing_points": 2}], 50),
            predicted([{"source": "decoder", "closing_points": 9}], 250),
            predicted([{"score": 0.4}], 450),  # as written with anchoring off
        ],
    }
    rows = compare_with_labels(record, {"objects": [label(n, x) for n, x in (("a", 0), ("b", 200), ("c", 400))]})
    assert [r["top_grasp_on_material"] for r in rows] == ["yes", "no", "n/a"]
    assert [r["top_grasp_source"] for r in rows] == ["observed", "decoder", None]
    print_comparison(rows)
    lines = capsys.readouterr().out.splitlines()
    assert "grasp on material" in lines[0] and lines[0].split()[-1] == "from"
    assert lines[1].split()[-2:] == ["yes", "observed"]
    assert lines[2].split()[-2:] == ["no", "decoder"]
    assert lines[3].split()[-2:] == ["n/a", "-"]
