"""``centerart predict``: one RGB-D image in, a folder of predictions out (JSON, meshes, pictures, 3-D scene).

Writes to ``--out`` (complete or not at all: a temporary folder renamed at the end)::

    predictions.json    every object's pose, joint, shape code and ranked grasps (schema: inference/prediction_io.py)
    object_XX.ply       each object's decoded mesh, camera frame (--no-meshes skips them)
    overlay.png         detections, poses, joint axes and top grasps on the RGB image (--show-rejected: and the
                        grasp candidates that anchoring rejected, coloured by reason)
    heatmap.png         the predicted centre heatmap over the image
    scene.glb           observed point cloud, meshes, grippers and joint axes (any glTF viewer)
    rgb.png, depth.npy, points.ply   the inputs, for the 3-D viewer (``centerart view OUT``)

With no ``--rgb`` it runs on the bundled example (a kitchen of objects no model was trained on).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from centerart.errors import CenterArtError
from centerart.inference.predictor import PredictorConfig
from centerart.utils.atomic import atomic_directory
from centerart.utils.checks import positive
from centerart.utils.folders import check_output_folder

EXAMPLE_DIR = Path(__file__).resolve().parent / "examples" / "kitchen"


@dataclass
class PredictConfig:
    """Predict objects, joints, meshes and grasps from one RGB-D image."""

    rgb: Path | None = None
    """Colour image (PNG / JPG). Default: the bundled example."""
    depth: Path | None = None
    """Depth: .npy in metres, or a 16-bit PNG (millimetres unless --depth-scale says otherwise)."""
    intrinsics: Path | None = None
    """JSON with a 3x3 K (+ width, height), or a ROS camera_info YAML/JSON."""
    out: Path = Path("outputs/predict")
    depth_scale: float | None = None
    """Metres per depth unit (default: 0.001 for integer images, 1 for float)."""
    encoder: Path | None = None
    """Encoder checkpoint (default: the shipped one)."""
    decoder: Path | None = None
    """Decoder checkpoint (default: the shipped one; must be the one the encoder was trained against)."""
    device: Literal["cpu", "cuda"] = "cpu"
    meshes: bool = True
    """Decode and write each object's mesh (costs about a second per object on a CPU)."""
    predictor: PredictorConfig = field(default_factory=PredictorConfig)
    gravity: tuple[float, float, float] | None = None
    """The downward direction in the camera frame (OpenCV: x right, y down, z forward), e.g. from TF or the
    camera's IMU; any length. With it, each object's pose is corrected from the depth before its grasps are placed
    (--predictor.pose-from-depth auto), kept upright, only its yaw and position changed."""
    show_rejected: bool = False
    """Also draw the grasp candidates that anchoring rejected on overlay.png, coloured by reason (a legend says
    which); predictions.json keeps them either way (``rejected_grasps``)."""
    view: bool = False
    """Open the interactive 3-D viewer on the result when done."""

    def __post_init__(self):
        positive("--depth-scale", self.depth_scale, allow_none=True)
        if self.gravity is not None and not (
            np.all(np.isfinite(self.gravity)) and np.linalg.norm(np.asarray(self.gravity, float)) > 1e-9
        ):
            raise CenterArtError(f"--gravity: expected a non-zero direction of 3 finite numbers, got {self.gravity}")


def resolve_inputs(cfg: PredictConfig):
    from centerart.inference.inputs import read_depth, read_intrinsics, read_rgb

    rgb_path, depth_path, intr_path = cfg.rgb, cfg.depth, cfg.intrinsics
    if rgb_path is None:
        rgb_path, depth_path, intr_path = (EXAMPLE_DIR / n for n in ("rgb.png", "depth.png", "intrinsics.json"))
    elif depth_path is None or intr_path is None:
        raise CenterArtError("--rgb needs --depth and --intrinsics as well")
    rgb = read_rgb(rgb_path)
    depth = read_depth(depth_path, cfg.depth_scale)
    camera = read_intrinsics(intr_path, width=rgb.shape[1], height=rgb.shape[0])
    return rgb, depth, camera, {"rgb": str(rgb_path), "depth": str(depth_path), "intrinsics": str(intr_path)}


def write_outputs(tmp: Path, predictor, preds, rgb, depth, camera, cfg: PredictConfig, sources: dict) -> dict:
    import trimesh
    from PIL import Image

    from centerart.geometry.camera import backproject_depth
    from centerart.inference.prediction_io import predictions_record
    from centerart.models.checkpoint_files import file_sha256
    from centerart.models.grasp_critic import critic_record
    from centerart.utils.atomic import atomic_write_json
    from centerart.viz.prediction_overlay import draw_prediction
    from centerart.viz.scene_export import build_scene, write_glb
    from centerart.viz.scenes_sheet import heatmap_image

    t0 = time.perf_counter()
    meshes = predictor.meshes(preds) if cfg.meshes else []
    timing = {**predictor.timing, "meshes_s": time.perf_counter() - t0}
    mesh_files = {}
    for k, mesh in enumerate(meshes):
        mesh.export(tmp / f"object_{k:02d}.ply")
        mesh_files[k] = f"object_{k:02d}.ply"
    points, uv = backproject_depth(depth, camera.K, return_pixels=True)
    colors = rgb[uv[:, 1], uv[:, 0], :3]
    trimesh.PointCloud(points, colors=colors).export(tmp / "points.ply")
    Image.fromarray(rgb[..., :3]).save(tmp / "rgb.png")
    np.save(tmp / "depth.npy", depth.astype(np.float32))
    overlay = draw_prediction(rgb, preds, camera.K, show_rejected=cfg.show_rejected)
    Image.fromarray(overlay).save(tmp / "overlay.png")
    Image.fromarray(heatmap_image(rgb[..., :3], predictor.last_heatmap)).save(tmp / "heatmap.png")
    step = max(1, len(points) // 60000)
    write_glb(build_scene(points[::step], colors[::step], preds, meshes), tmp / "scene.glb")
    enc, dec = predictor.encoder.path, predictor.decoder.path
    checkpoints = {
        "encoder": {"path": str(enc), "sha256": file_sha256(enc)},
        "decoder": {"path": str(dec), "sha256": file_sha256(dec)},
        "grasp_critic": critic_record(dec) if cfg.predictor.grasp_critic else None,
        "anchor_critic": critic_record(dec, "anchor_critic") if cfg.predictor.grasp_critic else None,
    }
    files = {
        "inputs": {"rgb": "rgb.png", "depth": "depth.npy", "points": "points.ply", **sources},
        "meshes": mesh_files,
    }
    config = {**asdict(cfg.predictor), "device": cfg.device}
    record = predictions_record(preds, camera, checkpoints, config, timing, files)
    atomic_write_json(tmp / "predictions.json", record)
    return record


def anchoring_summary(obj: dict) -> str | None:
    """One line of what grasp anchoring did for one object of a predictions record (its ``refinement.anchoring``
    counts and its top grasp's source and closing points), or None when anchoring did not run for it."""
    counts = (obj.get("refinement") or {}).get("anchoring")
    if not counts:
        return None
    sources = ", ".join(f"{s} {counts.get(f'candidates_{s}', 0)}" for s in ("decoder", "observed", "handle"))
    total = sum(counts.get(f"candidates_{s}", 0) for s in ("decoder", "observed", "handle"))
    checks = ", ".join(f"{k.replace('_', ' ')} {counts[k]}" for k in ("snapped", "material_between_pads", "clear")
                       if k in counts)  # fmt: skip
    line = f"anchoring: {counts.get('kept', 0)} kept of {total} candidates ({sources}; survived: {checks})"
    grasps = obj.get("grasps") or []
    if grasps and "source" in grasps[0]:
        line += f"; top grasp from {grasps[0]['source']}, {grasps[0].get('closing_points', '?')} points between pads"
    return line


def run_predict(cfg: PredictConfig) -> dict:
    """Predict and write the output folder (atomically: complete or absent); returns the predictions record."""
    from centerart.inference.inputs import check_inputs
    from centerart.inference.predictor import Predictor

    out = check_output_folder(cfg.out)
    rgb, depth, camera, sources = resolve_inputs(cfg)
    depth = check_inputs(rgb, depth, camera)  # before loading any model: a bad input is reported at once
    predictor = Predictor(cfg.encoder, cfg.decoder, cfg.device, cfg.predictor)
    preds = predictor.predict(rgb, depth, camera, gravity=cfg.gravity)
    with atomic_directory(out) as tmp:
        return write_outputs(tmp, predictor, preds, rgb, depth, camera, cfg, sources)
