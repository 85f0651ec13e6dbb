"""The RGB-D encoder: RGB-D stem, residual body, FPN, and dense heads (CenterArt's encoder plus joint heads).

Input: a batch of letterboxed images, ``rgb`` (B, 3, H, W) in [0, 1] and ``depth`` (B, 1, H, W) in metres
(0 = hole). Output (:class:`EncoderOutput`), per pixel, all in the **OpenCV camera frame** of the input image:

- ``heatmap`` (B, H, W): object-centre heatmap in [0, 1] at input resolution;
- at stride ``head_stride`` (B, C, H/s, W/s), where each cell's values describe the object whose centre it
  sees: ``rotation`` (9, a raw 3x3 matrix, row-major; :func:`rotation_from_raw` projects it to SO(3)),
  ``center_offset`` (2, pixels / ``OFFSET_SCALE_PX`` from the cell centre to the projected object origin),
  ``center_depth`` (1, z of the object origin, m: the cell's observed depth plus a predicted residual),
  ``shape_code`` (code_dim), ``joint_code`` (1, the normalized
  joint state in [0, 1], sigmoid), ``joint_type_logits`` (2: revolute, prismatic), ``axis_direction`` (3, unit),
  ``axis_point_offset`` (3, m: the point of the joint axis nearest the object origin, minus that origin) and
  ``joint_state`` (1, metric: rad or m).

Why centre offset + depth instead of the paper's direct translation: with the intrinsics as an input the
translation ``t = depth * K^-1 [u, v, 1]`` is exact for any camera, and the depth is what the depth channel
measures; a directly regressed translation ties the network to the training camera. The depth head predicts a
residual to the mean observed depth of its cell (:func:`cell_depth`): the object origin lies a fraction of the
object's size behind the surface the cell sees, which is much easier to learn than an absolute distance.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import nn

from centerart.models.encoder.config import EncoderConfig

OFFSET_SCALE_PX = 100.0
JOINT_TYPES = ("revolute", "prismatic")
#: name -> channels of the dense output, in this order.
DENSE_LAYOUT_FIXED = {
    "rotation": 9,
    "center_offset": 2,
    "center_depth": 1,
    "joint_code": 1,
    "joint_type_logits": 2,
    "axis_direction": 3,
    "axis_point_offset": 3,
    "joint_state": 1,
}


def dense_layout(code_dim: int) -> dict[str, int]:
    return {**DENSE_LAYOUT_FIXED, "shape_code": code_dim}


@dataclass
class EncoderOutput:
    """Raw encoder maps (see the module docstring); ``dense`` holds the stride-``s`` fields by name."""

    heatmap: torch.Tensor
    dense: dict[str, torch.Tensor]
    stride: int


def _norm(kind: str, channels: int) -> nn.Module:
    if kind == "bn":
        return nn.BatchNorm2d(channels)
    return nn.GroupNorm(min(8, channels), channels)


def _conv(cin: int, cout: int, k: int = 3, stride: int = 1, dilation: int = 1) -> nn.Conv2d:
    return nn.Conv2d(cin, cout, k, stride, padding=dilation * (k // 2), dilation=dilation, bias=False)


class BasicBlock(nn.Module):
    def __init__(self, cin: int, cout: int, stride: int, norm: str, ratio: int = 1):
        super().__init__()
        self.body = nn.Sequential(
            _conv(cin, cout, 3, stride), _norm(norm, cout), nn.ReLU(inplace=True), _conv(cout, cout), _norm(norm, cout)
        )
        self.short = (
            nn.Identity()
            if stride == 1 and cin == cout
            else nn.Sequential(_conv(cin, cout, 1, stride), _norm(norm, cout))
        )

    def forward(self, x):
        return F.relu(self.body(x) + self.short(x))


class Bottleneck(BasicBlock):
    def __init__(self, cin: int, cout: int, stride: int, norm: str, ratio: int = 2):
        super().__init__(cin, cout, stride, norm)
        mid = max(cout // ratio, 8)
        self.body = nn.Sequential(
            _conv(cin, mid, 1), _norm(norm, mid), nn.ReLU(inplace=True),
            _conv(mid, mid, 3, stride), _norm(norm, mid), nn.ReLU(inplace=True),
            _conv(mid, cout, 1), _norm(norm, cout),
        )  # fmt: skip


class RGBDStem(nn.Module):
    """RGB and depth branches to stride 4, concatenated (the published RGBDStem, widths configurable)."""

    def __init__(self, cfg: EncoderConfig):
        super().__init__()
        self.rgb = nn.Sequential(nn.Conv2d(3, cfg.stem_rgb, 7, 2, 3), nn.ReLU(inplace=True), nn.MaxPool2d(3, 2, 1))
        self.depth = nn.Sequential(nn.Conv2d(2, cfg.stem_depth, 7, 2, 3), nn.ReLU(inplace=True), nn.MaxPool2d(3, 2, 1))
        # Pre-activation residual block with dilation 5: depth edges need a wide context at little cost.
        self.depth_res = nn.Sequential(
            _norm(cfg.norm, cfg.stem_depth), nn.ReLU(), _conv(cfg.stem_depth, cfg.stem_depth, dilation=5)
        )
        self.out_channels = cfg.stem_rgb + cfg.stem_depth

    def forward(self, rgb, depth_in):
        d = self.depth(depth_in)
        return torch.cat([self.rgb(rgb), d + self.depth_res(d)], dim=1)


class FPN(nn.Module):
    """Top-down feature pyramid with sum fusion: p2..p5 at strides 4..32, ``channels`` each."""

    def __init__(self, in_channels: tuple[int, ...], channels: int):
        super().__init__()
        self.lateral = nn.ModuleList(nn.Conv2d(c, channels, 1) for c in in_channels)
        self.smooth = nn.ModuleList(nn.Conv2d(channels, channels, 3, padding=1) for _ in in_channels)

    def forward(self, feats: list[torch.Tensor]) -> list[torch.Tensor]:
        x = self.lateral[-1](feats[-1])
        outs = [self.smooth[-1](x)]
        for i in range(len(feats) - 2, -1, -1):
            x = self.lateral[i](feats[i]) + F.interpolate(x, size=feats[i].shape[-2:], mode="nearest")
            outs.insert(0, self.smooth[i](x))
        return outs


def _tower(cin: int, cmid: int, cout: int, norm: str) -> nn.Sequential:
    return nn.Sequential(
        _conv(cin, cmid), _norm(norm, cmid), nn.ReLU(inplace=True),
        _conv(cmid, cmid), _norm(norm, cmid), nn.ReLU(inplace=True),
        nn.Conv2d(cmid, cout, 1),
    )  # fmt: skip


class RGBDEncoder(nn.Module):
    """Stem + residual body + FPN + heatmap head (full resolution) + dense heads (stride ``head_stride``)."""

    def __init__(self, cfg: EncoderConfig):
        super().__init__()
        self.config = cfg
        self.stem = RGBDStem(cfg)
        block = BasicBlock if cfg.block == "basic" else Bottleneck
        stages, cin = [], self.stem.out_channels
        for i, (depth, width) in enumerate(zip(cfg.depths, cfg.widths, strict=True)):
            layers = [block(cin if j == 0 else width, width, 2 if (i > 0 and j == 0) else 1, cfg.norm,
                            cfg.bottleneck_ratio) for j in range(depth)]  # fmt: skip
            stages.append(nn.Sequential(*layers))
            cin = width
        self.stages = nn.ModuleList(stages)
        self.fpn = FPN(tuple(cfg.widths), cfg.fpn_channels)
        self.heatmap_head = _tower(cfg.fpn_channels, cfg.head_channels, 1, cfg.norm)
        self.layout = dense_layout(cfg.code_dim)
        pose_ch = sum(self.layout[k] for k in ("rotation", "center_offset", "center_depth"))
        self.pose_head = _tower(cfg.fpn_channels, cfg.head_channels, pose_ch, cfg.norm)
        self.object_head = _tower(cfg.fpn_channels, cfg.head_channels, sum(self.layout.values()) - pose_ch, cfg.norm)
        nn.init.constant_(self.heatmap_head[-1].bias, -4.0)  # start near an empty heatmap (sigmoid ~ 0.02)

    def normalize_inputs(self, rgb: torch.Tensor, depth: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """RGB standardised; depth in metres with holes 0, plus a validity channel (holes are not 'very near')."""
        cfg = self.config
        valid = (depth > 0) & (depth < cfg.max_depth_m) & torch.isfinite(depth)
        depth = torch.where(valid, depth, torch.zeros_like(depth))
        return (rgb - cfg.rgb_mean) / cfg.rgb_std, torch.cat([depth, valid.to(depth.dtype)], dim=1)

    def forward(self, rgb: torch.Tensor, depth: torch.Tensor) -> EncoderOutput:
        h, w = rgb.shape[-2:]
        pad_h, pad_w = (-h) % 32, (-w) % 32  # the body needs sizes divisible by its total stride
        rgb_n, depth_n = self.normalize_inputs(rgb, depth)
        if pad_h or pad_w:
            rgb_n, depth_n = F.pad(rgb_n, (0, pad_w, 0, pad_h)), F.pad(depth_n, (0, pad_w, 0, pad_h))
        x = self.stem(rgb_n, depth_n)
        feats = []
        for stage in self.stages:
            x = stage(x)
            feats.append(x)
        p = self.fpn(feats)
        s4 = p[0] + sum(F.interpolate(q, size=p[0].shape[-2:], mode="bilinear", align_corners=False) for q in p[1:])
        heat = self.heatmap_head(s4)
        heat = F.interpolate(heat, scale_factor=4, mode="bilinear", align_corners=False)[:, 0, :h, :w]
        s8 = p[1] + sum(F.interpolate(q, size=p[1].shape[-2:], mode="bilinear", align_corners=False) for q in p[2:])
        dense = torch.cat([self.pose_head(s8), self.object_head(s8)], dim=1)
        hc, wc = -(-h // self.config.head_stride), -(-w // self.config.head_stride)
        fields = split_dense(dense[..., :hc, :wc], self.layout)
        observed = cell_depth(depth_n[:, :1], depth_n[:, 1:], self.config.head_stride)[..., :hc, :wc]
        fields["center_depth"] = fields["center_depth"] + observed
        return EncoderOutput(torch.sigmoid(heat), fields, self.config.head_stride)


def cell_depth(depth: torch.Tensor, valid: torch.Tensor, stride: int, fallback_cells: int = 5) -> torch.Tensor:
    """(B, 1, H/s, W/s): mean valid depth (m) of each stride cell; a cell without a valid pixel takes the mean of
    the valid pixels in the ``fallback_cells`` x ``fallback_cells`` cells around it (0 if none)."""
    depth_sum = F.avg_pool2d(depth * valid, stride, stride, ceil_mode=True)
    count = F.avg_pool2d(valid, stride, stride, ceil_mode=True)
    near = count > 0
    pad = fallback_cells // 2
    wide_sum = F.avg_pool2d(depth_sum, fallback_cells, 1, pad, count_include_pad=False)
    wide_count = F.avg_pool2d(count, fallback_cells, 1, pad, count_include_pad=False)
    wide = wide_sum / wide_count.clamp_min(1e-6)
    return torch.where(near, depth_sum / count.clamp_min(1e-6), wide)


def split_dense(dense: torch.Tensor, layout: dict[str, int]) -> dict[str, torch.Tensor]:
    """Named fields of the raw dense map (B, C, h, w), with their activations applied."""
    out, i = {}, 0
    for name, n in layout.items():
        out[name] = dense[:, i : i + n]
        i += n
    out["joint_code"] = torch.sigmoid(out["joint_code"])
    out["axis_direction"] = F.normalize(out["axis_direction"], dim=1, eps=1e-6)
    return out


def rotation_from_raw(raw: torch.Tensor) -> torch.Tensor:
    """Project raw 9-vectors (N, 9), row-major 3x3, to the nearest rotations (N, 3, 3) (SVD, det +1)."""
    m = raw.reshape(-1, 3, 3)
    u, _, vt = torch.linalg.svd(m)
    d = torch.sign(torch.det(u @ vt))
    d = torch.where(d == 0, torch.ones_like(d), d)
    fix = torch.ones(m.shape[0], 3, dtype=m.dtype, device=m.device)
    fix[:, 2] = d
    return u @ torch.diag_embed(fix) @ vt


def cell_centers(h: int, w: int, stride: int, device=None) -> torch.Tensor:
    """(h, w, 2) input-image pixel (u, v) at the centre of each stride-``stride`` cell."""
    v = torch.arange(h, device=device, dtype=torch.float32) * stride + (stride - 1) / 2.0
    u = torch.arange(w, device=device, dtype=torch.float32) * stride + (stride - 1) / 2.0
    return torch.stack(torch.meshgrid(u, v, indexing="xy"), dim=-1)


def object_translation(
    cells_uv: torch.Tensor, center_offset: torch.Tensor, center_depth: torch.Tensor, K: torch.Tensor
) -> torch.Tensor:
    """Camera-frame object origins (N, 3) from cell pixels (N, 2), raw offsets (N, 2), depths (N,), K (N, 3, 3)."""
    uv = cells_uv + center_offset * OFFSET_SCALE_PX
    y = (uv[:, 1] - K[:, 1, 2]) / K[:, 1, 1]
    x = (uv[:, 0] - K[:, 0, 2] - K[:, 0, 1] * y) / K[:, 0, 0]
    return torch.stack([x, y, torch.ones_like(x)], dim=1) * center_depth[:, None]
