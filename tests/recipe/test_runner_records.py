"""Recipe records written before a config field existed still resume when the plan keeps that field's old value."""

from centerart.recipe.runner import ADDED_FIELDS, _differences


def test_records_from_before_an_added_field_resume_with_its_old_value_only():
    old = {"objects": {"count": 8, "seed": 0}, "train_kitchen": {"count": 139}}
    same = {
        "objects": {"count": 8, "seed": 0, "variety": "classic"},
        "train_kitchen": {"count": 139, "ir_shading": "full"},
    }
    assert _differences(old, same) == []
    new = {
        "objects": {"count": 8, "seed": 0, "variety": "extended"},
        "train_kitchen": {"count": 139, "ir_shading": "fast"},
    }
    assert _differences(old, new) == [
        "objects.variety: 'classic' -> 'extended'",
        "train_kitchen.ir_shading: 'full' -> 'fast'",
    ]
    assert set(ADDED_FIELDS) == {"variety", "ir_shading"}
