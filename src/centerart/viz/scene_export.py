"""``scene.glb``: the observed point cloud, predicted meshes, grasps (gripper meshes) and joint axes in one glTF
file that any 3-D viewer opens (Blender, MeshLab, online glTF viewers).

glTF is y-up with the viewer looking down -z, which is the OpenGL camera frame: the OpenCV camera-frame scene is
mapped with ``OPENGL_T_OPENCV`` (y and z flipped), so a viewer's default view looks at the scene as the camera did.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from centerart.geometry.camera import OPENCV_T_OPENGL
from centerart.grasps.gripper import gripper_mesh
from centerart.utils.atomic import atomic_write_bytes
from centerart.viz.scenes_sheet import PALETTE

OPENGL_T_OPENCV = np.linalg.inv(OPENCV_T_OPENGL)


def axis_cylinder(point: np.ndarray, direction: np.ndarray, length: float = 0.6, radius: float = 0.006):
    d = np.asarray(direction, float) / max(np.linalg.norm(direction), 1e-9)
    a, b = np.asarray(point, float) - d * length / 2, np.asarray(point, float) + d * length / 2
    cyl = trimesh.creation.cylinder(radius=radius, segment=np.stack([a, b]))
    cyl.visual.face_colors = [255, 220, 0, 255]
    return cyl


def build_scene(points: np.ndarray, colors: np.ndarray | None, preds, meshes: list, top_k: int = 5) -> trimesh.Scene:
    """A trimesh scene in the OpenCV camera frame's coordinates mapped to glTF's (see module docstring)."""
    scene = trimesh.Scene()
    if len(points):
        scene.add_geometry(trimesh.PointCloud(points, colors=colors), node_name="observed_points")
    for k, pred in enumerate(preds):
        color = np.append(PALETTE[k % len(PALETTE)], 255)
        if k < len(meshes) and meshes[k] is not None:
            mesh = meshes[k].copy()
            mesh.visual.face_colors = np.append(PALETTE[k % len(PALETTE)], 200)
            scene.add_geometry(mesh, node_name=f"object_{k:02d}_mesh")
        for r, pose in enumerate(pred.grasp_poses[:top_k]):
            g = gripper_mesh(pose)
            g.visual.face_colors = color
            scene.add_geometry(g, node_name=f"object_{k:02d}_grasp_{r}")
        scene.add_geometry(axis_cylinder(pred.axis_point, pred.axis_direction), node_name=f"object_{k:02d}_axis")
    scene.apply_transform(OPENGL_T_OPENCV)
    return scene


def write_glb(scene: trimesh.Scene, path: Path) -> Path:
    atomic_write_bytes(Path(path), scene.export(file_type="glb"))
    return Path(path)
