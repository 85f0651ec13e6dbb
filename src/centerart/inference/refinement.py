"""Refinement of a predicted object against the observed depth (each step a flag, measured on and off).

ICP (the paper's option): the decoded surface, as the camera would see it (points facing the camera), is
aligned to the object's observed points (its instance mask back-projected) with point-to-point ICP (open3d),
starting from the predicted pose with its translation moved so that the centroid of the surface it should see lands
on the centroid of the observed points (the published initialisation). The result is rejected, keeping the
prediction, when ICP moves the object by more than ``max_shift_m`` (0.3 m, the published threshold) or fits fewer
than ``min_fitness`` of the points.

SDF fitting (beyond the paper, :func:`refine_sdf`): the object's pose (a 6-D correction), shape code and joint code
are optimised together, decoder frozen, so that the decoded SDF is zero at the observed points and positive up to
1 and 3 cm in front of them along the camera rays (free space); the encoder's code stays the prior
(``code_prior``). Unseen space is left to the shape prior.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch


@dataclass(frozen=True)
class RefineConfig:
    icp: bool = False
    """ICP of the decoded surface to the object's observed points."""
    icp_max_correspondence_m: float = 0.05
    icp_iterations: int = 30
    max_shift_m: float = 0.3
    """Reject a refinement that moves the object further (the published rejection threshold)."""
    min_fitness: float = 0.3
    surface_points: int = 4000
    centroid_init: bool = True
    """Start ICP with the seen surface's centroid moved onto the observed points' centroid (published)."""


def visible_surface_points(mesh, camera_T_object: np.ndarray, count: int, seed: int = 0) -> np.ndarray:
    """Points of ``mesh`` (object frame) whose normals face the camera, in the object frame."""
    import trimesh

    pts, faces = trimesh.sample.sample_surface(mesh, count * 2, seed=seed)
    normals = mesh.face_normals[faces]
    cam = np.linalg.inv(camera_T_object)[:3, 3]
    facing = np.einsum("ij,ij->i", normals, cam - pts) > 0
    return pts[facing][:count]


def icp_point_to_point(src: np.ndarray, dst: np.ndarray, init: np.ndarray, max_correspondence_m: float,
                       iterations: int):  # fmt: skip
    """open3d's point-to-point ICP of ``src`` (N, 3, the pose's source frame) onto ``dst`` (M, 3) from ``init``
    (4x4); its result (``transformation``, ``fitness``, ``inlier_rmse``)."""
    import open3d as o3d

    reg = o3d.pipelines.registration
    return reg.registration_icp(
        o3d.geometry.PointCloud(o3d.utility.Vector3dVector(src)),
        o3d.geometry.PointCloud(o3d.utility.Vector3dVector(dst)),
        max_correspondence_m, init, reg.TransformationEstimationPointToPoint(),
        reg.ICPConvergenceCriteria(max_iteration=iterations),
    )  # fmt: skip


def refine_pose_icp(mesh, camera_T_object: np.ndarray, observed: np.ndarray, cfg: RefineConfig):
    """Refined ``camera_T_object`` and a dict (accepted, fitness, rmse, shift_m)."""
    if len(observed) < 50 or len(mesh.faces) == 0:
        return camera_T_object, {"accepted": False, "reason": "too few observed points or empty mesh"}
    src = visible_surface_points(mesh, camera_T_object, cfg.surface_points)
    observed = np.asarray(observed, float)
    init = camera_T_object.copy()
    if cfg.centroid_init:  # the published initialisation: move the seen surface's centroid onto the observed one
        init[:3, 3] += observed.mean(0) - (src @ camera_T_object[:3, :3].T + camera_T_object[:3, 3]).mean(0)
    result = icp_point_to_point(src, observed, init, cfg.icp_max_correspondence_m, cfg.icp_iterations)
    pose = np.asarray(result.transformation)
    shift = float(np.linalg.norm(pose[:3, 3] - camera_T_object[:3, 3]))
    info = {"fitness": float(result.fitness), "rmse": float(result.inlier_rmse), "shift_m": shift}
    accepted = shift <= cfg.max_shift_m and result.fitness >= cfg.min_fitness
    info["accepted"] = bool(accepted)
    return (pose if accepted else camera_T_object), info


@dataclass(frozen=True)
class SdfRefineConfig:
    """Beyond the paper: pose, shape code and joint code fitted so the decoded SDF is zero at the observed points
    and positive in the free space in front of them (decoder frozen)."""

    enabled: bool = False
    steps: int = 60
    lr_pose: float = 3e-3
    lr_code: float = 3e-3
    points: int = 3000
    code_prior: float = 1e-2
    """Weight of |code - predicted code|^2: the encoder's code is the prior, the depth only corrects it."""
    clamp: float = 0.05
    max_shift_m: float = 0.15


def _se3(params: torch.Tensor) -> torch.Tensor:
    """4x4 pose from a 6-vector (rotation vector, translation), differentiable."""
    rot = torch.linalg.matrix_exp(
        torch.stack([
            torch.stack([torch.zeros_like(params[0]), -params[2], params[1]]),
            torch.stack([params[2], torch.zeros_like(params[0]), -params[0]]),
            torch.stack([-params[1], params[0], torch.zeros_like(params[0])]),
        ])
    )  # fmt: skip
    top = torch.cat([rot, params[3:, None]], dim=1)
    return torch.cat([top, torch.tensor([[0.0, 0.0, 0.0, 1.0]], dtype=params.dtype)], dim=0)


def refine_sdf(decoder, code: np.ndarray, joint: float, camera_T_object: np.ndarray, observed: np.ndarray,
               cfg: SdfRefineConfig, seed: int = 0):  # fmt: skip
    """Refined (camera_T_object, code, joint code, info). ``observed``: (N, 3) points of the object, camera frame."""
    from centerart.models.code_fitting import Observations

    if len(observed) < 50:
        return camera_T_object, code, joint, {"accepted": False, "reason": "too few observed points"}
    rng = np.random.default_rng(seed)
    pick = observed[rng.choice(len(observed), min(cfg.points, len(observed)), replace=False)]
    obs = Observations.from_depth(pick, np.zeros(3), free_space_offsets=(0.01, 0.03))  # camera frame
    pts, lo, hi = (torch.as_tensor(a, dtype=torch.float32) for a in (obs.points, obs.lower, obs.upper))
    base = torch.as_tensor(np.linalg.inv(camera_T_object), dtype=torch.float32)  # object_T_camera
    delta = torch.zeros(6, requires_grad=True)
    z0 = torch.as_tensor(code, dtype=torch.float32)
    z = z0.clone().requires_grad_(True)
    j_logit = torch.tensor(float(np.log(np.clip(joint, 1e-3, 1 - 1e-3) / (1 - np.clip(joint, 1e-3, 1 - 1e-3)))),
                           requires_grad=True)  # fmt: skip
    opt = torch.optim.Adam([{"params": [delta], "lr": cfg.lr_pose}, {"params": [z, j_logit], "lr": cfg.lr_code}])
    decoder.requires_grad_(False)
    with torch.enable_grad():
        for _ in range(cfg.steps):
            obj_T_cam = _se3(delta) @ base
            p_obj = pts @ obj_T_cam[:3, :3].T + obj_T_cam[:3, 3]
            s = decoder.sdf_only(z.expand(len(p_obj), -1), torch.sigmoid(j_logit).expand(len(p_obj)), p_obj)
            s = s.clamp(-cfg.clamp, cfg.clamp)
            data = (
                torch.relu(lo.clamp(-cfg.clamp, cfg.clamp) - s) + torch.relu(s - hi.clamp(-cfg.clamp, cfg.clamp))
            ).mean()
            loss = data + cfg.code_prior * ((z - z0) ** 2).sum()
            opt.zero_grad()
            loss.backward()
            opt.step()
    pose = np.linalg.inv((_se3(delta.detach()) @ base).numpy().astype(np.float64))
    shift = float(np.linalg.norm(pose[:3, 3] - camera_T_object[:3, 3]))
    info = {"accepted": shift <= cfg.max_shift_m, "shift_m": shift, "data_loss": float(data.detach())}
    if not info["accepted"]:
        return camera_T_object, code, joint, info
    return pose, z.detach().numpy(), float(torch.sigmoid(j_logit).detach()), info
