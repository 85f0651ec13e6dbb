"""Recipe records written before a config field existed still resume when the plan keeps that field's old value."""

from centerart.recipe.runner import ADDED_FIELDS, _differences


def test_records_from_before_an_added_field_resume_with_its_old_value_only():
    old = {"objects": {"count": 8, "seed": 0}, "train_kitchen": {"count": 139}, "decoder": {"epochs": 150}}
    same = {
        "objects": {"count": 8, "seed": 0, "variety": "classic"},
        "train_kitchen": {"count": 139, "ir_shading": "full"},
        "decoder": {"epochs": 150, "code_weight": 1e-4},
    }
    assert _differences(old, same) == []
    new = {
        "objects": {"count": 8, "seed": 0, "variety": "extended"},
        "train_kitchen": {"count": 139, "ir_shading": "fast"},
        "decoder": {"epochs": 150, "code_weight": 0.01},
    }
    assert _differences(old, new) == [
        "decoder.code_weight: 0.0001 -> 0.01",
        "objects.variety: 'classic' -> 'extended'",
        "train_kitchen.ir_shading: 'full' -> 'fast'",
    ]
    assert set(ADDED_FIELDS) == {"variety", "ir_shading", "code_weight"}
