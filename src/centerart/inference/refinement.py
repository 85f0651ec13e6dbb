"""Refinement of a predicted object against the observed depth (each step a flag, measured on and off).

ICP (the paper's option): the decoded surface, as the camera would see it (points facing the camera), is
aligned to the object's observed points (its instance mask back-projected) with point-to-point ICP (open3d),
starting from the predicted pose. The result is rejected, keeping the prediction, when ICP moves the object by
more than ``max_shift_m`` or fits fewer than ``min_fitness`` of the points (the published implementation rejected
centroid errors over 0.3 m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RefineConfig:
    icp: bool = False
    """ICP of the decoded surface to the object's observed points."""
    icp_max_correspondence_m: float = 0.05
    icp_iterations: int = 30
    max_shift_m: float = 0.15
    min_fitness: float = 0.3
    surface_points: int = 4000


def visible_surface_points(mesh, camera_T_object: np.ndarray, count: int, seed: int = 0) -> np.ndarray:
    """Points of ``mesh`` (object frame) whose normals face the camera, in the object frame."""
    import trimesh

    pts, faces = trimesh.sample.sample_surface(mesh, count * 2, seed=seed)
    normals = mesh.face_normals[faces]
    cam = np.linalg.inv(camera_T_object)[:3, 3]
    facing = np.einsum("ij,ij->i", normals, cam - pts) > 0
    return pts[facing][:count]


def refine_pose_icp(mesh, camera_T_object: np.ndarray, observed: np.ndarray, cfg: RefineConfig):
    """Refined ``camera_T_object`` and a dict (accepted, fitness, rmse, shift_m)."""
    import open3d as o3d

    if len(observed) < 50 or len(mesh.faces) == 0:
        return camera_T_object, {"accepted": False, "reason": "too few observed points or empty mesh"}
    src = visible_surface_points(mesh, camera_T_object, cfg.surface_points)
    src_pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(src))
    dst_pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.asarray(observed, float)))
    result = o3d.pipelines.registration.registration_icp(
        src_pc, dst_pc, cfg.icp_max_correspondence_m, camera_T_object,
        o3d.pipelines.registration.TransformationEstimationPointToPoint(),
        o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=cfg.icp_iterations),
    )  # fmt: skip
    pose = np.asarray(result.transformation)
    shift = float(np.linalg.norm(pose[:3, 3] - camera_T_object[:3, 3]))
    info = {"fitness": float(result.fitness), "rmse": float(result.inlier_rmse), "shift_m": shift}
    accepted = shift <= cfg.max_shift_m and result.fitness >= cfg.min_fitness
    info["accepted"] = bool(accepted)
    return (pose if accepted else camera_T_object), info
