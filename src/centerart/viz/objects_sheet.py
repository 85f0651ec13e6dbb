"""``centerart objects show``: every object at closed, half-open and open, as shaded renders."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import numpy as np
import tyro
from tqdm.auto import tqdm

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.dataset import list_objects
from centerart.utils.checks import at_least
from centerart.viz.contact_sheet import grid, labelled, save_png


@dataclass
class ShowObjectsConfig:
    """Render a contact sheet of articulated objects at several states of their target joint."""

    path: Annotated[Path, tyro.conf.Positional]
    """An object folder, or a folder of object folders (generated or PartNet-Mobility)."""
    out: Path = Path("objects.png")
    """PNG file to write."""
    states: int = 3
    """States per object, evenly from closed to fully open."""
    objects_per_row: int = 4
    max_objects: int = 120
    """Render at most this many objects (sorted by name)."""
    image_width: int = 240
    image_height: int = 180

    def __post_init__(self):
        for name in ("states", "objects_per_row", "max_objects", "image_width", "image_height"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 1)


def show_objects(cfg: ShowObjectsConfig) -> Path:
    from centerart.viz.object_renderer import ObjectRenderer

    folders = list_objects(cfg.path)[: cfg.max_objects]
    # Load (and so validate) every object before rendering anything: a bad folder fails fast, no partial sheet.
    objects = [ArticulatedObject.load(folder) for folder in folders]
    renderer = ObjectRenderer(cfg.image_width, cfg.image_height)
    tiles = []
    for obj in tqdm(objects, desc="render", unit="object"):
        lo, hi = obj.joint_range
        qs = list(np.linspace(lo, hi, cfg.states))
        images = renderer.render_states(obj, qs)
        unit = "rad" if obj.joint_type == "revolute" else "m"
        tiles.append([labelled(img, f"{obj.object_id}  q={q:.2f} {unit}") for img, q in zip(images, qs, strict=True)])
    rows = []
    for start in range(0, len(tiles), cfg.objects_per_row):
        rows.append([img for tile in tiles[start : start + cfg.objects_per_row] for img in tile])
    return save_png(grid(rows), cfg.out)
