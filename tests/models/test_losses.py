import numpy as np
import torch
from scipy.spatial.transform import Rotation

from centerart.grasps.gripper import FLIP_Z, control_points
from centerart.models.decoder import DecoderOutput
from centerart.models.losses import LossConfig, decoder_loss, grasp_point_weights


def _perfect(n=50, seed=0):
    rng = np.random.default_rng(seed)
    R = Rotation.random(n, random_state=seed).as_matrix()
    poses = np.tile(np.eye(4), (n, 1, 1))
    poses[:, :3, :3] = R
    poses[:, :3, 3] = rng.normal(0, 0.2, (n, 3))
    xyz = rng.normal(0, 0.2, (n, 3))
    sdf = rng.normal(0, 0.05, n)
    gp = control_points(poses)
    dist = np.linalg.norm(xyz - poses[:, :3, 3], axis=1)
    t = lambda a: torch.as_tensor(a, dtype=torch.float32)  # noqa: E731
    return poses, t(xyz), t(sdf), t(gp), t(dist)


def _output(poses, xyz, sdf):
    R = torch.as_tensor(poses[:, :3, :3], dtype=torch.float32)
    offset = torch.as_tensor(poses[:, :3, 3], dtype=torch.float32) - xyz
    raw = torch.cat([sdf[:, None], offset, R[..., 0], R[..., 1]], 1)
    return DecoderOutput(sdf=sdf.clone(), offset=offset, rotation=R, raw=raw)


def test_perfect_prediction_has_zero_loss():
    poses, xyz, sdf, gp, dist = _perfect()
    for weighting in ("none", "label", "surface"):
        terms = decoder_loss(LossConfig(grasp_weighting=weighting), _output(poses, xyz, sdf), xyz, sdf, gp, dist)
        assert float(terms["loss"]) < 1e-5, weighting


def test_swapped_fingers_have_zero_grasp_loss():
    poses, xyz, sdf, gp, dist = _perfect()
    flipped = poses @ FLIP_Z  # the same gripper turned 180 degrees about its approach axis
    terms = decoder_loss(LossConfig(), _output(flipped, xyz, sdf), xyz, sdf, gp, dist)
    assert float(terms["grasp"]) < 1e-5


def test_wrong_grasp_and_sdf_are_penalised():
    poses, xyz, sdf, gp, dist = _perfect()
    turned = poses @ np.diag([1.0, -1.0, -1.0, 1.0])  # 180 degrees about x: approach reversed
    terms = decoder_loss(LossConfig(grasp_weighting="none"), _output(turned, xyz, sdf + 0.01), xyz, sdf, gp, dist)
    assert float(terms["grasp"]) > 0.05
    assert 0.009 < float(terms["sdf"]) <= 0.01 + 1e-6  # less only where the 0.1 m clamp cuts in


def test_sdf_clamped_in_loss_only():
    poses, xyz, sdf, gp, dist = _perfect()
    far = torch.full_like(sdf, 0.3)
    out = _output(poses, xyz, torch.full_like(sdf, 0.5))
    assert float(decoder_loss(LossConfig(), out, xyz, far, gp, dist)["sdf"]) == 0.0
    assert float(out.sdf[0]) == 0.5


def test_grasp_weights():
    sdf = torch.tensor([0.0, 0.0, 0.1])
    dist = torch.tensor([0.0, float("inf"), 0.05])
    assert torch.allclose(grasp_point_weights(LossConfig(grasp_weighting="none"), sdf, dist), torch.tensor([1, 0, 1.0]))
    w = grasp_point_weights(LossConfig(grasp_weighting="label", grasp_weight_scale=0.05), sdf, dist)
    assert torch.allclose(w, torch.tensor([1.0, 0.0, np.exp(-1.0)], dtype=torch.float32), atol=1e-6)
    w = grasp_point_weights(LossConfig(grasp_weighting="surface", grasp_weight_scale=0.05), sdf, dist)
    assert torch.allclose(w, torch.tensor([1.0, 0.0, np.exp(-2.0)], dtype=torch.float32), atol=1e-6)


def test_no_labels_gives_zero_grasp_term():
    poses, xyz, sdf, gp, _ = _perfect()
    inf = torch.full_like(sdf, float("inf"))
    turned = poses @ np.diag([1.0, -1.0, -1.0, 1.0])
    assert float(decoder_loss(LossConfig(), _output(turned, xyz, sdf), xyz, sdf, gp, inf)["grasp"]) == 0.0
