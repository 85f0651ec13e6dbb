"""``centerart demo``: the main job on its built-in default.

For now: generate a few checked objects of every category and write their contact sheet. It grows into the full
image-to-grasps prediction as later stages land.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
from centerart.viz.objects_sheet import ShowObjectsConfig, show_objects


@dataclass
class DemoConfig:
    """Generate a few objects of every category and render them at closed, half-open and open."""

    out: Path = Path("outputs/demo")
    """Output folder."""
    count: int = 2
    """Objects per category."""
    seed: int = 0


def run_demo(cfg: DemoConfig) -> None:
    objects = Path(cfg.out) / "objects"
    generate_objects(GenerateObjectsConfig(out=objects, category="all", count=cfg.count, seed=cfg.seed))
    sheet = show_objects(ShowObjectsConfig(path=objects, out=Path(cfg.out) / "objects.png", objects_per_row=2))
    print(f"objects in {objects}\npicture: {sheet}")
