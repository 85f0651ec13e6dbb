"""``centerart decoder show``: an object's reconstruction with its top grasps at several joint states.

One column per joint state (normalized joint codes evenly spaced over [0, 1]). The decoder's mesh is drawn
shaded in the SAPIEN scene of :class:`~centerart.viz.object_renderer.ObjectRenderer`, on a floor at the lowest
drawn point, and the top grasps as gripper markers (:func:`~centerart.viz.object_renderer.marker_boxes`) coloured
by rank: red = best, then orange, yellow, green, blue. Object canonical frame (x out of the front, z up,
metres). Top row: one camera for every column, at ``--azim`` / ``--elev`` degrees, far enough to hold every
mesh and marker whole; bottom row: a close-up on that column's grasps (as in ``centerart grasps show``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from centerart.errors import CenterArtError
from centerart.utils.checks import at_least, finite
from centerart.viz.contact_sheet import grid, labelled, save_png, titled

MESH_COLOUR = (0.62, 0.7, 0.84, 1.0)  # light steel blue: apart from the floor and every marker
RANK_COLOURS = [
    (0.9, 0.1, 0.1, 1.0),
    (0.95, 0.5, 0.1, 1.0),
    (0.9, 0.8, 0.1, 1.0),
    (0.3, 0.7, 0.2, 1.0),
    (0.2, 0.4, 0.9, 1.0),
]
"""Marker colour by grasp rank (best first); ranks past the list share its last colour."""


@dataclass
class ShowDecoderConfig:
    data: Path
    """SDF sample folder (used to fit a code when the object has none in the checkpoint, and for true states)."""
    object: str
    """Object id (folder name under --data)."""
    out: Path
    """PNG file to write."""
    checkpoint: Path | None = None
    """Decoder checkpoint (default: the shipped small checkpoint)."""
    states: int = 3
    """Joint states shown, evenly spaced normalized codes from 0 (closed) to 1 (open)."""
    top_k: int = 5
    resolution: int = 96
    elev: float = 20.0
    """Camera elevation above the horizon, degrees."""
    azim: float = 35.0
    """Camera azimuth from +x (out of the front) towards +y, degrees."""
    image_width: int = 480
    image_height: int = 360

    def __post_init__(self):
        for name in ("states", "image_width", "image_height"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 1)
        at_least("--top-k", self.top_k, 0)
        at_least("--resolution", self.resolution, 8)
        finite("--elev", self.elev)
        finite("--azim", self.azim)


def _shape_code(loaded, cfg: ShowDecoderConfig) -> tuple[np.ndarray, str]:
    """The object's trained code, or one fitted to its SDF samples with the decoder frozen; and which it is."""
    from centerart.models.code_fitting import CodeFitConfig, Observations, fit_code
    from centerart.sdf.samples import load_states

    if cfg.object in loaded.codes:
        return loaded.code(cfg.object), "trained code"
    folder = Path(cfg.data) / cfg.object
    if not folder.is_dir():
        raise CenterArtError(f"{folder}: object not in the checkpoint and no SDF samples to fit a code")
    states = [s for s in load_states(cfg.data, 20000, progress=False) if s.object_id == cfg.object]
    obs = Observations.from_states(states)
    code, _, _ = fit_code(loaded.decoder, obs, CodeFitConfig())
    return code, "fitted code (decoder frozen)"


def _extent(panels, fallback: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) corners of a box around every panel's mesh and grasp markers (object frame, m)."""
    from centerart.viz.object_renderer import marker_corners

    pts = [np.asarray(recon.mesh.vertices) for _, recon, _ in panels if len(recon.mesh.faces)]
    pts += [marker_corners(grasps.poses).reshape(-1, 3) for _, _, grasps in panels if len(grasps)]
    if not pts:  # nothing predicted anywhere: frame the checkpoint's box
        return np.asarray(fallback[0], float), np.asarray(fallback[1], float)
    pts = np.concatenate(pts)
    return pts.min(0), pts.max(0)


def _column(renderer, whole, u: float, recon, grasps) -> list[np.ndarray]:
    """The whole view and the close-up (blank without grasps) of one joint code, captioned."""
    from centerart.viz.object_renderer import close_up

    added = [renderer.add_mesh(recon.mesh, MESH_COLOUR, "reconstruction")] if len(recon.mesh.faces) else []
    for rank, pose in enumerate(grasps.poses):
        added += renderer.add_markers(pose[None], RANK_COLOURS[min(rank, len(RANK_COLOURS) - 1)])
    best = f", best {grasps.scores[0]:.2f}" if len(grasps) else ""
    renderer.look(whole)
    column = [labelled(renderer.picture(), f"joint code {u:.2f}: {len(grasps)} grasps{best}")]
    if len(grasps):
        renderer.look(close_up(grasps.poses, renderer.narrow_fov))
        column.append(labelled(renderer.picture(), f"joint code {u:.2f}: close-up on the grasps"))
    else:
        column.append(np.full_like(column[0], 255))
    renderer.remove(added)
    return column


def show_decoder(cfg: ShowDecoderConfig) -> Path:
    """Write the reconstruction sheet to ``cfg.out``: one panel per joint code (see the module doc)."""
    from centerart.inference.decoder_grasps import GraspExtractionConfig, predict_shape_and_grasps
    from centerart.inference.reconstruction import MeshConfig
    from centerart.models.checkpoint import load_decoder
    from centerart.viz.object_renderer import ObjectRenderer

    loaded = load_decoder(cfg.checkpoint)
    code, how = _shape_code(loaded, cfg)
    joints = np.linspace(0.0, 1.0, cfg.states) if cfg.states > 1 else np.array([0.0])
    mesh_cfg, grasp_cfg = MeshConfig(resolution=cfg.resolution), GraspExtractionConfig(top_k=cfg.top_k)

    def decode(u: float):  # the critic, where the checkpoint has one, ranks the grasps drawn as it does in predict
        return predict_shape_and_grasps(
            loaded.decoder, code, u, loaded.bounds, mesh_cfg, grasp_cfg, critic=loaded.critic
        )

    panels = [(float(u), *decode(float(u))) for u in joints]
    renderer = ObjectRenderer(cfg.image_width, cfg.image_height)
    lo, hi = _extent(panels, loaded.bounds)
    renderer.set_floor(lo[2])
    whole = renderer.fit_view(lo, hi, cfg.azim, cfg.elev)
    columns = [_column(renderer, whole, *panel) for panel in panels]
    rows = [[column[i] for column in columns] for i in range(2)]
    return save_png(titled(grid(rows), f"{cfg.object} ({how}); {Path(loaded.path).name}"), cfg.out)
