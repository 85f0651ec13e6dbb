"""``centerart view DIR``: an interactive 3-D viewer (viser, in a web browser) of a prediction folder.

Shows what ``centerart predict`` wrote to DIR (``predictions.json``, schema in
:mod:`centerart.inference.prediction_io`): the observed coloured point cloud (``points.ply``; else back-projected
from ``depth.npy`` and ``rgb.png``), each object's mesh (``object_XX.ply``; decoded from its shape code when the
file is missing), its frame, its joint axis, and its ranked grasps as gripper markers coloured by score (or by
source: decoder / observed / handle, where grasp anchoring saved them). The ``rejected`` layer (off at start) shows
the candidates anchoring rejected, as thin outlines coloured by reason (the overlay's :data:`REASON_COLORS`).

GUI: a checkbox per layer and per object, a top-k grasps slider, a grasp-colour choice, and a slider per object that
moves its joint state (normalized, 0 closed .. 1 open) and re-decodes the mesh with the decoder the prediction was
made with.

Frames: every pose in the file is ``camera_T_X`` in the OpenCV camera frame (x right, y down, z forward). The whole
scene hangs under one node, ``/camera``, posed as ``world_T_camera = WORLD_R_CAMERA`` (-90 degrees about x), so
that viser's z-up world shows it upright; the initial view looks from the camera with the image's field of view.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import trimesh
import tyro

from centerart.errors import CenterArtError
from centerart.geometry.rotations import quat_from_matrix
from centerart.grasps.gripper import FINGERTIP_BEYOND_TCP, MAX_OPENING, PALM_TO_TCP, gripper_mesh
from centerart.inference.prediction_io import read_predictions
from centerart.utils.checks import at_least, between, positive

#: Columns: the OpenCV camera axes (x right, y down, z forward) in viser's z-up world (x right, y forward, z up).
WORLD_R_CAMERA = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
ROOT = "/camera"
LAYERS = ("points", "meshes", "grasps", "rejected", "axes", "frames")
#: RGB of kept grasps by source (grasp anchoring), when the grasp colour is "source".
SOURCE_COLORS = {"decoder": (80, 120, 255), "observed": (40, 200, 90), "handle": (255, 150, 0)}
AXIS_LENGTH = 0.6  # m, joint-axis line through the predicted axis point
AXIS_COLOR = (255, 200, 0)
LAYER_HINTS = {"rejected": "grasp candidates that anchoring rejected: pale blue-grey far from material, "
               "cyan no material between the pads, magenta collides with observed points"}  # fmt: skip
#: Gripper outline in the TCP frame (segments, m): wrist stem, palm bar, two fingers to their tips.
GRIPPER_SEGMENTS_TCP = np.array(
    [
        [[0.0, 0.0, -PALM_TO_TCP - 0.06], [0.0, 0.0, -PALM_TO_TCP]],
        [[0.0, -MAX_OPENING / 2, -PALM_TO_TCP], [0.0, MAX_OPENING / 2, -PALM_TO_TCP]],
        [[0.0, -MAX_OPENING / 2, -PALM_TO_TCP], [0.0, -MAX_OPENING / 2, FINGERTIP_BEYOND_TCP]],
        [[0.0, MAX_OPENING / 2, -PALM_TO_TCP], [0.0, MAX_OPENING / 2, FINGERTIP_BEYOND_TCP]],
    ]
)


@dataclass
class ViewConfig:
    """Open an interactive 3-D viewer of a prediction folder (written by centerart predict) in a web browser."""

    path: Annotated[Path, tyro.conf.Positional]
    """Prediction folder (holding predictions.json), or the predictions.json file itself."""
    port: int = 8080
    """HTTP port (the next free one if taken)."""
    host: str = "127.0.0.1"
    """Address to listen on (0.0.0.0: reachable from other machines)."""
    top_k: int = 5
    """Grasps shown per object at start (the GUI slider changes it)."""
    grasp_style: Literal["lines", "mesh"] = "lines"
    """Gripper markers: outline lines, or the gripper's box mesh."""
    resolution: int = 64
    """Marching-cubes resolution of the meshes decoded in the viewer (joint sliders, missing mesh files)."""
    decoder: Path | None = None
    """Decoder checkpoint (default: the one named in predictions.json, else the shipped one)."""
    max_points: int = 200_000
    """Show at most this many points of the observed cloud (evenly subsampled)."""
    point_size: float = 0.004
    """Point size in metres (the GUI slider changes it)."""
    mesh_opacity: float = 0.8
    """Object mesh opacity, 0..1 (the GUI slider changes it); below 1 the frames and grasps inside show."""
    show_rejected: bool = False
    """Show the grasp candidates that anchoring rejected, coloured by reason, at start (a GUI checkbox toggles it)."""
    grasp_colors: Literal["score", "source"] = "score"
    """Kept grasps coloured by score, or by source (decoder / observed / handle); the GUI changes it."""

    def __post_init__(self):
        at_least("--top-k", self.top_k, 0)
        at_least("--resolution", self.resolution, 8)
        at_least("--max-points", self.max_points, 1)
        positive("--point-size", self.point_size)
        between("--mesh-opacity", self.mesh_opacity, 0.0, 1.0)


@dataclass
class ObjectView:
    """One object's scene nodes and joint-slider state."""

    record: dict
    color: tuple[int, int, int]
    nodes: dict = field(default_factory=dict)
    grasps: list = field(default_factory=list)
    rejected: dict = field(default_factory=dict)
    """Rejection reason -> one line-segments node with all of the object's candidates rejected for it."""
    joint: float = 0.0
    requested: float = 0.0
    lock: threading.Lock = field(default_factory=threading.Lock)
    gui: dict = field(default_factory=dict)
    num_faces: int = 0


def _palette(k: int) -> tuple[int, int, int]:
    from centerart.viz.scenes_sheet import PALETTE

    return tuple(int(c) for c in PALETTE[k % len(PALETTE)])


def score_colors(scores: np.ndarray) -> np.ndarray:
    """RGB uint8 (N, 3) of grasp scores in [0, 1]: the plasma colour map up to orange (dark violet 0, orange 1),
    leaving yellow to the joint axes."""
    from matplotlib import colormaps

    return (colormaps["plasma"](0.85 * np.clip(np.asarray(scores, float), 0.0, 1.0))[:, :3] * 255).astype(np.uint8)


def grasp_colors(grasps: list[dict], mode: str) -> np.ndarray:
    """RGB uint8 (N, 3) of saved grasps: by score (:func:`score_colors`), or by their ``source``
    (:data:`SOURCE_COLORS`; a grasp without a known source keeps its score colour)."""
    if not grasps:
        return np.zeros((0, 3), np.uint8)
    colors = score_colors([g.get("score", 0.0) for g in grasps])
    if mode == "source":
        for r, g in enumerate(grasps):
            if g.get("source") in SOURCE_COLORS:
                colors[r] = SOURCE_COLORS[g["source"]]
    return colors


def anchoring_markdown(rec: dict) -> str | None:
    """A line for an object's GUI folder: grasp anchoring's counts (candidates per source, survivors of each
    check, kept) and the rejected candidates per reason; None when the record has no anchoring counts."""
    counts = (rec.get("refinement") or {}).get("anchoring")
    if not counts:
        return None
    sources = ", ".join(f"{s} {counts.get(f'candidates_{s}', 0)}" for s in SOURCE_COLORS)
    checks = ", ".join(f"{k.replace('_', ' ')} {counts[k]}" for k in ("snapped", "material_between_pads", "clear")
                       if k in counts)  # fmt: skip
    reasons: dict[str, int] = {}
    for r in rec.get("rejected_grasps") or []:
        reasons[r["reason"]] = reasons.get(r["reason"], 0) + 1
    rejected = ", ".join(f"{k.replace('_', ' ')} {n}" for k, n in sorted(reasons.items())) or "none"
    return f"anchoring: candidates {sources}; survived {checks}; kept {counts.get('kept', 0)}. Rejected: {rejected}"


def _wxyz(rot: np.ndarray) -> np.ndarray:
    x, y, z, w = quat_from_matrix(np.asarray(rot, float))
    return np.array([w, x, y, z])


def _pose_kwargs(pose: np.ndarray) -> dict:
    pose = np.asarray(pose, float)
    return {"wxyz": _wxyz(pose[:3, :3]), "position": pose[:3, 3]}


def load_points(folder: Path, data: dict, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Observed points (N, 3) (camera frame, m) and colours (N, 3) uint8: ``points.ply``, else the depth image
    back-projected with the file's K (coloured by ``rgb.png`` when present); empty when neither is there."""
    inputs = data.get("inputs") or {}
    ply = folder / inputs.get("points", "points.ply")
    depth_file = folder / inputs.get("depth", "depth.npy")
    points, colors = np.zeros((0, 3)), None
    if ply.is_file():
        try:
            cloud = trimesh.load(ply, process=False)
        except Exception as err:  # trimesh raises many types for bad files
            raise CenterArtError(f"{ply}: not a readable point cloud ({_first_line(err)})") from None
        points = np.asarray(cloud.vertices, float)
        vc = getattr(cloud, "colors", None)
        if vc is None or len(vc) != len(points):
            vc = getattr(getattr(cloud, "visual", None), "vertex_colors", None)
        if vc is not None and len(vc) == len(points):
            colors = np.asarray(vc)[:, :3].astype(np.uint8)
    elif depth_file.suffix == ".npy" and depth_file.is_file() and "image" in data:
        from centerart.geometry.camera import backproject_depth
        from centerart.inference.inputs import read_depth, read_rgb

        depth = read_depth(depth_file)
        points, uv = backproject_depth(depth, np.asarray(data["image"]["K"], float), return_pixels=True)
        rgb_file = folder / inputs.get("rgb", "rgb.png")
        if rgb_file.is_file():
            rgb = read_rgb(rgb_file)
            if rgb.shape[:2] == depth.shape:
                colors = rgb[uv[:, 1], uv[:, 0]]
    if colors is None:
        colors = np.full((len(points), 3), 160, np.uint8)
    step = max(1, int(np.ceil(len(points) / max(max_points, 1))))
    return points[::step], colors[::step]


def _first_line(err: Exception) -> str:
    text = str(err).strip()
    return f"{type(err).__name__}: {text.splitlines()[0]}" if text else type(err).__name__


def load_mesh(path: Path) -> trimesh.Trimesh:
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as err:  # trimesh raises many types for bad files
        raise CenterArtError(f"{path}: not a readable mesh ({_first_line(err)})") from None
    return mesh


def _joint_marks(pred: float) -> tuple:
    marks = {0.0: "closed", 1.0: "open"}
    marks[round(pred, 2)] = "pred"
    return tuple(sorted(marks.items()))


class Viewer:
    """The scene and GUI of one prediction folder on a running viser server."""

    def __init__(self, server, cfg: ViewConfig, data: dict | None = None):
        self.server = server
        self.cfg = cfg
        path = Path(cfg.path)
        self.data = read_predictions(path) if data is None else data
        self.folder = path if path.is_dir() else path.parent
        self._decoder = None
        self._decoder_lock = threading.Lock()
        self.gui: dict = {}
        self.layers = dict.fromkeys(LAYERS, True)
        self.layers["rejected"] = bool(cfg.show_rejected)
        self.grasp_colors = cfg.grasp_colors
        self.top_k = cfg.top_k
        self.mesh_opacity = float(np.clip(cfg.mesh_opacity, 0.0, 1.0))
        self.objects = [ObjectView(rec, _palette(k)) for k, rec in enumerate(self.data.get("objects", []))]
        self.nodes: dict = {}
        self._build_scene()
        self._build_gui()

    # --- decoder -------------------------------------------------------------------------------------------
    def decoder_path(self) -> Path:
        from centerart.models.checkpoint import default_checkpoint

        if self.cfg.decoder is not None:
            return Path(self.cfg.decoder)
        named = ((self.data.get("checkpoints") or {}).get("decoder") or {}).get("path")
        if named and Path(named).is_file():
            return Path(named)
        default = default_checkpoint()
        if named:
            print(f"centerart view: decoder {named} (named in predictions.json) not found; using {default}")
        return default

    @property
    def decoder_loaded(self) -> bool:
        return self._decoder is not None

    @property
    def decoder(self):
        """The decoder, loaded on first use (once)."""
        with self._decoder_lock:
            if self._decoder is None:
                from centerart.models.checkpoint import load_decoder

                self._decoder = load_decoder(self.decoder_path())
        return self._decoder

    def decode(self, k: int, joint: float) -> trimesh.Trimesh:
        """Object k's mesh at normalized joint state ``joint``, camera frame."""
        from centerart.inference.reconstruction import MeshConfig, reconstruct_object

        rec = self.objects[k].record
        code = np.asarray(rec.get("shape_code") or [], np.float32)
        if code.size == 0:
            raise CenterArtError(f"object {k}: no shape code in predictions.json to decode a mesh from")
        dec = self.decoder
        if code.shape != (dec.decoder.config.code_dim,):
            raise CenterArtError(
                f"object {k}: shape code of length {code.size} does not fit decoder {dec.path} "
                f"(code_dim {dec.decoder.config.code_dim})"
            )
        rec_mesh = reconstruct_object(dec.decoder, code, float(joint), dec.bounds, MeshConfig(self.cfg.resolution))
        mesh = rec_mesh.mesh.copy()
        mesh.apply_transform(np.asarray(rec["camera_T_object"], float))
        return mesh

    # --- scene ---------------------------------------------------------------------------------------------
    def _build_scene(self) -> None:
        scene = self.server.scene
        self.nodes["root"] = scene.add_frame(ROOT, show_axes=False, wxyz=_wxyz(WORLD_R_CAMERA))
        points, colors = load_points(self.folder, self.data, self.cfg.max_points)
        self.num_points = len(points)
        if len(points):
            self.nodes["points"] = scene.add_point_cloud(
                f"{ROOT}/points", points.astype(np.float32), colors, point_size=self.cfg.point_size
            )
        for k, obj in enumerate(self.objects):
            self._build_object(k, obj)
        self._set_initial_camera(points)

    def _build_object(self, k: int, obj: ObjectView) -> None:
        scene, rec, name = self.server.scene, obj.record, f"{ROOT}/object_{k:02d}"
        joint = rec.get("joint") or {}
        obj.joint = obj.requested = float(np.clip(joint.get("state_normalized", 0.5), 0.0, 1.0))
        obj.nodes["group"] = scene.add_frame(name, show_axes=False)
        mesh_file = rec.get("mesh")
        if mesh_file and (self.folder / mesh_file).is_file():
            self._add_mesh(k, load_mesh(self.folder / mesh_file))
        else:
            try:
                self._add_mesh(k, self.decode(k, obj.joint))
            except CenterArtError as err:  # show the rest of the prediction all the same
                print(f"centerart view: object {k} shown without a mesh: {err}")
        obj.nodes["frame"] = scene.add_frame(
            f"{name}/frame", axes_length=0.1, axes_radius=0.004, **_pose_kwargs(rec["camera_T_object"])
        )
        if "axis_direction_camera" in joint and "axis_point_camera" in joint:
            d = np.asarray(joint["axis_direction_camera"], float)
            d = d / max(np.linalg.norm(d), 1e-9)
            p = np.asarray(joint["axis_point_camera"], float)
            seg = np.stack([p - d * AXIS_LENGTH / 2, p + d * AXIS_LENGTH / 2])[None]
            obj.nodes["axis"] = scene.add_line_segments(f"{name}/axis", seg, AXIS_COLOR, thickness=0.008)
        grasps = rec.get("grasps") or []
        for r, (g, color) in enumerate(zip(grasps, grasp_colors(grasps, self.grasp_colors), strict=True)):
            pose = np.asarray(g["camera_T_tcp"], float)
            visible = r < self.cfg.top_k
            gname = f"{name}/grasps/{r:03d}"
            if self.cfg.grasp_style == "mesh":
                gm = gripper_mesh(pose)
                handle = scene.add_mesh_simple(gname, gm.vertices, gm.faces, color=tuple(color), visible=visible)
            else:
                segs = GRIPPER_SEGMENTS_TCP @ pose[:3, :3].T + pose[:3, 3]
                handle = scene.add_line_segments(gname, segs, tuple(color), thickness=0.004, visible=visible)
            obj.grasps.append(handle)
        self._build_rejected(obj, name)

    def _build_rejected(self, obj: ObjectView, name: str) -> None:
        """One thin line-segments node per rejection reason: the gripper outlines of the object's rejected
        candidates (camera-frame TCP poses), in the reason's colour; shown with the ``rejected`` layer."""
        from centerart.viz.prediction_overlay import OTHER_REASON_COLOR, REASON_COLORS

        rejected = obj.record.get("rejected_grasps") or []
        for reason in sorted({r["reason"] for r in rejected}):
            poses = np.asarray([r["camera_T_tcp"] for r in rejected if r["reason"] == reason], float)
            segs = np.einsum("sej,nij->nsei", GRIPPER_SEGMENTS_TCP, poses[:, :3, :3]) + poses[:, None, None, :3, 3]
            obj.rejected[reason] = self.server.scene.add_line_segments(
                f"{name}/rejected/{reason}", segs.reshape(-1, 2, 3).astype(np.float32),
                REASON_COLORS.get(reason, OTHER_REASON_COLOR), thickness=0.0015, visible=self.layers["rejected"],
            )  # fmt: skip

    def _add_mesh(self, k: int, mesh: trimesh.Trimesh) -> None:
        """Add (or replace) object k's mesh node, keeping the mesh layer's visibility."""
        obj = self.objects[k]
        visible = self.layers["meshes"]
        obj.nodes["mesh"] = self.server.scene.add_mesh_simple(
            f"{ROOT}/object_{k:02d}/mesh",
            np.asarray(mesh.vertices, np.float32),
            np.asarray(mesh.faces, np.uint32),
            color=obj.color,
            opacity=self.mesh_opacity if self.mesh_opacity < 1.0 else None,
            side="double",
            visible=visible,
        )
        obj.num_faces = len(mesh.faces)

    def _set_initial_camera(self, points: np.ndarray) -> None:
        """Look from the camera (world origin) along its optical axis, with the image's vertical field of view."""
        depths = points[:, 2] if len(points) else np.array([])
        centers = [np.asarray(o.record["camera_T_object"], float)[2, 3] for o in self.objects]
        dist = float(np.median(np.concatenate([depths, centers]))) if len(depths) + len(centers) else 1.0
        cam = self.server.initial_camera
        image = self.data.get("image") or {}
        if "K" in image and "height" in image:
            cam.fov = float(2 * np.arctan2(image["height"] / 2, np.asarray(image["K"], float)[1, 1]))
        cam.position = (0.0, 0.0, 0.0)
        cam.look_at = tuple(WORLD_R_CAMERA @ np.array([0.0, 0.0, max(dist, 0.1)]))
        cam.up = (0.0, 0.0, 1.0)

    # --- GUI -----------------------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.server.gui
        n_grasps = max((len(o.grasps) for o in self.objects), default=0)
        gui.add_markdown(
            f"**{self.folder.name}**: {len(self.objects)} objects, {self.num_points} points. "
            "Poses in the camera frame; the view starts at the camera."
        )
        with gui.add_folder("Layers"):
            for key in LAYERS:
                box = gui.add_checkbox(key, self.layers[key], hint=LAYER_HINTS.get(key))
                box.on_update(lambda event, key=key: self.set_layer(key, event.target.value))
                self.gui[key] = box
            self.gui["top_k"] = gui.add_slider(
                "top-k grasps", min=0, max=n_grasps, step=1, initial_value=min(self.cfg.top_k, n_grasps)
            )
            self.gui["top_k"].on_update(lambda event: self.set_top_k(event.target.value))
            self.gui["grasp_colors"] = gui.add_dropdown(
                "grasp colour", ("score", "source"), initial_value=self.grasp_colors,
                hint="kept grasps by score (violet low, orange high) or by source (decoder blue, observed green, "
                "handle orange)",
            )  # fmt: skip
            self.gui["grasp_colors"].on_update(lambda event: self.set_grasp_colors(event.target.value))
            self.gui["point_size"] = gui.add_slider(
                "point size (m)", min=0.001, max=0.02, step=0.001, initial_value=float(self.cfg.point_size)
            )
            self.gui["point_size"].on_update(lambda event: self._set_point_size(event.target.value))
            self.gui["opacity"] = gui.add_slider(
                "mesh opacity", min=0.1, max=1.0, step=0.05, initial_value=max(0.1, round(self.mesh_opacity, 2))
            )
            self.gui["opacity"].on_update(lambda event: self.set_mesh_opacity(event.target.value))
        for k, obj in enumerate(self.objects):
            rec, joint = obj.record, obj.record.get("joint") or {}
            title = f"object {k}: {joint.get('type', '?')}, score {rec.get('score', 0.0):.2f}"
            with gui.add_folder(title):
                state = f"{joint.get('state', float('nan')):.3f} {joint.get('unit', '')}"
                gui.add_markdown(f"predicted state {state} (normalized {obj.joint:.2f}), {len(obj.grasps)} grasps")
                if (summary := anchoring_markdown(rec)) is not None:
                    gui.add_markdown(summary)
                show = gui.add_checkbox("show", True)
                show.on_update(lambda event, k=k: self.set_object_visible(k, event.target.value))
                slider = gui.add_slider(
                    "joint state", min=0.0, max=1.0, step=0.01, initial_value=round(obj.joint, 2),
                    marks=_joint_marks(obj.joint),
                    hint="normalized joint state; moving it re-decodes the mesh (the grasps stay the predicted ones)",
                )  # fmt: skip
                slider.on_update(lambda _event, k=k: self._on_joint_slider(k))
                obj.gui.update(show=show, joint=slider)

    # --- actions (GUI callbacks; also called by tests) -------------------------------------------------------
    def set_layer(self, key: str, visible: bool) -> None:
        """Show or hide one layer (one of ``LAYERS``) of every object."""
        self.layers[key] = bool(visible)
        if key == "points":
            if "points" in self.nodes:
                self.nodes["points"].visible = visible
            return
        if key == "grasps":
            self.set_top_k(self.top_k)
            return
        if key == "rejected":
            for obj in self.objects:
                for handle in obj.rejected.values():
                    handle.visible = visible
            return
        node_key = {"meshes": "mesh", "axes": "axis", "frames": "frame"}[key]
        for obj in self.objects:
            if node_key in obj.nodes:
                obj.nodes[node_key].visible = visible

    def set_top_k(self, top_k: int) -> None:
        """Show the ``top_k`` best grasps of every object (while the grasps layer is on)."""
        self.top_k = int(top_k)
        for obj in self.objects:
            for r, handle in enumerate(obj.grasps):
                handle.visible = self.layers["grasps"] and r < self.top_k

    def set_grasp_colors(self, mode: str) -> None:
        """Colour every object's kept grasps by ``score`` or by ``source`` (grasps without one: by score)."""
        self.grasp_colors = mode
        for obj in self.objects:
            colors = grasp_colors(obj.record.get("grasps") or [], mode)
            for handle, color in zip(obj.grasps, colors, strict=True):
                if self.cfg.grasp_style == "mesh":
                    handle.color = tuple(int(c) for c in color)
                else:
                    handle.colors = np.broadcast_to(np.asarray(color, np.uint8), handle.colors.shape).copy()

    def _set_point_size(self, size: float) -> None:
        if "points" in self.nodes:
            self.nodes["points"].point_size = float(size)

    def set_mesh_opacity(self, opacity: float) -> None:
        self.mesh_opacity = float(np.clip(opacity, 0.0, 1.0))
        for obj in self.objects:
            if "mesh" in obj.nodes:
                obj.nodes["mesh"].opacity = self.mesh_opacity if self.mesh_opacity < 1.0 else None

    def set_object_visible(self, k: int, visible: bool) -> None:
        self.objects[k].nodes["group"].visible = visible

    def _on_joint_slider(self, k: int) -> None:
        slider = self.objects[k].gui["joint"]
        try:
            self.set_joint(k, slider.value)
        except CenterArtError as err:  # e.g. no usable decoder: say so once, keep the viewer running
            print(f"centerart view: error: {err}")
            slider.disabled = True

    def set_joint(self, k: int, joint: float) -> bool:
        """Re-decode object k at normalized joint state ``joint``. Slider moves arrive faster than decoding: a
        request that a newer one overtook while it waited is dropped (False)."""
        obj = self.objects[k]
        joint = float(np.clip(joint, 0.0, 1.0))
        obj.requested = joint
        with obj.lock:
            if obj.requested != joint:
                return False
            if joint != obj.joint:
                self._add_mesh(k, self.decode(k, joint))
                obj.joint = joint
        return True


def viewer_url(server) -> str:
    host = server.get_host()
    return f"http://{'localhost' if host in ('0.0.0.0', '::') else host}:{server.get_port()}"


def block_until_interrupted(server) -> None:
    """Serve until Ctrl+C, then stop the server."""
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()


def serve_viewer(cfg: ViewConfig, block: bool = True):
    """Start a viser server showing the prediction folder ``cfg.path``; returns the server (``block``: serve
    until Ctrl+C first). The folder is read before the server starts, so bad input starts nothing."""
    import socket

    import viser

    path = Path(cfg.path)
    if not path.exists():
        raise CenterArtError(f"{path}: no such prediction folder (make one with centerart predict --out {path})")
    data = read_predictions(path)
    if not 0 <= cfg.port <= 65535:
        raise CenterArtError(f"--port {cfg.port}: not a TCP port (0..65535; 0 picks a free one)")
    try:  # viser retries a failing bind on the next port, forever: find a host it cannot listen on first
        family, _, _, _, address = socket.getaddrinfo(cfg.host, 0, type=socket.SOCK_STREAM)[0]
        with socket.socket(family, socket.SOCK_STREAM) as sock:
            sock.bind(address)
    except (OSError, UnicodeError) as err:
        raise CenterArtError(f"--host {cfg.host!r}: cannot listen there ({err})") from None
    server = viser.ViserServer(host=cfg.host, port=cfg.port, label="centerart", verbose=False)
    try:
        server.gui.configure_theme(show_share_button=False, control_width="medium")
        server.viewer = Viewer(server, cfg, data)
    except BaseException:
        server.stop()
        raise
    if block:
        block_until_interrupted(server)
    return server
