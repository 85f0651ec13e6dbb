"""The plan of a sliced training run (``RUN/run.json``) and its named presets.

A sliced run trains the RGB-D encoder across working periods: each ``centerart slices next`` renders a new slice
of scenes (new seeds) of the decoder's training objects, continues the run's state on them and validates on a
fixed set of the decoder's held-out objects. The plan fixes what every slice shares (the model, the decoder, the
objects, the validation set, the seed); what may change between slices (scene counts, steps, learning-rate
scale) has defaults here and is recorded per slice in the ledger (:mod:`centerart.recipe.ledger`).
"""

from __future__ import annotations

import copy
from dataclasses import asdict, dataclass, field
from typing import Literal

from centerart.errors import CenterArtError
from centerart.models.encoder.losses import EncoderLossConfig
from centerart.training.encoder_augment import AugmentConfig

#: First scene seed of slice k is SLICE_SEED_BASE + SLICE_SEED_STRIDE * k (kitchens; singles + SINGLE_OFFSET):
#: far above every seed a test set uses (the recipe's 9000 + 100/200, the repository's 9100-9400).
SLICE_SEED_BASE = 100_000
SLICE_SEED_STRIDE = 1_000
SINGLE_OFFSET = 500
#: A run's ``seed_block`` b moves its seeds by b x SEED_BLOCK_STRIDE: runs that continue one another's encoder
#: (``--init`` of a sliced run's output) draw other scenes than the ones their start was trained on.
SEED_BLOCK_STRIDE = 1_000_000


@dataclass
class SliceData:
    """The scenes one slice renders (``centerart scenes generate`` settings) and trains on."""

    kitchen: int = 300
    """Kitchen scenes (2-5 objects each)."""
    single: int = 300
    """Single-object scenes."""
    kitchen_views: int = 2
    single_views: int = 1
    intrinsics: Literal["d415", "d415-half", "paper", "tiny"] = "d415"
    depth: Literal["true", "stereo", "stereo-model", "analytic"] = "stereo"
    ir_shading: Literal["fast", "full"] = "fast"

    def images(self) -> int:
        return self.kitchen * self.kitchen_views + self.single * self.single_views


@dataclass
class ValidationSet:
    """The fixed validation scenes of the decoder's held-out objects (the recipe's val sets at seed 0)."""

    kitchen: int = 15
    single: int = 20
    kitchen_seed: int = 300
    single_seed: int = 400
    kitchen_views: int = 2
    intrinsics: Literal["d415", "paper", "tiny"] = "d415"
    depth: Literal["true", "stereo", "analytic"] = "stereo"


@dataclass
class SlicePlan:
    """What every slice of a run shares (``RUN/run.json``)."""

    preset: str
    encoder_preset: Literal["tiny", "small", "paper"] = "small"
    encoder: dict = field(default_factory=dict)
    """The encoder config (code_dim aside) as the run was made; empty in plans saved before it was recorded."""
    decoder: str = "src/centerart/weights/sgdf_small.pt"
    """Decoder checkpoint whose shape codes are the targets (relative to the repository root, or absolute)."""
    decoder_sha256: str = ""
    objects_seed: int = 0
    objects_count: int = 8
    """Objects per category generated with ``objects_seed`` (a new run takes it from its decoder's objects); the
    decoder's training objects among them are the slices' objects, its held-out objects the validation set's
    (checked by content fingerprint)."""
    variety: Literal["classic", "extended"] = "classic"
    seed: int = 0
    """Seed of the initial weights, batch order and augmentation."""
    seed_block: int = 0
    """Block of scene seeds of this run (:func:`slice_seeds`); a run started from another run's encoder takes
    another block."""
    init: str | None = None
    """Encoder checkpoint the run starts from (None: weights drawn from ``seed``)."""
    init_sha256: str = ""
    init_other_decoder: bool = False
    """True when ``init`` was trained against another decoder's codes (a run made with ``--decoder``): its shape
    head is then only a warm start, and nothing checks it against this run's decoder."""
    batch_size: int = 8
    lr: float = 1e-3
    warmup_steps: int = 500
    steps: int = 6000
    """Default optimizer steps per slice."""
    data: SliceData = field(default_factory=SliceData)
    validation: ValidationSet = field(default_factory=ValidationSet)
    augment: dict = field(default_factory=lambda: AugmentConfig().to_dict())
    loss: dict = field(default_factory=lambda: EncoderLossConfig().to_dict())

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> SlicePlan:
        try:
            return cls(
                **{k: v for k, v in data.items() if k not in ("data", "validation")},
                data=SliceData(**data.get("data", {})),
                validation=ValidationSet(**data.get("validation", {})),
            )
        except TypeError as err:
            raise CenterArtError(f"run.json: not a slice plan ({err})") from None

    def augment_config(self) -> AugmentConfig:
        cfg = dict(self.augment)
        cfg["scale_range"] = tuple(cfg["scale_range"])
        return AugmentConfig(**cfg)


def slice_seeds(index: int, block: int = 0) -> dict[str, int]:
    """Scene seeds of slice ``index`` (1-based) of a run with seed block ``block``."""
    kitchen = SLICE_SEED_BASE + SEED_BLOCK_STRIDE * block + SLICE_SEED_STRIDE * index
    return {"kitchen": kitchen, "single": kitchen + SINGLE_OFFSET}


_TINY = SlicePlan(
    preset="tiny",
    encoder_preset="tiny",
    batch_size=2,
    warmup_steps=2,
    steps=3,
    data=SliceData(kitchen=1, single=2, kitchen_views=1, intrinsics="tiny", depth="analytic"),
    validation=ValidationSet(kitchen=0, single=2, intrinsics="tiny", depth="analytic"),
)
"""Tests: the shipped decoder's objects, 3 tiny (320x240) views a slice, 3 steps, 2 validation views."""

_SMALL = SlicePlan(preset="small")
"""The shipped encoder's scale (small preset, batch 8, lr 1e-3) against the shipped decoder; 900 new views a
slice at 640x480 with stereo depth, 6,000 steps (48,000 images); validation on the recipe's 50 views."""

PRESETS: dict[str, SlicePlan] = {"tiny": _TINY, "small": _SMALL}


def plan_preset(name: str) -> SlicePlan:
    if name not in PRESETS:
        raise CenterArtError(f"unknown slice preset {name!r}; choose from {', '.join(PRESETS)}")
    return copy.deepcopy(PRESETS[name])
