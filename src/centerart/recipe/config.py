"""The recipe's configuration: one dataclass per step, the whole pipeline's config, and the named presets.

A preset is a complete :class:`RecipeConfig` (every step's sizes, resolutions and epochs); the command line starts
from the chosen preset's values and overrides any of them (``centerart recipe --preset small --decoder.epochs 300``).
Python: ``recipe_preset("small", out=Path("runs/small"))``, then change fields with :func:`dataclasses.replace`.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Literal, get_args

StepName = Literal["objects", "grasps", "sdf", "decoder", "scenes", "encoder", "evaluation"]
STEPS: tuple[str, ...] = get_args(StepName)
PresetName = Literal["tiny", "small", "paper"]


@dataclass
class ObjectsStep:
    """Procedural objects: training objects (``--seed``) and held-out test objects (``--test-seed``)."""

    count: int = 8
    """Training objects per category; the decoder holds a share of them out for validation (never trained on)."""
    test_count: int = 4
    """Test objects per category, generated with ``--test-seed``: no model sees them; the evaluation runs on them."""
    category: Literal["microwave", "oven", "refrigerator", "dishwasher", "storage_furniture", "all"] = "all"
    variety: Literal["classic", "extended"] = "classic"
    """Object variety of training and test objects (``centerart objects generate --variety``)."""


@dataclass
class GraspsStep:
    """Physics-verified grasp labels of the training objects (``centerart grasps generate``)."""

    states: int = 6
    per_state: int = 100
    max_trials: int = 400
    max_candidates: int = 12000
    keep_failures: int = 2000


@dataclass
class SdfStep:
    """SDF samples with nearest-grasp targets (``centerart sdf generate``)."""

    points: int = 50_000


@dataclass
class DecoderStep:
    """Auto-decoder training of the SGDF decoder (``centerart train decoder``)."""

    preset: Literal["tiny", "small", "paper"] = "small"
    epochs: int = 150
    batch_items: int = 8
    points_per_item: int = 2048
    min_items_per_epoch: int = 256
    max_points_per_state: int = 40000
    lr_decoder: float = 1e-3
    lr_codes: float = 2e-3
    code_weight: float = 1e-2
    """Weight of the code prior (``centerart train decoder --code-weight``; the shipped files since session 13)."""
    heldout_object_fraction: float = 0.15
    """Share of the training objects held out of decoder training; their scenes validate the encoder."""
    heldout_states_per_object: int = 1
    val_every: int = 25
    val_code_fit_steps: int = 100
    threads: int = 1
    """torch CPU threads (0: torch default)."""


@dataclass
class ScenesStep:
    """Rendered scenes (``centerart scenes generate``): counts of scenes per set; a set of 0 scenes is skipped.

    ``train_*``: the decoder's training objects (labels carry their shape codes); ``val_*``: the decoder's held-out
    objects (encoder validation); ``test_*``: the test objects (evaluation)."""

    intrinsics: Literal["d415", "paper", "tiny"] = "d415"
    depth: Literal["true", "stereo", "analytic"] = "stereo"
    train_intrinsics: Literal["d415", "d415-half", "paper", "tiny"] | None = None
    """Camera of the training sets (default: ``intrinsics``). ``d415-half`` renders at the small encoder's input
    size (320x240), with ``train_depth stereo-model`` about 10x faster per view (``centerart slices``' cheap data);
    validation and test sets keep ``intrinsics`` and ``depth``."""
    train_depth: Literal["true", "stereo", "stereo-model", "analytic"] | None = None
    """Realistic depth of the training sets (default: ``depth``). ``stereo-model``: the full-size stereo sensor's
    measured errors drawn from the true depth, at any size (docs/scenes.md)."""
    train_kitchen: int = 139
    train_single: int = 120
    val_kitchen: int = 15
    val_single: int = 20
    test_kitchen: int = 50
    test_single: int = 100
    kitchen_views: int = 2
    single_views: int = 1
    save_ir: bool = False
    ir_shading: Literal["fast", "full"] = "fast"
    """Stereo IR pair: ``fast`` (shaded from geometry) or ``full`` (lit render; recipe runs recorded before this
    option made their scenes so, and resume only with it)."""


@dataclass
class EncoderStep:
    """RGB-D encoder training against the recipe's decoder (``centerart train encoder``)."""

    preset: Literal["tiny", "small", "paper"] = "small"
    epochs: int = 56
    batch_size: int = 8
    lr: float = 1e-3
    val_every: int = 5
    loader_workers: int = 1
    threads: int = 2
    """torch CPU threads (0: torch default)."""


@dataclass
class EvaluationStep:
    """Closed-loop evaluation on the test scenes (``centerart eval scenes``)."""

    depth: tuple[Literal["true", "realistic"], ...] = ("true", "realistic")
    labels_per_state: int = 100
    label_max_trials: int = 400
    shape: bool = True
    ablation: bool = True
    oracle: bool = True
    baseline: bool = True
    max_scenes: int | None = None
    """Evaluate only the first N scenes of each test set."""
    threads: int = 1


@dataclass
class RecipeConfig:
    """From nothing to trained, evaluated models: objects -> grasp labels -> SDF samples -> decoder -> scenes ->
    encoder -> evaluation on held-out objects. Rerun the same command to resume; finished steps are skipped."""

    out: Path
    """Output folder: one subfolder per step and OUT/manifest.json for the whole run."""
    preset: PresetName = "small"
    """Named full-pipeline configuration (tiny: tests, minutes; small: the shipped models, hours on a CPU;
    paper: the paper's scale, for GPUs and a cluster); every value below starts from it."""
    seed: int = 0
    """Seed of the training objects, labels, samples, scenes and training."""
    test_seed: int = 9000
    """Seed of the held-out test objects and their scenes; must differ from --seed."""
    until: StepName | None = None
    """Stop after this step (later steps run on a later call)."""
    workers: int | None = None
    """Processes of the data steps and the evaluation (default: all cores)."""
    ray_address: str | None = None
    """Run the data steps (objects, grasps, SDF, scenes) on a Ray cluster at this address (auto, ray://host:10001),
    or local for a private Ray instance on this machine."""
    accelerator: Literal["auto", "cpu", "gpu"] = "auto"
    """Training device kind (decoder and encoder)."""
    devices: int = 1
    """Training devices per node; more than one trains with DDP."""
    num_nodes: int = 1
    """Training machines (DDP); start the recipe on every node with the cluster's launcher (README)."""
    strategy: Literal["auto", "ddp", "ddp_spawn"] = "auto"
    """Training strategy; auto: one process for one device, else ddp_spawn on one node and ddp across nodes."""
    progress: bool = True
    decoder_from: Path | None = None
    """Adopt the finished decoder of this earlier recipe run (its output folder, or a copy of its manifest.json and
    decoder/) instead of training one: same decoder settings and same training objects required."""
    objects: ObjectsStep = field(default_factory=ObjectsStep)
    grasps: GraspsStep = field(default_factory=GraspsStep)
    sdf: SdfStep = field(default_factory=SdfStep)
    decoder: DecoderStep = field(default_factory=DecoderStep)
    scenes: ScenesStep = field(default_factory=ScenesStep)
    encoder: EncoderStep = field(default_factory=EncoderStep)
    evaluation: EvaluationStep = field(default_factory=EvaluationStep)

    def steps(self) -> tuple[str, ...]:
        """The steps this call runs, in order (all of them, or up to ``until``)."""
        return STEPS if self.until is None else STEPS[: STEPS.index(self.until) + 1]

    def training_strategy(self) -> str:
        """The Lightning strategy for the training steps (see ``strategy``)."""
        if self.strategy != "auto" or self.devices * self.num_nodes == 1:
            return self.strategy
        # On one node the recipe stays the single driver process: it spawns the training processes itself.
        return "ddp_spawn" if self.num_nodes == 1 else "ddp"


# ---------------------------------------------------------------------------- presets
_SMALL = RecipeConfig(out=Path("runs/recipe-small"), preset="small")
"""The shipped models' scale (src/centerart/weights/README.md): 8 objects per category, 6 states x 100 labels,
50k SDF points, small decoder 150 epochs; 139 + 120 training scenes of the decoder's objects, 15 + 20 validation
scenes of its held-out objects at 640x480 with stereo depth; small encoder 56 epochs; 4 test objects per category
(seed 9000) in 100 single and 50 kitchen scenes."""

_TINY = RecipeConfig(
    out=Path("runs/recipe-tiny"),
    preset="tiny",
    objects=ObjectsStep(count=1, test_count=1),
    grasps=GraspsStep(states=2, per_state=4, max_trials=30, max_candidates=300, keep_failures=20),
    sdf=SdfStep(points=3000),
    decoder=DecoderStep(
        preset="tiny",
        epochs=3,
        batch_items=4,
        points_per_item=256,
        min_items_per_epoch=16,
        max_points_per_state=3000,
        lr_decoder=2e-3,
        lr_codes=2e-3,
        heldout_object_fraction=0.2,
        val_every=3,
        val_code_fit_steps=5,
    ),
    scenes=ScenesStep(
        intrinsics="tiny", train_kitchen=2, train_single=0, val_kitchen=0, val_single=1, test_kitchen=0, test_single=2
    ),
    encoder=EncoderStep(preset="tiny", epochs=2, batch_size=2, val_every=2, loader_workers=0, threads=1),
    evaluation=EvaluationStep(depth=("realistic",), labels_per_state=5, label_max_trials=40, shape=False),
)
"""Tests: 5 + 5 objects, 2 states, a few labels and points, 3 + 2 epochs, 5 tiny (320x240) scenes."""

_PAPER = RecipeConfig(
    out=Path("runs/recipe-paper"),
    preset="paper",
    objects=ObjectsStep(count=100, test_count=20),
    grasps=GraspsStep(states=10, per_state=500, max_trials=3000),
    sdf=SdfStep(points=100_000),
    decoder=DecoderStep(
        preset="paper", epochs=300, batch_items=32, lr_decoder=5e-4, lr_codes=1e-3, val_every=25, threads=0
    ),
    scenes=ScenesStep(
        intrinsics="paper",
        train_kitchen=5000,
        train_single=2000,
        val_kitchen=250,
        val_single=200,
        test_kitchen=200,
        test_single=500,
    ),
    encoder=EncoderStep(preset="paper", epochs=100, batch_size=16, lr=6e-4, loader_workers=4, threads=0),
    evaluation=EvaluationStep(),
)
"""The paper's scale on GPUs and a cluster: 500 training objects, 10 states x 500 labels, 100k SDF points, the
8 x 512 decoder, 7000 training scenes at the paper's 960x512 camera, the ResNet-50-layout encoder; 100 test objects."""

PRESETS: dict[str, RecipeConfig] = {"tiny": _TINY, "small": _SMALL, "paper": _PAPER}


def recipe_preset(name: str, **overrides) -> RecipeConfig:
    """A fresh copy of preset ``name`` with top-level fields replaced (``out=...``, ``seed=...``)."""
    if name not in PRESETS:
        raise ValueError(f"unknown recipe preset {name!r}; choose from {', '.join(PRESETS)}")
    cfg = copy.deepcopy(PRESETS[name])
    known = {f.name for f in fields(RecipeConfig)}
    for key, value in overrides.items():
        if key not in known:
            raise ValueError(f"unknown recipe field {key!r}")
        setattr(cfg, key, value)
    return cfg


def cli_default(argv: list[str]) -> RecipeConfig:
    """The defaults the command line starts from: the preset named by ``--preset`` in ``argv`` (default small),
    with ``out`` left for the user to give (``tyro.MISSING``)."""
    import tyro

    name = "small"
    for i, arg in enumerate(argv):
        if arg == "--preset" and i + 1 < len(argv):
            name = argv[i + 1]
        elif arg.startswith("--preset="):
            name = arg.split("=", 1)[1]
    cfg = recipe_preset(name if name in PRESETS else "small")
    cfg.out = tyro.MISSING
    return cfg
