"""The SGDF decoder: (shape code, joint code, point) -> signed distance + the nearest valid grasp.

Inputs (all in the object's canonical frame, see ``assets/canonical_frame.py``):

- ``code``  (B, code_dim): the object's shape code, shared by all its joint states;
- ``joint`` (B, 1): the *normalized* target-joint state u = (q - lower) / (upper - lower) in [0, 1]. One number
  because every object has exactly one target joint; normalized so revolute (rad) and prismatic (m) joints, and
  objects with different ranges, share one scale, and the RGB-D encoder can predict it with a sigmoid. The
  metric state is recovered with ``ArticulatedObject.denormalize``;
- ``xyz``   (B, 3): query point, metres.

Outputs (:class:`DecoderOutput`):

- ``sdf`` (B,): signed distance in metres, positive outside. Not squashed or clamped: the clamp lives only in the
  loss, so far-field values stay usable for coarse-to-fine meshing;
- ``offset`` (B, 3): grasp TCP position minus the query point, metres (no tanh, unlike the published decoder);
- ``rotation`` (B, 3, 3): grasp TCP orientation (columns x, y, z of the TCP frame, ``grasps/gripper.py``), built
  by Gram-Schmidt from two raw 3-vectors: x = a/|a|, y = normalize(b - (b.x)x), z = x cross y.

Layer layout: layer 0 takes [code, xyz] (+ joint if ``joint_layer == 0``); layer ``joint_layer`` additionally
takes the joint code; each layer in ``skip_layers`` additionally takes [code, joint, xyz] (the DeepSDF latent
skip). Extra inputs are concatenated to the hidden width (the layer is simply wider), not carved out of it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace

import numpy as np
import torch
from torch import nn

OUT_DIM = 10  # sdf (1) + offset (3) + two rotation vectors (6)


@dataclass(frozen=True)
class DecoderConfig:
    code_dim: int = 32
    """Shape-code length."""
    width: int = 256
    """Hidden units per layer."""
    depth: int = 6
    """Number of hidden layers."""
    skip_layers: tuple[int, ...] = (3,)
    """Hidden layers that get [code, joint, xyz] again as extra input (latent skip)."""
    joint_layer: int = 1
    """Hidden layer where the joint code enters (0 = with the input)."""
    weight_norm: bool = False
    """Weight normalisation on the hidden layers."""
    dropout: float = 0.0
    """Dropout probability after every hidden layer (training only)."""

    def __post_init__(self):
        if not 0 <= self.joint_layer < self.depth:
            raise ValueError(f"joint_layer {self.joint_layer} must be in [0, {self.depth})")
        if any(not 0 < s < self.depth for s in self.skip_layers):
            raise ValueError(f"skip_layers {self.skip_layers} must be in (0, {self.depth})")

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> DecoderConfig:
        d = dict(d)
        d["skip_layers"] = tuple(d.get("skip_layers", ()))
        return cls(**d)


#: ``tiny``: unit tests (seconds on CPU); ``small``: the shipped CPU checkpoint; ``paper``: the published recipe
#: (8x512, latent skip at layer 4, joint code at layer 1, weight norm, dropout 0.2).
PRESETS: dict[str, DecoderConfig] = {
    "tiny": DecoderConfig(width=64, depth=4, skip_layers=(2,), joint_layer=1),
    "small": DecoderConfig(width=256, depth=6, skip_layers=(3,), joint_layer=1),
    "paper": DecoderConfig(width=512, depth=8, skip_layers=(4,), joint_layer=1, weight_norm=True, dropout=0.2),
}


def preset(name: str, **overrides) -> DecoderConfig:
    if name not in PRESETS:
        raise ValueError(f"unknown decoder preset {name!r}; choose from {sorted(PRESETS)}")
    return replace(PRESETS[name], **overrides)


@dataclass
class DecoderOutput:
    """The decoder's outputs for B query points, object canonical frame, metres (see the module doc)."""

    sdf: torch.Tensor
    """(B,) signed distance, positive outside."""
    offset: torch.Tensor
    """(B, 3) grasp TCP position minus the query point."""
    rotation: torch.Tensor
    """(B, 3, 3) grasp TCP orientation (columns x, y, z)."""
    raw: torch.Tensor = field(repr=False)
    """(B, OUT_DIM) the head's outputs these were decoded from (kept to store and decode again)."""

    def grasp_position(self, xyz: torch.Tensor) -> torch.Tensor:
        return xyz + self.offset

    def grasp_poses(self, xyz: torch.Tensor) -> torch.Tensor:
        """(B, 4, 4) TCP poses in the object frame."""
        pose = torch.zeros(*self.rotation.shape[:-2], 4, 4, dtype=xyz.dtype, device=xyz.device)
        pose[..., :3, :3] = self.rotation
        pose[..., :3, 3] = xyz + self.offset
        pose[..., 3, 3] = 1.0
        return pose


def gram_schmidt(a: torch.Tensor, b: torch.Tensor, eps: float = 1e-8) -> torch.Tensor:
    """Rotation matrices (..., 3, 3) with columns x = a/|a|, y = b orthogonalised against x, z = x cross y."""
    x = a / a.norm(dim=-1, keepdim=True).clamp_min(eps)
    b = b - (b * x).sum(-1, keepdim=True) * x
    y = b / b.norm(dim=-1, keepdim=True).clamp_min(eps)
    z = torch.cross(x, y, dim=-1)
    return torch.stack([x, y, z], dim=-1)


def decode_outputs(raw: torch.Tensor | np.ndarray) -> DecoderOutput:
    """Typed outputs from raw head outputs (..., OUT_DIM) laid out [sdf | offset (3) | rotation vectors a, b (3 + 3)].

    The one place that knows the layout: the forward pass and everything that stores raw outputs (e.g. the
    reconstruction's final-level points) decode through it.
    """
    raw = torch.as_tensor(raw)
    return DecoderOutput(
        sdf=raw[..., 0],
        offset=raw[..., 1:4],
        rotation=gram_schmidt(raw[..., 4:7], raw[..., 7:10]),
        raw=raw,
    )


class SGDFDecoder(nn.Module):
    def __init__(self, config: DecoderConfig):
        super().__init__()
        self.config = config
        c = config
        layers = []
        for i in range(c.depth):
            n_in = (c.code_dim + 3) if i == 0 else c.width
            if i == c.joint_layer:
                n_in += 1
            if i in c.skip_layers:
                n_in += c.code_dim + 1 + 3
            lin = nn.Linear(n_in, c.width)
            if c.weight_norm:
                lin = nn.utils.parametrizations.weight_norm(lin)
            layers.append(lin)
        self.layers = nn.ModuleList(layers)
        self.head = nn.Linear(c.width, OUT_DIM)
        self.dropout = nn.Dropout(c.dropout) if c.dropout > 0 else nn.Identity()
        self._init_head()

    def _init_head(self):
        # Start near a valid grasp frame: small weights and a bias making a = x-axis, b = y-axis, so Gram-Schmidt
        # is well conditioned from step 0; offsets and sdf start near zero.
        with torch.no_grad():
            self.head.weight.mul_(0.1)
            self.head.bias.zero_()
            self.head.bias[4] = 1.0
            self.head.bias[8] = 1.0

    def forward(self, code: torch.Tensor, joint: torch.Tensor, xyz: torch.Tensor) -> DecoderOutput:
        if joint.dim() == code.dim() - 1:
            joint = joint.unsqueeze(-1)
        c = self.config
        h = None
        for i, lin in enumerate(self.layers):
            parts = [torch.cat([code, xyz], -1)] if i == 0 else [h]
            if i == c.joint_layer:
                parts.append(joint)
            if i in c.skip_layers:
                parts.extend([code, joint, xyz])
            h = self.dropout(torch.relu(lin(torch.cat(parts, -1))))
        return decode_outputs(self.head(h))

    def sdf_only(self, code: torch.Tensor, joint: torch.Tensor, xyz: torch.Tensor) -> torch.Tensor:
        return self.forward(code, joint, xyz).sdf

    def num_parameters(self) -> int:
        return sum(p.numel() for p in self.parameters())
