"""Shape codes for objects the decoder never saw: DeepSDF test-time optimisation with the decoder frozen.

Observations are points (object canonical frame, m) with an interval [lower, upper] on their signed distance:

- full SDF samples: lower = upper = the true SDF (both clamped to +-clamp, as in training);
- a partial depth point cloud seen from a camera at ``camera_origin`` (object frame): every observed surface
  point p gives lower = upper = 0; and along its camera ray r = (p - o)/|p - o|, the points p - t r for a few
  t in ``free_space_offsets`` lie in free space between the camera and the surface, so 0 < sdf <= t (the surface
  point p is t away, and nothing was seen in front of it). Occluded space gets no constraint, which is what
  leaves the unseen side to the shape prior (the code).

The loss per point is relu(lower - s) + relu(s - upper) on the clamped prediction s (the clamped L1 when
lower = upper), plus ``code_weight * |z|^2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from centerart.models.decoder import SGDFDecoder


@dataclass(frozen=True)
class CodeFitConfig:
    steps: int = 400
    lr: float = 5e-3
    code_weight: float = 1e-4
    points_per_step: int = 8192
    clamp: float = 0.1
    seed: int = 0
    joint_starts: tuple[float, ...] = (0.15, 0.5, 0.85)
    """Initial joint codes tried when the joint is unknown (the best fit wins)."""
    dropout: bool = False
    """Fit with the decoder's dropout on, as a run with dropout learned its training codes. Off (the default), the
    fit sees the deterministic decoder that inference decodes with."""


@dataclass
class Observations:
    """Points (N, 3) with SDF bounds lower/upper (N,) and the normalized joint code of each point (N,)."""

    points: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    joint: np.ndarray

    @classmethod
    def from_samples(cls, states: list[tuple[float, np.ndarray, np.ndarray]]) -> Observations:
        """From full SDF samples: ``states`` = [(joint code, points (N, 3), sdf (N,)), ...] of ONE object."""
        pts = np.concatenate([p for _, p, _ in states]).astype(np.float32)
        sdf = np.concatenate([s for _, _, s in states]).astype(np.float32)
        joint = np.concatenate([np.full(len(p), j, np.float32) for j, p, _ in states])
        return cls(pts, sdf, sdf.copy(), joint)

    @classmethod
    def from_states(cls, states: list) -> Observations:
        """From full SDF samples of ONE object given as states with ``joint``, ``points`` and ``sdf``
        (``sdf.samples.StateData``)."""
        return cls.from_samples([(s.joint, s.points, s.sdf) for s in states])

    @classmethod
    def from_depth(
        cls,
        surface_points: np.ndarray,
        camera_origin: np.ndarray,
        joint: float = float("nan"),
        free_space_offsets: tuple[float, ...] = (0.005, 0.01, 0.02, 0.04, 0.08),
    ) -> Observations:
        """From observed surface points (N, 3) and the camera centre (3,), both in the object frame."""
        p = np.asarray(surface_points, np.float32)
        o = np.asarray(camera_origin, np.float32).reshape(1, 3)
        ray = p - o
        ray /= np.linalg.norm(ray, axis=1, keepdims=True).clip(1e-9)
        pts, lo, hi = [p], [np.zeros(len(p), np.float32)], [np.zeros(len(p), np.float32)]
        for t in free_space_offsets:
            pts.append(p - t * ray)
            lo.append(np.zeros(len(p), np.float32))
            hi.append(np.full(len(p), t, np.float32))
        pts = np.concatenate(pts)
        return cls(pts, np.concatenate(lo), np.concatenate(hi), np.full(len(pts), joint, np.float32))


def interval_loss(pred: torch.Tensor, lo: torch.Tensor, hi: torch.Tensor, clamp: float) -> torch.Tensor:
    """Mean of relu(lo - s) + relu(s - hi) over points, s the prediction clamped to +-clamp (see the module doc)."""
    s = pred.clamp(-clamp, clamp)
    return (torch.relu(lo.clamp(-clamp, clamp) - s) + torch.relu(s - hi.clamp(-clamp, clamp))).mean()


def fit_code(
    decoder: SGDFDecoder,
    obs: Observations,
    cfg: CodeFitConfig = CodeFitConfig(),
    fit_joint: bool = False,
    start: np.ndarray | None = None,
) -> tuple[np.ndarray, float | None, float]:
    """Optimise a shape code (and, with ``fit_joint``, one shared joint code) to the observations, starting from
    ``start`` (code_dim,) or the zero code (the mean of the code prior).

    The decoder is frozen (no parameter is updated; its train/eval mode is left as found; dropout is on during the
    fit only with ``cfg.dropout``, and the final loss is always measured without it). Returns (code (code_dim,),
    fitted joint code or None, final data loss).
    """
    device = next(decoder.parameters()).device
    was_training = decoder.training
    grad_flags = [p.requires_grad for p in decoder.parameters()]
    decoder.requires_grad_(False)  # frozen: and no wasted weight gradients
    starts = cfg.joint_starts if fit_joint else (None,)
    best = None
    try:
        for j0 in starts:
            result = _fit_once(decoder, obs, cfg, j0, device, start)
            if best is None or result[2] < best[2]:
                best = result
    finally:
        decoder.train(was_training)
        for p, flag in zip(decoder.parameters(), grad_flags, strict=True):
            p.requires_grad_(flag)
    return best


def _fit_once(decoder, obs, cfg, j0, device, start=None):
    decoder.train(cfg.dropout)  # the fit's steps see dropout only with cfg.dropout; fit_code restores the mode
    gen = torch.Generator().manual_seed(cfg.seed)
    pts = torch.as_tensor(obs.points, device=device)
    lo = torch.as_tensor(obs.lower, device=device)
    hi = torch.as_tensor(obs.upper, device=device)
    joint_obs = torch.as_tensor(obs.joint, device=device)
    code = torch.zeros(decoder.config.code_dim, device=device)
    if start is not None:
        code = torch.as_tensor(np.asarray(start, np.float32).reshape(-1), device=device).clone()
    code.requires_grad_(True)
    params = [code]
    joint_logit = None
    if j0 is not None:
        joint_logit = torch.tensor(float(np.log(j0 / (1 - j0))), device=device, requires_grad=True)
        params.append(joint_logit)
    opt = torch.optim.Adam(params, lr=cfg.lr)
    sched = torch.optim.lr_scheduler.StepLR(opt, step_size=max(1, cfg.steps // 2), gamma=0.3)
    n = len(pts)
    with torch.enable_grad():
        for _ in range(cfg.steps):
            idx = torch.randint(0, n, (min(cfg.points_per_step, n),), generator=gen).to(device)
            j = torch.sigmoid(joint_logit).expand(len(idx)) if joint_logit is not None else joint_obs[idx]
            pred = decoder.sdf_only(code.expand(len(idx), -1), j, pts[idx])
            loss = interval_loss(pred, lo[idx], hi[idx], cfg.clamp) + cfg.code_weight * (code**2).sum()
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            sched.step()
    decoder.eval()  # the final loss always without dropout
    with torch.no_grad():
        idx = torch.arange(0, n, max(1, n // 20000), device=device)
        j = torch.sigmoid(joint_logit).expand(len(idx)) if joint_logit is not None else joint_obs[idx]
        pred = decoder.sdf_only(code.expand(len(idx), -1), j, pts[idx])
        final = float(interval_loss(pred, lo[idx], hi[idx], cfg.clamp))
    joint_fit = float(torch.sigmoid(joint_logit)) if joint_logit is not None else None
    return code.detach().cpu().numpy().astype(np.float32), joint_fit, final
