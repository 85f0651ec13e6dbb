"""``centerart grasps show``: stored grasp labels drawn as gripper markers on the object at a few states.

Each marker is the classic parallel-jaw "fork" in the TCP frame (:mod:`centerart.grasps.gripper`): a wrist stem
along -z behind the palm, a cross bar at the palm face spanning the open stroke, and two fingers reaching to
the fingertips; the TCP (pad centre) sits between the fingers. Successful labels are green; with
``--failures`` some failed trials are drawn in red. Markers are visual-only actors in the SAPIEN scene of
:class:`~centerart.viz.object_renderer.ObjectRenderer`, so they are shaded and occluded like the object.
Rows: states; columns: two views (front-right and front-left).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.errors import CenterArtError
from centerart.geometry.transforms import make_pose
from centerart.grasps.gripper import FINGERTIP_BEYOND_TCP, MAX_OPENING, PALM_TO_TCP
from centerart.grasps.labels import load_object_labels
from centerart.viz.contact_sheet import grid, labelled, save_png

MARKER_RADIUS = 0.0025  # m, half-thickness of the marker's sticks
STEM_LENGTH = 0.04  # m of wrist stem drawn behind the palm face


@dataclass
class ShowGraspsConfig:
    """Draw stored grasp labels as gripper markers on an object at a few joint states."""

    labels: Path
    """Label folder written by `centerart grasps generate`."""
    objects: Path
    """Folder holding the object folders (or the object folder itself)."""
    object: str
    """Object id (its folder name)."""
    out: Path = Path("grasps.png")
    """PNG file to write."""
    states: int = 3
    """How many of the stored states to show (evenly picked, closed to open)."""
    grasps: int = 20
    """Successful grasps drawn per state (evenly picked from the stored ones)."""
    failures: int = 0
    """Failed trials drawn per state in red."""
    image_width: int = 480
    image_height: int = 360


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


def _pick(n_total: int, n: int) -> np.ndarray:
    if n_total == 0 or n <= 0:
        return np.zeros(0, int)
    return np.unique(np.linspace(0, n_total - 1, min(n, n_total)).round().astype(int))


def show_grasps(cfg: ShowGraspsConfig) -> Path:
    import sapien

    from centerart.viz.object_renderer import ObjectRenderer, look_at_pose

    folder = Path(cfg.objects) / cfg.object
    if not (folder / "mobility.urdf").is_file():
        if (Path(cfg.objects) / "mobility.urdf").is_file() and Path(cfg.objects).name == cfg.object:
            folder = Path(cfg.objects)
        else:
            raise CenterArtError(f"{folder}: no object folder with that id")
    obj = ArticulatedObject.load(folder)
    all_states = load_object_labels(cfg.labels, cfg.object)
    chosen = [all_states[i] for i in _pick(len(all_states), cfg.states)]

    renderer = ObjectRenderer(cfg.image_width, cfg.image_height)
    scene = renderer.scene
    loader = scene.create_urdf_loader()
    loader.fix_root_link = True
    loader.scale = obj.scale
    art = loader.load(str(obj.path / "mobility.urdf"))
    art.set_root_pose(sapien.Pose(obj.canonical_T_base))
    names = [j.name for j in art.get_active_joints()]
    green = sapien.render.RenderMaterial(base_color=[0.1, 0.85, 0.2, 1.0])
    red = sapien.render.RenderMaterial(base_color=[0.9, 0.15, 0.1, 1.0])

    bounds = np.concatenate([obj.bounds(s.q) for s in chosen])
    lo, hi = bounds.min(0), bounds.max(0)
    for e in renderer._ground:
        e.set_pose(sapien.Pose([0, 0, lo[2] + 10.0 - 0.001]))
    center = (lo + hi) / 2
    radius = 0.5 * np.linalg.norm(hi - lo) + 0.1
    fov = min(renderer.fovy, renderer.fovy * renderer.width / renderer.height)
    dist = radius / np.sin(fov / 2) * 0.85
    rows = []
    for labels in chosen:
        config = obj.configuration(labels.q)
        art.set_qpos(np.array([config.get(n, 0.0) for n in names], dtype=np.float32))
        actors = []
        for poses, material in (
            (labels.poses[_pick(labels.count, cfg.grasps)], green),
            (labels.failed_poses[_pick(len(labels.failed_poses), cfg.failures)], red),
        ):
            for pose in poses:
                builder = scene.create_actor_builder()
                for half, tcp_T_box in marker_boxes():
                    builder.add_box_visual(pose=sapien.Pose(tcp_T_box), half_size=half.tolist(), material=material)
                actor = builder.build_static(name="grasp_marker")
                actor.set_pose(sapien.Pose(pose))
                actors.append(actor)
        row = []
        unit = "rad" if labels.joint_type == "revolute" else "m"
        verb = "open" if labels.direction > 0 else "close"
        for az in (35.0, -35.0):
            a, el = np.deg2rad(az), np.deg2rad(22.0)
            eye = center + dist * np.array([np.cos(el) * np.cos(a), np.cos(el) * np.sin(a), np.sin(el)])
            renderer.camera.entity.set_pose(sapien.Pose(look_at_pose(eye, center)))
            scene.update_render()
            renderer.camera.take_picture()
            rgba = renderer.camera.get_picture("Color")
            img = (np.clip(rgba[..., :3], 0, 1) * 255).astype(np.uint8)
            text = (
                f"{obj.object_id} state {labels.state_index} q={labels.q:.2f} {unit} ({verb}): "
                f"{labels.count} labels, {min(labels.count, cfg.grasps)} drawn"
            )
            row.append(labelled(img, text))
        rows.append(row)
        for actor in actors:
            scene.remove_actor(actor)
    scene.remove_articulation(art)
    return save_png(grid(rows), cfg.out)
