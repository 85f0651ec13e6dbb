"""Frame and pose conventions, written once (see :mod:`centerart.geometry.transforms`)."""

from centerart.geometry.transforms import (
    apply_transform,
    invert_pose,
    make_pose,
    rotation_about_axis,
    transform_about_line,
)

__all__ = ["apply_transform", "invert_pose", "make_pose", "rotation_about_axis", "transform_about_line"]
