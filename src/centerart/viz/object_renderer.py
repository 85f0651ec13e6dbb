"""Shaded renders of articulated objects, meshes and gripper markers with SAPIEN 3's rasterizer (CPU, Mesa lavapipe).

SAPIEN loads the object's own URDF, so real PartNet-Mobility textures and generated objects' colours both show.
The object's root is placed at ``canonical_T_base`` and scaled by ``obj.scale``, so a render is in the
canonical object frame (x out of the front, z up, metres); meshes and grasp markers added to the scene are given
in that frame too. The first picture of a process costs a few seconds of shader compilation; later ones take
tens of milliseconds.

A grasp marker is the classic parallel-jaw "fork" in the TCP frame (:mod:`centerart.grasps.gripper`): a wrist
stem along -z behind the palm, a cross bar at the palm face spanning the open stroke, and two fingers reaching to
the fingertips; the TCP (pad centre) sits between the fingers. Markers are visual-only actors, so they are
shaded and occluded like the object.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.geometry.transforms import make_pose
from centerart.grasps.gripper import FINGERTIP_BEYOND_TCP, MAX_OPENING, PALM_TO_TCP

MARKER_RADIUS = 0.0025  # m, half-thickness of the marker's sticks
STEM_LENGTH = 0.04  # m of wrist stem drawn behind the palm face
_UNIT_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)


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


def view_direction(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """Unit vector from the looked-at point towards the camera (azimuth from +x towards +y, elevation up)."""
    az, el = np.deg2rad(azimuth_deg), np.deg2rad(elevation_deg)
    return np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])


@dataclass(frozen=True)
class View:
    """A camera looking at ``center`` (render frame, m) from ``dist`` metres along
    :func:`view_direction` (``azimuth_deg``, ``elevation_deg``)."""

    center: np.ndarray
    dist: float
    azimuth_deg: float
    elevation_deg: float


def close_up(tcp_poses: np.ndarray, fov: float) -> View:
    """Centred on the TCPs of poses (N, 4, 4), seen from 40 degrees beside their mean approach direction, close
    enough that their spread plus 15 cm fills the field of view ``fov`` (rad)."""
    tcps = tcp_poses[:, :3, 3]
    mean_dir = -tcp_poses[:, :3, 2].mean(0)
    az = float(np.degrees(np.arctan2(mean_dir[1], mean_dir[0]))) + 40.0
    span = float(np.linalg.norm(tcps.max(0) - tcps.min(0))) / 2 + 0.15
    return View(tcps.mean(0), span / np.sin(fov / 2), az, 25.0)


def marker_boxes(opening: float = MAX_OPENING) -> list[tuple[np.ndarray, np.ndarray]]:
    """Marker sticks as (half extents (3,), ``tcp_T_box``), TCP frame, metres."""
    r, w = MARKER_RADIUS, opening / 2
    finger_len = PALM_TO_TCP + FINGERTIP_BEYOND_TCP
    finger_z = -PALM_TO_TCP + finger_len / 2
    return [
        (np.array([r, r, STEM_LENGTH / 2]), make_pose(translation=[0, 0, -PALM_TO_TCP - STEM_LENGTH / 2])),
        (np.array([r, w + r, r]), make_pose(translation=[0, 0, -PALM_TO_TCP])),
        (np.array([r, r, finger_len / 2]), make_pose(translation=[0, -w, finger_z])),
        (np.array([r, r, finger_len / 2]), make_pose(translation=[0, w, finger_z])),
    ]


def marker_corners(poses: np.ndarray) -> np.ndarray:
    """(N, 4 sticks, 8, 3) corners of the marker sticks of TCP poses (N, 4, 4), in the poses' frame (m).

    What the camera must keep in the picture to show every marker whole."""
    local = np.stack([_UNIT_CORNERS * half @ T[:3, :3].T + T[:3, 3] for half, T in marker_boxes()])
    poses = np.asarray(poses, float).reshape(-1, 4, 4)
    return np.einsum("nij,skj->nski", poses[:, :3, :3], local) + poses[:, None, None, :3, 3]


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

    def set_floor(self, z: float) -> None:
        """Put the floor's top just below height ``z`` (m, render frame), so what starts at ``z`` stands on it."""
        for e in self._ground:
            e.set_pose(self._sapien.Pose([0, 0, z + 10.0 - 0.001]))

    def fit_distance(self, lo: np.ndarray, hi: np.ndarray, center: np.ndarray, back: np.ndarray) -> float:
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

    @property
    def narrow_fov(self) -> float:
        """The smaller of the vertical and the horizontal field of view, rad."""
        return min(self.fovy, self.fovy * self.width / self.height)

    def fit_view(self, lo: np.ndarray, hi: np.ndarray, azimuth_deg: float, elevation_deg: float) -> View:
        """The view from that direction that holds the box [lo, hi] (render frame, m) whole."""
        center = (lo + hi) / 2
        back = view_direction(azimuth_deg, elevation_deg)
        return View(center, self.fit_distance(lo, hi, center, back), azimuth_deg, elevation_deg)

    def look(self, view: View) -> None:
        """Move the camera to ``view``."""
        eye = view.center + view.dist * view_direction(view.azimuth_deg, view.elevation_deg)
        self.camera.entity.set_pose(self._sapien.Pose(look_at_pose(eye, view.center)))

    def picture(self) -> np.ndarray:
        """RGB image (H, W, 3, uint8) of the scene as it is now."""
        self.scene.update_render()
        self.camera.take_picture()
        rgba = self.camera.get_picture("Color")
        return (np.clip(rgba[..., :3], 0, 1) * 255).astype(np.uint8)

    def add_object(self, obj: ArticulatedObject):
        """Load ``obj``'s URDF with its root at ``canonical_T_base``: the render frame is the canonical frame."""
        loader = self.scene.create_urdf_loader()
        loader.fix_root_link = True
        loader.scale = obj.scale
        art = loader.load(str(obj.path / "mobility.urdf"))
        art.set_root_pose(self._sapien.Pose(obj.canonical_T_base))
        return art

    @staticmethod
    def set_state(art, obj: ArticulatedObject, q: float) -> None:
        """Pose the loaded articulation at target-joint state ``q`` (metric: rad or m)."""
        config = obj.configuration(q)
        names = [j.name for j in art.get_active_joints()]
        art.set_qpos(np.array([config.get(n, 0.0) for n in names], dtype=np.float32))

    def add_markers(self, poses: np.ndarray, rgba) -> list:
        """One gripper marker (:func:`marker_boxes`) per TCP pose (N, 4, 4), render frame; returns the actors."""
        sapien = self._sapien
        material = sapien.render.RenderMaterial(base_color=list(rgba))
        actors = []
        for pose in poses:
            builder = self.scene.create_actor_builder()
            for half, tcp_T_box in marker_boxes():
                builder.add_box_visual(pose=sapien.Pose(tcp_T_box), half_size=half.tolist(), material=material)
            actor = builder.build_static(name="grasp_marker")
            actor.set_pose(sapien.Pose(pose))
            actors.append(actor)
        return actors

    def add_mesh(self, mesh, rgba, name: str = "mesh"):
        """A trimesh (render frame, m) as a visual-only entity in one colour, smooth-shaded by vertex normals."""
        sapien = self._sapien
        v = np.asarray(mesh.vertices, np.float32)
        shape = sapien.render.RenderShapeTriangleMesh(
            v,
            np.asarray(mesh.faces, np.uint32),
            np.asarray(mesh.vertex_normals, np.float32),
            np.zeros((len(v), 2), np.float32),
            sapien.render.RenderMaterial(base_color=list(rgba)),
        )
        body = sapien.render.RenderBodyComponent()
        body.attach(shape)
        entity = sapien.Entity()
        entity.name = name
        entity.add_component(body)
        self.scene.add_entity(entity)
        return entity

    def remove(self, entities) -> None:
        """Take added markers or meshes out of the scene again."""
        for e in entities:
            self.scene.remove_entity(e)

    def render_states(
        self,
        obj: ArticulatedObject,
        states: list[float],
        azimuth_deg: float = 35.0,
        elevation_deg: float = 22.0,
    ) -> list[np.ndarray]:
        """RGB images (H, W, 3, uint8) of ``obj`` at each target-joint state (metric)."""
        art = self.add_object(obj)
        try:
            bounds = np.concatenate([obj.bounds(q) for q in states])
            lo, hi = bounds.min(0), bounds.max(0)
            self.set_floor(lo[2])
            self.look(self.fit_view(lo, hi, azimuth_deg, elevation_deg))
            images = []
            for q in states:
                self.set_state(art, obj, q)
                images.append(self.picture())
            return images
        finally:
            self.scene.remove_articulation(art)
