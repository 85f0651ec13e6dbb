"""Camera intrinsics presets and camera poses sampled on a shell around a point of interest.

Poses are ``world_T_camera`` in the OpenCV convention (x right, y down, z forward). ``K`` uses OpenCV's pixel
convention (the centre of pixel (u, v) is at integer coordinates (u, v)); both conventions are written once in
:mod:`centerart.geometry.camera`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from centerart.geometry.camera import Intrinsics

#: name -> (width, height, fx, fy). Principal point at the image centre ((w - 1) / 2, (h - 1) / 2).
INTRINSICS_PRESETS: dict[str, tuple[int, int, float, float]] = {
    # RealSense D415 colour stream at 640x480: about 69 x 42 degrees -> fx ~ 615 px at this resolution.
    "d415": (640, 480, 615.0, 615.0),
    # The paper's camera (ZED 2 at half resolution): 960x512, f = 530 px.
    "paper": (960, 512, 530.0, 530.0),
    # The d415 camera at half size: the small encoder's input (320x240), so the loader's letterbox is the identity.
    "d415-half": (320, 240, 307.5, 307.5),
    # Small images for tests and quick previews.
    "tiny": (320, 240, 307.5, 307.5),
}


def intrinsics(preset: str) -> tuple[int, int, np.ndarray]:
    """(width, height, K) of a preset."""
    if preset not in INTRINSICS_PRESETS:
        raise ValueError(f"unknown intrinsics preset {preset!r}; choose from {sorted(INTRINSICS_PRESETS)}")
    w, h, fx, fy = INTRINSICS_PRESETS[preset]
    camera = Intrinsics(w, h, fx, fy, (w - 1) / 2.0, (h - 1) / 2.0)
    return camera.width, camera.height, camera.K


@dataclass
class ShellRanges:
    """Where cameras are sampled around the point of interest (world frame, z up, objects face +x).

    Radius is drawn so that points are uniform in the shell's volume; elevation is above the horizontal; azimuth
    is measured from +x (straight in front of the wall) towards +y.
    """

    radius_m: tuple[float, float] = (1.0, 2.5)
    elevation_deg: tuple[float, float] = (10.0, 40.0)
    azimuth_deg: tuple[float, float] = (-40.0, 40.0)
    target_jitter_m: float = 0.05
    roll_deg: float = 3.0
    """Standard deviation of the camera roll about its optical axis (a hand-held or robot-mounted tilt)."""


def look_at_opencv(eye: np.ndarray, target: np.ndarray, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """``world_T_camera`` (OpenCV) at ``eye`` looking at ``target`` with image-up close to world ``up``."""
    z = np.asarray(target, float) - np.asarray(eye, float)
    z /= np.linalg.norm(z)
    x = np.cross(z, np.asarray(up, float))
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, :3] = np.stack([x, y, z], axis=1)
    pose[:3, 3] = eye
    return pose


def sample_shell_pose(rng: np.random.Generator, target: np.ndarray, ranges: ShellRanges) -> np.ndarray:
    """A ``world_T_camera`` (OpenCV) on the shell around ``target``, looking at it (with jitter and roll)."""
    r0, r1 = ranges.radius_m
    radius = (r0**3 + rng.random() * (r1**3 - r0**3)) ** (1.0 / 3.0)
    el = np.deg2rad(rng.uniform(*ranges.elevation_deg))
    az = np.deg2rad(rng.uniform(*ranges.azimuth_deg))
    direction = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    aim = np.asarray(target, float) + rng.uniform(-1, 1, 3) * ranges.target_jitter_m
    pose = look_at_opencv(aim + radius * direction, aim)
    roll = np.deg2rad(rng.normal(0.0, ranges.roll_deg))
    c, s = np.cos(roll), np.sin(roll)
    pose[:3, :3] = pose[:3, :3] @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return pose
