"""Test-time code fitting with a frozen, differentiable toy decoder whose shape code sets a sphere's radius."""

import numpy as np
import torch
from torch import nn

from centerart.models.code_fitting import CodeFitConfig, Observations, fit_code
from centerart.models.decoder import DecoderConfig, DecoderOutput


class RadiusDecoder(nn.Module):
    """sdf = |x - c(j)| - (0.2 + z[0]), centre moving with the joint code: c(j) = (0.1 j, 0, 0)."""

    def __init__(self):
        super().__init__()
        self.config = DecoderConfig(code_dim=4, width=8, depth=2, skip_layers=(1,))
        self.dummy = nn.Parameter(torch.zeros(1))  # a frozen "weight" that must not change

    def sdf_only(self, code, joint, xyz):
        centre = torch.stack([0.1 * joint, torch.zeros_like(joint), torch.zeros_like(joint)], -1)
        return (xyz - centre).norm(dim=-1) - (0.2 + code[:, 0]) + 0 * self.dummy

    def forward(self, code, joint, xyz):
        sdf = self.sdf_only(code, joint, xyz)
        z = torch.zeros(len(sdf), 3)
        return DecoderOutput(sdf=sdf, offset=z, rotation=torch.eye(3).expand(len(sdf), 3, 3), raw=z)


def _sphere_samples(r, joint, n=4000, seed=0):
    rng = np.random.default_rng(seed)
    p = rng.uniform(-0.4, 0.4, (n, 3)).astype(np.float32)
    c = np.array([0.1 * joint, 0, 0])
    return p, (np.linalg.norm(p - c, axis=1) - r).astype(np.float32)


def test_fit_code_from_full_samples_recovers_shape():
    dec = RadiusDecoder()
    states = [(j, *_sphere_samples(0.25, j, seed=i)) for i, j in enumerate([0.0, 1.0])]
    code, joint, loss = fit_code(dec, Observations.from_samples(states), CodeFitConfig(steps=300, lr=1e-2))
    assert joint is None and abs(code[0] - 0.05) < 0.005 and loss < 2e-3
    assert float(dec.dummy) == 0.0 and dec.dummy.requires_grad  # decoder frozen during the fit, restored after


def test_fit_code_and_joint_from_partial_depth():
    dec = RadiusDecoder()
    rng = np.random.default_rng(1)
    # camera on +x looking at the sphere of radius 0.25 centred at (0.07, 0, 0) (joint code 0.7): only the
    # visible cap is observed
    centre, r = np.array([0.07, 0, 0]), 0.25
    d = rng.normal(size=(3000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = d[d[:, 0] > 0.3]
    surface = centre + r * d
    obs = Observations.from_depth(surface, camera_origin=np.array([1.5, 0, 0]))
    assert (obs.lower <= obs.upper).all() and len(obs.points) == 6 * len(surface)
    code, joint, _ = fit_code(dec, obs, CodeFitConfig(steps=300, lr=1e-2), fit_joint=True)
    # a one-sided view constrains the visible cap: radius and centre trade off along the view axis, so check
    # that the visible surface is explained rather than each number alone
    pred = dec.sdf_only(
        torch.as_tensor(code).expand(len(surface), -1),
        torch.full((len(surface),), joint),
        torch.as_tensor(surface, dtype=torch.float32),
    )
    assert float(pred.abs().mean()) < 0.003
    assert 0.0 <= joint <= 1.0


def test_fit_starts_from_a_given_code():
    """A fit started at the matching sphere's code stays on it, where one step from the zero code cannot get; the
    start is copied, not optimised in place."""
    dec = RadiusDecoder()
    start = np.array([0.05, 0.0, 0.0, 0.0], np.float32)  # radius 0.25
    original = start.copy()
    obs = Observations.from_samples([(0.5, *_sphere_samples(0.25, 0.5))])
    cfg = CodeFitConfig(steps=1, lr=1e-3)
    started, _, loss_started = fit_code(dec, obs, cfg, start=start)
    _, _, loss_zero = fit_code(dec, obs, cfg)
    assert abs(started[0] - 0.05) < 2e-3 and loss_started < 2e-3 < loss_zero
    assert np.array_equal(start, original)


class TrainModeShiftDecoder(RadiusDecoder):
    """RadiusDecoder whose sphere is 3 cm larger in train mode: a deterministic stand-in for dropout's effect."""

    def sdf_only(self, code, joint, xyz):
        return super().sdf_only(code, joint, xyz) - (0.03 if self.training else 0.0)


def test_fit_under_dropout_sees_the_train_mode_decoder_and_restores_the_mode():
    """``CodeFitConfig.dropout`` fits the code the train-mode decoder needs (radius 0.25 = 0.2 + z + 0.03, so
    z = 0.02, not 0.05); the reported loss is the eval-mode one, and the decoder's mode is left as found."""
    obs = Observations.from_samples([(0.5, *_sphere_samples(0.25, 0.5))])
    for mode in (False, True):
        dec = TrainModeShiftDecoder().train(mode)
        plain, _, loss_plain = fit_code(dec, obs, CodeFitConfig(steps=300, lr=1e-2))
        dropped, _, loss_dropped = fit_code(dec, obs, CodeFitConfig(steps=300, lr=1e-2, dropout=True))
        assert abs(plain[0] - 0.05) < 0.005 and abs(dropped[0] - 0.02) < 0.005
        assert loss_plain < 2e-3 < 5e-3 < loss_dropped  # measured without the train-mode shift: 3 cm off
        assert dec.training is mode


def test_observations_from_states_equal_those_from_their_samples():
    from centerart.sdf.samples import StateData

    p, s = _sphere_samples(0.25, 0.5, n=50)
    fields = {f: None for f in StateData.__dataclass_fields__}
    states = [StateData(**(fields | {"joint": j, "points": p + j, "sdf": s})) for j in (0.0, 1.0)]
    a, b = Observations.from_states(states), Observations.from_samples([(0.0, p, s), (1.0, p + 1.0, s)])
    assert all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("points", "lower", "upper", "joint"))
