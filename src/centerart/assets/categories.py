"""Object categories: the paper's five, with PartNet-Mobility's spelling mapped to ours."""

from __future__ import annotations

from typing import Literal

Category = Literal["microwave", "oven", "refrigerator", "dishwasher", "storage_furniture"]
CATEGORIES: tuple[str, ...] = ("microwave", "oven", "refrigerator", "dishwasher", "storage_furniture")

#: PartNet-Mobility ``meta.json`` ``model_cat`` -> our category name.
PARTNET_CATEGORY = {
    "Microwave": "microwave",
    "Oven": "oven",
    "Refrigerator": "refrigerator",
    "Dishwasher": "dishwasher",
    "StorageFurniture": "storage_furniture",
}
#: And back, for writing generated objects in PartNet-Mobility layout.
MODEL_CAT = {v: k for k, v in PARTNET_CATEGORY.items()}


def normalize_category(model_cat: str) -> str:
    """Map a ``model_cat`` (e.g. ``StorageFurniture``) or our own name to our snake_case name."""
    if model_cat in PARTNET_CATEGORY:
        return PARTNET_CATEGORY[model_cat]
    snake = "".join("_" + c.lower() if c.isupper() else c for c in model_cat).lstrip("_")
    return snake.replace(" ", "_")
