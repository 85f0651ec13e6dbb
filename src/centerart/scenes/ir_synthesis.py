"""IR images of the stereo sensor shaded from geometry instead of a second full render (``--ir-shading fast``).

Why: rasterising each IR camera with SAPIEN's lit pipeline re-renders every light's shadow maps (a point light's
cube map is six passes) per camera; on a CPU renderer that was 0.47 of the 0.95 CPU-s a stereo image cost
(``benchmarks/scenes_bench_result.json``). Here each IR camera is rasterised with SAPIEN's unlit ``trivial``
shader (albedo and position, no shadow passes) and shaded below: the dot projector's pattern with its occlusion,
the room's ambient, point and directional lights (diffuse, without shadows), then SAPIEN's display gamma. The
matcher sees the same dots, on the same surfaces, at the same brightness falloff as in the lit render.

Frames: everything is in the RGB camera's OpenCV frame (x right, y down, z forward; metres). The IR cameras and the
projector sit on its x axis (``StereoSpec``), share its orientation and intrinsics, so each IR camera is a
rectified partner of the projector: a point seen at pixel (u, v) and depth z falls on the projector's row v.

Projector model (SAPIEN's textured spot light): the pattern fills a square frustum of full angle ``fov``,
irradiance ``intensity * pattern * cos(theta) / d^2`` with Lambertian reflection ``albedo / pi``. Occlusion: the
projector is a rectified partner of each IR camera, so along an image row a pixel is in the projector's shadow when
a pixel on its projector side lands at or beyond its projector column (the scan of a disparity-based occlusion
test); surfaces hidden from the camera but seen by the projector, slivers of a few millimetres at this 1.5-4 cm
offset, cast no shadow.

Images are float32 (H, W) arrays, one per coordinate, so that every step is one vectorised pass (0.03 s per
640x480 image on one core, against 0.23 s for a lit render of the pair).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

DISPLAY_GAMMA = 2.2  # SAPIEN's composite pass: colour ** (1 / 2.2)
OCCLUSION_MARGIN_PX = 0.5  # projector columns a nearer pixel must reach past to shade (rendering noise)


@dataclass
class IrLighting:
    """What lights an IR image, in the RGB camera's OpenCV frame (see the module docstring)."""

    pattern: np.ndarray  # (H, W) float32 in 0..1, the projector's dot pattern
    projector_x: float  # m, the projector's offset along x
    fov_deg: float  # full angle of the projector's square frustum
    intensity: float
    ambient: float  # grey ambient radiance
    point_lights: list[tuple[np.ndarray, float]]  # (position (3,), grey radiance)
    directional_lights: list[tuple[np.ndarray, float]]  # (direction of travel (3,), grey radiance)


def surface_normals(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit normals (three (H, W) arrays) of a camera-frame point map from its central image-space differences,
    turned to face the camera."""
    du = [cv2.Sobel(c, cv2.CV_32F, 1, 0, ksize=1) for c in (x, y, z)]
    dv = [cv2.Sobel(c, cv2.CV_32F, 0, 1, ksize=1) for c in (x, y, z)]
    nx = du[1] * dv[2] - du[2] * dv[1]
    ny = du[2] * dv[0] - du[0] * dv[2]
    nz = du[0] * dv[1] - du[1] * dv[0]
    norm = np.sqrt(nx * nx + ny * ny + nz * nz) + 1e-12
    sign = np.where(nx * x + ny * y + nz * z > 0, -1.0, 1.0).astype(np.float32) / norm
    return nx * sign, ny * sign, nz * sign


def projector_visibility(depth: np.ndarray, fx: float, shift_x: float) -> np.ndarray:
    """(H, W) True where the projector sees each pixel's surface point. ``shift_x`` = camera x - projector x (m):
    the point of pixel u at depth z lands on projector column ``u + fx * shift_x / z`` of the same row.

    With the projector on the camera's right (``shift_x`` < 0) nearer points move further left, so pixel u is
    shaded when some pixel right of it lands at or left of its column: a reversed running minimum along the row;
    mirrored for a projector on the left. Background pixels (depth 0) shade nothing.
    """
    h, w = depth.shape
    hit = depth > 0
    offset = np.where(hit, fx * shift_x / np.where(hit, depth, 1.0), 0.0)
    col = np.arange(w, dtype=np.float64)[None, :] + offset
    if shift_x < 0:
        col = np.where(hit, col, np.inf)
        later = np.minimum.accumulate(col[:, ::-1], axis=1)[:, ::-1]
        nearest_other = np.concatenate([later[:, 1:], np.full((h, 1), np.inf)], axis=1)
        return hit & (nearest_other > col - OCCLUSION_MARGIN_PX)
    col = np.where(hit, col, -np.inf)
    earlier = np.maximum.accumulate(col, axis=1)
    nearest_other = np.concatenate([np.full((h, 1), -np.inf), earlier[:, :-1]], axis=1)
    return hit & (nearest_other < col + OCCLUSION_MARGIN_PX)


def shade_ir(albedo: np.ndarray, depth: np.ndarray, K: np.ndarray, camera_x: float, lighting: IrLighting):
    """IR image (H, W) float32 in 0..1 of the camera ``camera_x`` m along the RGB camera's x axis.

    ``albedo`` (H, W) grey surface albedo, ``depth`` (H, W) metres along the optical axis (0 = nothing hit),
    ``K`` the shared intrinsics.
    """
    h, w = depth.shape
    z = depth.astype(np.float32)
    hit = z > 0
    # The pinhole back-projection of geometry.camera.depth_to_point_map, kept as float32 per-axis arrays without
    # NaN holes: this function runs twice per stereo image and the (H, W, 3) float64 map tripled its time.
    x = (np.arange(w, dtype=np.float32)[None, :] - np.float32(K[0, 2])) / np.float32(K[0, 0]) * z
    y = (np.arange(h, dtype=np.float32)[:, None] - np.float32(K[1, 2])) / np.float32(K[1, 1]) * z
    normals = surface_normals(x, y, z)
    x = x + np.float32(camera_x)  # the RGB camera's frame from here on
    rx = x - np.float32(lighting.projector_x)  # projector to point
    half = np.float32(np.tan(np.deg2rad(lighting.fov_deg) / 2.0))
    ph, pw = lighting.pattern.shape
    safe_z = np.where(hit, z, np.float32(1.0))
    map_x = np.where(hit, (rx / safe_z / half * 0.5 + 0.5) * pw - 0.5, -1.0).astype(np.float32)
    map_y = np.where(hit, (y / safe_z / half * 0.5 + 0.5) * ph - 0.5, -1.0).astype(np.float32)
    dots = cv2.remap(lighting.pattern, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    d2 = rx * rx + y * y + z * z + np.float32(1e-6)
    cos_p = np.clip(-(normals[0] * rx + normals[1] * y + normals[2] * z) / np.sqrt(d2), 0.0, None)
    lit = projector_visibility(depth, float(K[0, 0]), camera_x - lighting.projector_x)
    irradiance = np.float32(lighting.intensity) * dots * cos_p / d2 * lit
    irradiance += room_irradiance((x, y, z), normals, lighting)
    linear = albedo * (irradiance / np.float32(np.pi) + np.float32(lighting.ambient))
    return np.where(hit, np.clip(linear, 0.0, 1.0) ** np.float32(1.0 / DISPLAY_GAMMA), 0.0).astype(np.float32)


def room_irradiance(points, normals, lighting: IrLighting) -> np.ndarray:
    """Diffuse irradiance (H, W) of the room's point and directional lights, without their shadows; ``points`` and
    ``normals`` are (x, y, z) tuples of (H, W) arrays in the RGB camera's frame."""
    x, y, z = points
    nx, ny, nz = normals
    total = np.zeros_like(x)
    for position, radiance in lighting.point_lights:
        lx, ly, lz = (np.float32(c) for c in position)
        tx, ty, tz = lx - x, ly - y, lz - z
        d2 = tx * tx + ty * ty + tz * tz + np.float32(1e-6)
        total += np.float32(radiance) * np.clip(nx * tx + ny * ty + nz * tz, 0.0, None) / (d2 * np.sqrt(d2))
    for direction, radiance in lighting.directional_lights:
        dx, dy, dz = (np.float32(-c) for c in direction)
        total += np.float32(radiance) * np.clip(nx * dx + ny * dy + nz * dz, 0.0, None)
    return total
