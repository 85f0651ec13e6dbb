"""The ledger's per-slice wall-time count (issue 29): a slice trained across calls records what all of them cost."""

from __future__ import annotations

import pytest

from centerart.errors import CenterArtError
from centerart.recipe.ledger import CALLS, add_call_wall


def test_each_call_adds_its_wall_time_to_the_slices_total(tmp_path):
    assert add_call_wall(tmp_path, {"data": 60.0, "train": 1200.04}) == {
        "calls": 1,
        "wall_s": {"data": 60.0, "train": 1200.0},
    }
    totals = add_call_wall(tmp_path, {"data": 5.0, "train": 300.0})
    assert totals == {"calls": 2, "wall_s": {"data": 65.0, "train": 1500.0}}
    assert (tmp_path / CALLS).is_file()


def test_a_damaged_count_is_one_error_naming_the_file(tmp_path):
    (tmp_path / CALLS).write_text("{not json")
    with pytest.raises(CenterArtError, match=CALLS):
        add_call_wall(tmp_path, {"train": 1.0})
