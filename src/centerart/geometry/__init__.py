"""Frame, pose, camera and rotation conventions, written once.

:mod:`~centerart.geometry.transforms` (poses), :mod:`~centerart.geometry.camera` (OpenCV cameras, intrinsics,
projection, renderer camera frames) and :mod:`~centerart.geometry.rotations` (quaternions, axis-angle).
"""

from centerart.geometry.transforms import (
    apply_transform,
    invert_pose,
    make_pose,
    rotation_about_axis,
    transform_about_line,
)

__all__ = ["apply_transform", "invert_pose", "make_pose", "rotation_about_axis", "transform_about_line"]
