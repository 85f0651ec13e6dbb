"""``centerart decoder show``: pictures of an object's reconstruction with its top grasps at several joint states.

One panel per joint state (normalized joint codes evenly spaced over [0, 1]); the mesh is drawn in grey with
matplotlib (headless, no GPU), the top grasps as gripper wireframes (wrist, palm, fingers) coloured by rank (red =
best). Object canonical frame: x out of the front, z up; the view looks at the front from the right.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from centerart.errors import CenterArtError
from centerart.grasps.gripper import CONTROL_POINTS_TCP


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
    azim: float = 35.0


def gripper_segments(pose: np.ndarray) -> np.ndarray:
    """(4, 2, 3) line segments of a gripper wireframe for a TCP pose (4, 4)."""
    cp = CONTROL_POINTS_TCP @ pose[:3, :3].T + pose[:3, 3]
    palm_c = 0.5 * (cp[1] + cp[2])
    return np.array([[cp[0], palm_c], [cp[1], cp[2]], [cp[1], cp[3]], [cp[2], cp[4]]])


def render_panel(ax, mesh, grasps_poses: np.ndarray, title: str, elev: float, azim: float, bounds: np.ndarray):
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    if len(mesh.faces):
        faces = mesh.faces
        if len(faces) > 20000:  # drawing cost; every face would be sub-pixel anyway
            faces = faces[np.linspace(0, len(faces) - 1, 20000).astype(int)]
        tris = mesh.vertices[faces]
        normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        normals /= np.linalg.norm(normals, axis=1, keepdims=True).clip(1e-12)
        light = np.array([0.5, 0.3, 0.8]) / np.linalg.norm([0.5, 0.3, 0.8])
        shade = 0.35 + 0.6 * np.clip(normals @ light, 0, 1)
        colors = np.column_stack([shade, shade, shade * 1.05, np.ones_like(shade)]).clip(0, 1)
        ax.add_collection3d(Poly3DCollection(tris, facecolors=colors, edgecolors="none"))
    cmap = [(0.9, 0.1, 0.1), (0.95, 0.5, 0.1), (0.9, 0.8, 0.1), (0.3, 0.7, 0.2), (0.2, 0.4, 0.9)]
    for r, pose in enumerate(grasps_poses[::-1]):
        rank = len(grasps_poses) - 1 - r
        segs = gripper_segments(pose)
        ax.add_collection3d(Line3DCollection(segs, colors=[cmap[min(rank, len(cmap) - 1)]], linewidths=2.5))
    lo, hi = bounds
    c, half = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(c[0] - half, c[0] + half)
    ax.set_ylim(c[1] - half, c[1] + half)
    ax.set_zlim(c[2] - half, c[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_title(title, fontsize=9)
    ax.set_axis_off()


def show_decoder(cfg: ShowDecoderConfig) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from centerart.inference.decoder_grasps import GraspExtractionConfig, predict_shape_and_grasps
    from centerart.inference.reconstruction import MeshConfig
    from centerart.models.checkpoint import load_decoder
    from centerart.models.code_fitting import CodeFitConfig, Observations, fit_code
    from centerart.sdf.samples import load_states

    loaded = load_decoder(cfg.checkpoint)
    if cfg.object in loaded.codes:
        code, how = loaded.code(cfg.object), "trained code"
    else:
        folder = Path(cfg.data) / cfg.object
        if not folder.is_dir():
            raise CenterArtError(f"{folder}: object not in the checkpoint and no SDF samples to fit a code")
        states = [s for s in load_states(cfg.data, 20000, progress=False) if s.object_id == cfg.object]
        obs = Observations.from_samples([(s.joint, s.points, s.sdf) for s in states])
        code, _, _ = fit_code(loaded.decoder, obs, CodeFitConfig())
        how = "fitted code (decoder frozen)"
    joints = np.linspace(0.0, 1.0, cfg.states) if cfg.states > 1 else np.array([0.0])
    fig = plt.figure(figsize=(4.2 * len(joints), 4.4), dpi=110)
    for i, u in enumerate(joints):
        recon, grasps = predict_shape_and_grasps(
            loaded.decoder,
            code,
            float(u),
            loaded.bounds,
            MeshConfig(resolution=cfg.resolution),
            GraspExtractionConfig(top_k=cfg.top_k),
        )
        ax = fig.add_subplot(1, len(joints), i + 1, projection="3d")
        best = f", best {grasps.scores[0]:.2f}" if len(grasps) else ""
        render_panel(
            ax,
            recon.mesh,
            grasps.poses,
            f"joint code {u:.2f}: {len(grasps)} grasps{best}",
            cfg.elev,
            cfg.azim,
            loaded.bounds,
        )
    fig.suptitle(f"{cfg.object} ({how}); {Path(loaded.path).name}", fontsize=10)
    fig.tight_layout()
    out = Path(cfg.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.stem + ".tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    tmp.replace(out)
    return out
