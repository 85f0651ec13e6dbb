"""Shaded renders of articulated objects with SAPIEN 3's rasterizer (CPU through Mesa lavapipe).

SAPIEN loads the object's own URDF, so real PartNet-Mobility textures and generated objects' colours both show.
The object's root is placed at ``canonical_T_base`` and scaled by ``obj.scale``, so a render is in the
canonical object frame (x out of the front, z up). The first picture of a process costs a few seconds of shader
compilation; later ones take tens of milliseconds.
"""

from __future__ import annotations

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject


def look_at_pose(eye: np.ndarray, target: np.ndarray, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """``world_T_camera`` for SAPIEN's camera convention (x forward, y left, z up)."""
    fwd = np.asarray(target, float) - np.asarray(eye, float)
    fwd /= np.linalg.norm(fwd)
    left = np.cross(up, fwd)
    left /= np.linalg.norm(left)
    pose = np.eye(4)
    pose[:3, :3] = np.stack([fwd, left, np.cross(fwd, left)], axis=1)
    pose[:3, 3] = eye
    return pose


class ObjectRenderer:
    """Renders one object at a time on a floor under soft light, seen from front-right and above."""

    def __init__(self, width: int = 320, height: int = 240, fovy_deg: float = 40.0):
        import sapien

        self._sapien = sapien
        self.width, self.height = width, height
        self.fovy = np.deg2rad(fovy_deg)
        self.scene = sapien.Scene()
        self.scene.set_ambient_light([0.45, 0.45, 0.45])
        self.scene.add_directional_light([-0.6, 0.4, -1.0], [0.75, 0.75, 0.72], shadow=True)
        self.scene.add_directional_light([0.3, -0.8, -0.4], [0.25, 0.25, 0.3])
        mat = sapien.render.RenderMaterial(base_color=[0.78, 0.76, 0.72, 1.0])
        self.scene.add_ground(altitude=-10.0, render_material=mat)
        self._ground = [e for e in self.scene.entities if "ground" in e.name.lower()]
        self.camera = self.scene.add_camera("camera", width, height, self.fovy, 0.01, 20.0)

    def _fit_distance(self, lo: np.ndarray, hi: np.ndarray, center: np.ndarray, back: np.ndarray) -> float:
        """Smallest camera distance along ``back`` at which all 8 box corners are inside the image (+8% margin).

        For a corner c (relative to the centre) the camera needs dist >= |lateral(c)| / tan(half fov) + depth(c).
        """
        pose = look_at_pose(back, np.zeros(3))
        fwd, left, up = pose[:3, 0], pose[:3, 1], pose[:3, 2]
        tan_v = np.tan(self.fovy / 2)
        tan_h = tan_v * self.width / self.height
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        rel = corners - center
        need = np.maximum(np.abs(rel @ left) / tan_h, np.abs(rel @ up) / tan_v) * 1.08 - rel @ fwd
        return float(need.max())

    def render_states(
        self,
        obj: ArticulatedObject,
        states: list[float],
        azimuth_deg: float = 35.0,
        elevation_deg: float = 22.0,
    ) -> list[np.ndarray]:
        """RGB images (H, W, 3, uint8) of ``obj`` at each target-joint state (metric)."""
        sapien = self._sapien
        loader = self.scene.create_urdf_loader()
        loader.fix_root_link = True
        loader.scale = obj.scale
        art = loader.load(str(obj.path / "mobility.urdf"))
        try:
            art.set_root_pose(sapien.Pose(obj.canonical_T_base))
            names = [j.name for j in art.get_active_joints()]
            bounds = np.concatenate([obj.bounds(q) for q in states])
            lo, hi = bounds.min(0), bounds.max(0)
            for e in self._ground:
                e.set_pose(sapien.Pose([0, 0, lo[2] + 10.0 - 0.001]))
            center = (lo + hi) / 2
            az, el = np.deg2rad(azimuth_deg), np.deg2rad(elevation_deg)
            back = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
            dist = self._fit_distance(lo, hi, center, back)
            self.camera.entity.set_pose(sapien.Pose(look_at_pose(center + dist * back, center)))
            images = []
            for q in states:
                config = obj.configuration(q)
                art.set_qpos(np.array([config.get(n, 0.0) for n in names], dtype=np.float32))
                self.scene.update_render()
                self.camera.take_picture()
                rgba = self.camera.get_picture("Color")
                images.append((np.clip(rgba[..., :3], 0, 1) * 255).astype(np.uint8))
            return images
        finally:
            self.scene.remove_articulation(art)
