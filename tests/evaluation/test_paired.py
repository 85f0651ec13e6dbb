"""Pairing two closed-loop evaluations (``evaluation.paired``): counts on hand-made records, the sign test on views
and on distinct objects, where the two disagree, and a folder without records as one error naming it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from centerart.errors import CenterArtError
from centerart.evaluation.paired import paired_table, read_outcomes, sign_test_p


def _write(out: Path, outcomes: dict[tuple[str, str], list[bool]]) -> Path:
    """An eval output whose single set holds one scene per (object, view) with the given outcomes."""
    folder = out / "records" / "single-0123abcd"
    folder.mkdir(parents=True)
    for obj, views in outcomes.items():
        for v, ok in enumerate(views):
            scene = f"{obj[0]}_{v}"
            row = {"scene": scene, "view": 0, "depth": "realistic", "method": "centerart[pose]", "instance": 1,
                   "object_id": obj[0], "sr_image": ok}  # fmt: skip
            baseline = {**row, "method": "baseline"}  # other methods' rows are not paired
            (folder / f"{scene}.json").write_text(json.dumps({"rows": [row, baseline]}))
    return out


def test_views_and_objects_are_counted_apart(tmp_path):
    # Object x: a opens 4 of its 4 views, b none (4 discordant views, one object for a); objects y1..y3: b opens
    # their one view, a does not (3 views, three objects for b); z: both open it.
    a = {("x",): [True] * 4, ("y1",): [False], ("y2",): [False], ("y3",): [False], ("z",): [True]}
    b = {("x",): [False] * 4, ("y1",): [True], ("y2",): [True], ("y3",): [True], ("z",): [True]}
    table = paired_table(read_outcomes(_write(tmp_path / "a", a)), read_outcomes(_write(tmp_path / "b", b)))
    single = table["sets"]["single"]
    assert (single["objects"], single["both"], single["only_a"], single["only_b"]) == (8, 1, 4, 3)
    assert (single["distinct_objects"], single["objects_a_better"], single["objects_b_better"]) == (5, 1, 3)
    assert single["sign_test_p"] == round(sign_test_p(4, 3), 4) == 1.0
    assert single["object_sign_test_p"] == round(sign_test_p(1, 3), 4) == 0.625
    assert table["sets"]["all"]["objects"] == 8 and table["rows_only_in_a"] == table["rows_only_in_b"] == 0


def test_many_views_of_one_object_are_not_many_objects(tmp_path):
    # Ten views of one object all favour a: certain for views (p 0.002), one object for objects (p 1).
    table = paired_table(read_outcomes(_write(tmp_path / "a", {("x",): [True] * 10})),
                         read_outcomes(_write(tmp_path / "b", {("x",): [False] * 10})))  # fmt: skip
    single = table["sets"]["single"]
    assert single["sign_test_p"] == 0.002 and single["object_sign_test_p"] == 1.0


def test_a_folder_without_records_is_one_error_naming_it(tmp_path):
    with pytest.raises(CenterArtError, match=str(tmp_path)):
        read_outcomes(tmp_path)


def test_the_cli_prints_the_table_and_refuses_bad_folders_in_one_line(tmp_path, capsys):
    from centerart.cli import main

    a = _write(tmp_path / "a", {("x",): [True, True], ("y",): [False]})
    b = _write(tmp_path / "b", {("x",): [False, True], ("y",): [True]})
    assert main(["eval", "compare", "--a", str(a), "--b", str(b), "--out", str(tmp_path / "t.json")]) == 0
    assert "| single | 3 | 1 | 1 | 1 | 1.000 | 2 | 1 | 1 | 1.000 |" in capsys.readouterr().out
    assert json.loads((tmp_path / "t.json").read_text())["sets"]["single"]["distinct_objects"] == 2
    assert main(["eval", "compare", "--a", str(a), "--b", str(tmp_path / "nothing")]) == 2
    err = capsys.readouterr().err
    assert "nothing: no records" in err and "Traceback" not in err
