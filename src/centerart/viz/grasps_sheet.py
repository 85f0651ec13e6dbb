"""``centerart grasps show``: stored grasp labels drawn as gripper markers on the object at a few states.

Markers are :func:`~centerart.viz.object_renderer.marker_boxes` forks (TCP between the fingers) added to the
SAPIEN scene of :class:`~centerart.viz.object_renderer.ObjectRenderer`, so they are shaded and occluded like the
object. Successful labels are green; with ``--failures`` some failed trials are drawn in red. Rows: states;
columns: the whole object from the front right, and a close-up on the drawn grasps. Object canonical frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.errors import CenterArtError
from centerart.grasps.labels import StateLabels, load_object_labels
from centerart.utils.checks import at_least
from centerart.viz.contact_sheet import grid, labelled, save_png

GREEN = (0.1, 0.85, 0.2, 1.0)  # successful labels
RED = (0.9, 0.15, 0.1, 1.0)  # failed trials


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

    def __post_init__(self):
        for name in ("states", "image_width", "image_height"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 1)
        at_least("--grasps", self.grasps, 0)
        at_least("--failures", self.failures, 0)


def _pick(n_total: int, n: int) -> np.ndarray:
    if n_total == 0 or n <= 0:
        return np.zeros(0, int)
    return np.unique(np.linspace(0, n_total - 1, min(n, n_total)).round().astype(int))


def _object_folder(objects: Path, object_id: str) -> Path:
    """``objects/<id>``, or ``objects`` itself when it is that object's folder."""
    folder = Path(objects) / object_id
    if (folder / "mobility.urdf").is_file():
        return folder
    if (Path(objects) / "mobility.urdf").is_file() and Path(objects).name == object_id:
        return Path(objects)
    raise CenterArtError(f"{folder}: no object folder with that id")


def _state_row(renderer, art, obj: ArticulatedObject, labels: StateLabels, cfg: ShowGraspsConfig, whole) -> list:
    """The pictures of one labelled state: the whole object, and a close-up when grasps are drawn."""
    from centerart.viz.object_renderer import close_up

    renderer.set_state(art, obj, labels.q)
    drawn = labels.poses[_pick(labels.count, cfg.grasps)]
    markers = renderer.add_markers(drawn, GREEN)
    markers += renderer.add_markers(labels.failed_poses[_pick(len(labels.failed_poses), cfg.failures)], RED)
    unit = "rad" if labels.joint_type == "revolute" else "m"
    verb = "open" if labels.direction > 0 else "close"
    views = [(whole, "")] + ([(close_up(drawn, renderer.narrow_fov), " (close-up)")] if len(drawn) else [])
    row = []
    for view, suffix in views:
        renderer.look(view)
        text = (
            f"{obj.object_id} state {labels.state_index} q={labels.q:.2f} {unit} ({verb}): "
            f"{labels.count} labels, {len(drawn)} drawn{suffix}"
        )
        row.append(labelled(renderer.picture(), text))
    while len(row) < 2:
        row.append(np.full_like(row[0], 255))
    renderer.remove(markers)
    return row


def show_grasps(cfg: ShowGraspsConfig) -> Path:
    """Write the label sheet to ``cfg.out``: one row per chosen state (see the module doc)."""
    from centerart.viz.object_renderer import ObjectRenderer, View

    obj = ArticulatedObject.load(_object_folder(cfg.objects, cfg.object))
    all_states = load_object_labels(cfg.labels, cfg.object)
    chosen = [all_states[i] for i in _pick(len(all_states), cfg.states)]

    renderer = ObjectRenderer(cfg.image_width, cfg.image_height)
    art = renderer.add_object(obj)
    bounds = np.concatenate([obj.bounds(s.q) for s in chosen])
    lo, hi = bounds.min(0), bounds.max(0)
    renderer.set_floor(lo[2])
    # The whole object from the front right: its bounding sphere (+10 cm) inside the narrower field of view.
    radius = 0.5 * np.linalg.norm(hi - lo) + 0.1
    whole = View((lo + hi) / 2, radius / np.sin(renderer.narrow_fov / 2) * 0.85, 35.0, 22.0)
    rows = [_state_row(renderer, art, obj, labels, cfg, whole) for labels in chosen]
    renderer.scene.remove_articulation(art)
    return save_png(grid(rows), cfg.out)
