"""``centerart demo``: the main job on its built-in default, end to end on a CPU in about a minute.

1. generate two checked objects of every category and render them closed, half-open and open;
2. label grasps on one oven in physics and draw them;
3. sample its SDF and reconstruct it with the shipped decoder, top grasps drawn;
4. render a kitchen scene of the generated objects with realistic (stereo) depth and its labels.

Every step calls the same code as the stage commands, at a small scale.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path


@dataclass
class DemoConfig:
    """Run every stage at a small scale and write the pictures to --out."""

    out: Path = Path("outputs/demo")
    """Output folder."""
    count: int = 2
    """Objects per category."""
    seed: int = 0
    workers: int | None = None
    """Parallel worker processes (default: all cores)."""


def run_demo(cfg: DemoConfig) -> None:
    from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
    from centerart.grasps.generate import GenerateGraspsConfig, generate_grasps
    from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes
    from centerart.sdf.generate import GenerateSdfConfig, generate_sdf
    from centerart.viz.decoder_sheet import ShowDecoderConfig, show_decoder
    from centerart.viz.grasps_sheet import ShowGraspsConfig, show_grasps
    from centerart.viz.objects_sheet import ShowObjectsConfig, show_objects
    from centerart.viz.scenes_sheet import ShowScenesConfig, show_scenes

    out = Path(cfg.out)
    objects, one, grasps, sdf, scenes = (out / name for name in ("objects", "oven", "grasps", "sdf", "kitchen"))
    # Start every run from scratch: the stage commands refuse to resume folders made with other settings (e.g.
    # by an older version of this package), which is right for datasets but would stop a rerun of the demo.
    # Only the demo's own subfolders are removed.
    for folder in (objects, one, grasps, sdf, scenes):
        if folder.is_dir():
            shutil.rmtree(folder)
    pictures = []
    print("1/4 objects")
    generate_objects(
        GenerateObjectsConfig(out=objects, category="all", count=cfg.count, seed=cfg.seed, workers=cfg.workers)
    )
    pictures.append(show_objects(ShowObjectsConfig(path=objects, out=out / "objects.png", objects_per_row=2)))

    print("2/4 grasp labels (one oven, 3 joint states)")
    # The same seed gives the same oven_0000 as in the objects folder; a folder of its own keeps the run short.
    generate_objects(GenerateObjectsConfig(out=one, category="oven", count=1, seed=cfg.seed, workers=1))
    generate_grasps(
        GenerateGraspsConfig(
            objects=one, out=grasps, states=3, per_state=60, max_trials=400, seed=cfg.seed, workers=cfg.workers
        )
    )
    pictures.append(
        show_grasps(ShowGraspsConfig(labels=grasps, objects=one, object="oven_0000", out=out / "grasps.png"))
    )

    print("3/4 SDF samples and reconstruction with the shipped decoder")
    generate_sdf(
        GenerateSdfConfig(objects=one, grasps=grasps, out=sdf, points=20000, seed=cfg.seed, workers=cfg.workers)
    )
    pictures.append(show_decoder(ShowDecoderConfig(data=sdf, object="oven_0000", out=out / "reconstruction.png")))

    print("4/4 a kitchen scene with realistic depth")
    generate_scenes(
        GenerateScenesConfig(
            objects=objects,
            out=scenes,
            layout="kitchen",
            count=1,
            views_per_scene=2,
            seed=cfg.seed,
            depth="stereo",
            workers=1,
        )
    )
    pictures.append(show_scenes(ShowScenesConfig(path=scenes, out=out / "kitchen.png")))
    print("pictures:\n" + "\n".join(f"  {p}" for p in pictures))
