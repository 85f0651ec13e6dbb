"""Encoder configuration and its named presets (``tiny`` for tests, ``small`` for a 2-core CPU, ``paper``)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from typing import Literal


@dataclass(frozen=True)
class EncoderConfig:
    """Layout of the RGB-D encoder (:class:`~centerart.models.encoder.network.RGBDEncoder`).

    Images are letterboxed to ``input_width`` x ``input_height`` (scaled to fit, intrinsics scaled with them,
    zero padding right and bottom). Heatmap at input resolution; every other head at stride ``head_stride``.
    """

    input_width: int = 320
    input_height: int = 240
    stem_rgb: int = 16
    """Channels of the RGB branch of the stem (stride 4)."""
    stem_depth: int = 16
    """Channels of the depth branch of the stem (stride 4, with a dilated residual block)."""
    block: Literal["basic", "bottleneck"] = "basic"
    depths: tuple[int, ...] = (2, 2, 2, 2)
    """Residual blocks per stage (strides 4, 8, 16, 32)."""
    widths: tuple[int, ...] = (32, 48, 64, 96)
    """Output channels per stage."""
    bottleneck_ratio: int = 2
    """Bottleneck blocks: inner width = width / ratio."""
    norm: Literal["bn", "gn"] = "gn"
    """bn: batch norm (the published choice, needs large batches); gn: group norm (small batches on a CPU)."""
    fpn_channels: int = 64
    head_channels: int = 64
    head_stride: int = 8
    code_dim: int = 32
    """Shape-code length: must equal the decoder checkpoint's."""
    rgb_mean: float = 0.5
    rgb_std: float = 0.2
    max_depth_m: float = 6.0
    """Depth beyond this (m) is treated as a hole."""
    read_radius_cells: int | None = None
    """Readout: an object's values are the heatmap-weighted mean over its instance region's stride cells within
    this many cells (Chebyshev distance) of its peak; 0 reads the peak cell alone, None the whole region
    (:func:`~centerart.models.encoder.readout.read_objects`). Why None: on the 50-view overfit check
    (``benchmarks/results/overfit_encoder/``) the whole region read translation at 0.8 cm and found every
    object where 3x3 cells (1, the value before this field; older checkpoints keep it) read 1.6 cm and missed
    two."""

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> EncoderConfig:
        known = {f.name for f in fields(cls)}
        unknown = set(data) - known
        if unknown:
            raise ValueError(f"unknown encoder config fields {sorted(unknown)}")
        data = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
        # A field added after a checkpoint was written takes the value that reproduces how that checkpoint was read.
        return cls(**{**LEGACY_DEFAULTS, **data})


LEGACY_DEFAULTS: dict[str, object] = {"read_radius_cells": 1}
"""Values of fields that older checkpoints' configs lack: the behaviour those checkpoints were measured with."""
READOUT_FIELDS = frozenset({"read_radius_cells"})
"""Fields that change how the outputs are read, not the weights: two configs that differ only in these hold
interchangeable weights."""


def same_weights_layout(a: EncoderConfig, b: EncoderConfig) -> bool:
    """Whether weights of one config load into the other with the same meaning (all but :data:`READOUT_FIELDS`)."""
    a_dict, b_dict = a.to_dict(), b.to_dict()
    return all(a_dict[k] == b_dict[k] for k in a_dict if k not in READOUT_FIELDS)


PRESETS: dict[str, EncoderConfig] = {
    "tiny": EncoderConfig(
        input_width=160,
        input_height=120,
        stem_rgb=8,
        stem_depth=8,
        depths=(1, 1, 1, 1),
        widths=(16, 24, 32, 48),
        fpn_channels=32,
        head_channels=32,
    ),
    "small": EncoderConfig(),
    # The published layout: ResNet-50 stages [3, 4, 6, 3] at a quarter of the width, FPN 64, heads 32, 960x512.
    "paper": EncoderConfig(
        input_width=960,
        input_height=512,
        stem_rgb=32,
        stem_depth=32,
        block="bottleneck",
        depths=(3, 4, 6, 3),
        widths=(64, 128, 256, 512),
        bottleneck_ratio=2,
        norm="bn",
        fpn_channels=64,
        head_channels=32,
    ),
}


def preset(name: str, **overrides) -> EncoderConfig:
    if name not in PRESETS:
        raise ValueError(f"unknown encoder preset {name!r}; choose from {sorted(PRESETS)}")
    return replace(PRESETS[name], **overrides)
